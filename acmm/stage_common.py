"""What every stage shares: the config it is given (object, file or packaged name) and the
conversion of its per-state output arrays into the config's unit system.

Split from :mod:`acmm.stages` (issue 12) so that :mod:`acmm.stage_design` and
:mod:`acmm.stage_simulate` need not import the module that re-exports them.
"""
from __future__ import annotations

import numpy as np

from acmm.config import Config, load_config

#: the figure worker's warm-up for the acmm stages, :func:`acmm.plots.warm_figure_worker`, named
#: as :func:`common.figure_worker.start` takes it (a string: the worker imports it, this process
#: need not)
FIGURE_WARM = "acmm.plots:warm_figure_worker"


def _in_system(items: dict, cfg: Config, roles: dict) -> dict:
    """Per-state arrays of ``items`` (path → role of :func:`acmm.units.state_space_in`) in the
    config's ``output.units``; their unit strings and ``state_units`` follow.  Other datasets
    are converted by unit string in :func:`common.results.write_h5`."""
    from dataclasses import replace

    from acmm.units import state_factors, state_space_in

    system = cfg.output.units
    if system == "imperial":
        return items
    _, su = state_factors(cfg.design.drf_mode, system)
    for path, role in roles.items():
        *groups, key = path.split("/")
        g = items
        for name in groups:
            g = g[name]
        ds = g[key]
        new = state_space_in(system, cfg.design.drf_mode, **{role: ds.data})[role]
        attrs = dict(ds.attrs)
        if "state_units" in attrs:
            attrs["state_units"] = np.array(su, dtype="S")
        g[key] = replace(ds, data=new, units=ds.units.replace("ft*lbf", "N*m"), attrs=attrs)
    if "state_units" in items:
        items["state_units"] = replace(items["state_units"], data=np.array(su, dtype="S"))
    return items



def _as_config(config) -> Config:
    return config if isinstance(config, Config) else load_config(config)
