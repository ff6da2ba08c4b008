"""``acmm plot``: a run's figures redrawn from its stored results files, each by the layer that
wrote it (the stages, the sweep, qpp's stages)."""
from __future__ import annotations

from pathlib import Path

from acmm.stages.design_output import design_figures_from_file
from acmm.stages.sim_output import sim_figures_from_file
from acmm.sweep.output import sweep_figures_from_file
from acmm_qpp.results import redraw_stored
from qpp.io import stages as qpp_stages


#: results file → the stage that writes it (root attribute ``stage``), in the order ``acmm plot``
#: redraws a run folder's figures (the qpp files too: a run folder may hold both)
FIGURE_SOURCES = {"design.h5": "design", "sim.h5": "simulate", "sweep.h5": "sweep", **qpp_stages.FIGURE_SOURCES}


def redraw_figures(target, out=None) -> list[Path]:
    """Redraw a run's figures from its stored results (``acmm plot``): ``design.h5``,
    ``sim.h5``, ``sweep.h5`` and the qpp files, each drawn from the file alone
    (:func:`acmm.stages.design_output.design_figures_from_file`,
    :func:`acmm.stages.sim_output.sim_figures_from_file`,
    :func:`acmm.sweep.output.sweep_figures_from_file`, :func:`qpp.io.stages.figure_calls_from_file`).

    Parameters
    ----------
    target : path-like
        A run folder (every results file with figures in it) or one results file.
    out : path-like, optional
        Folder of the figures (created if missing; default: the results file's folder).

    Returns
    -------
    list of pathlib.Path
        The figures written.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        ``target`` is missing or holds no results file of this project (exit 2).
    acmm_qpp.errors.FigureError
        A figure could not be drawn or written (exit 4).
    """
    readers = {"design": design_figures_from_file, "simulate": sim_figures_from_file,
               "sweep": sweep_figures_from_file, **qpp_stages.READERS}
    return redraw_stored(target, FIGURE_SOURCES, readers, out)
