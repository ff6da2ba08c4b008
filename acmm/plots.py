"""Matplotlib figures for the design and simulation stages (report Figs 5.3–5.26, 6.2–6.30).

Each function takes arrays, draws one figure and saves it as PNG (and PDF when asked) under the
given path; nothing is shown on screen.  The sector LQR and schedule of ch. 5.2–5.3, the
stair-case simulation of ch. 6.

Split for size (issue 12): the shared machinery (saving, skeletons, tick and line thinning, unit
labels) is in :mod:`acmm.plot_base`, the design figures in :mod:`acmm.design_plots`, the
simulation figures in :mod:`acmm.sim_plots`; every name is re-exported here.
"""
from __future__ import annotations

from acmm.design_plots import (  # noqa: F401  (re-exported)
    SampledSchedule,
    gain_schedule_grid,
    pole_map,
    sample_schedule,
    schedule_path_check,
    scheduled_pole_map,
)
from acmm.plot_base import (  # noqa: F401  (re-exported; acmm.sweep uses plots._plt, plots._save)
    _LAYOUTS,
    AXES,
    MAX_LINE_POINTS,
    PNG_COMPRESS_LEVEL,
    _layout,
    _plt,
    _save,
    decimate,
    gain_unit,
    prebuild,
    state_units,
)
from acmm.sim_plots import axis_histories, inertia_histories, summary  # noqa: F401  (re-exported)


def warm_figure_worker() -> None:
    """The figure worker's warm-up for the acmm stages (:data:`acmm.stage_common.FIGURE_WARM`,
    :func:`common.figure_worker.start`): matplotlib with the stage style and one
    small figure drawn (fonts, caches); the report's opt-in forked writers are turned off there
    (a writer draws in place, never forks again)."""
    from acmm import parallel_figures
    from common.plot_style import draw_warm_up_figure

    parallel_figures.forget()
    draw_warm_up_figure(_plt(), "roll θ (deg)", "time (orbits)")
