"""The simulation stage: the nonlinear closed loop of eqs 3.1–3.9 under the scheduled gains
through the stair-case of inertia levels (ch. 6), and its ``sim.h5`` and figures.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

import time

from acmm.io.config import Config
from acmm.io.dimensions import AUX_COORDS
from acmm.simulate import kernel, scenario
from acmm.stages import sim_output
from acmm.stages.common import as_config, define_units, in_system, write_results
from acmm.stages.design import design_for
from acmm_qpp.outputs import stage
from acmm_qpp.results import draw_figures


@dataclass
class SimulateResult:
    """A nonlinear closed-loop run (ch. 6).

    Attributes
    ----------
    config : acmm.io.config.Config
        The validated config.
    scenario : acmm.simulate.scenario.Scenario
        What was simulated (levels, gains, limits).
    sim : acmm.simulate.scenario.SimResult
        The run: t (s), state (report units), torques (ft·lbf), verdict.
    stats : list of dict
        Per-level statistics (:func:`acmm.simulate.scenario.level_statistics`).
    design_note : str
        Whether the design was reused or computed.
    wall_time : float
        Integration wall time, s.
    """

    config: Config
    scenario: object
    sim: object
    stats: list
    design_note: str
    wall_time: float

    @property
    def orbits_simulated(self) -> float:
        """Simulated time in orbits (2π/n)."""
        return float(self.sim.t[-1] * self.config.orbit_rate / (2 * np.pi))

    @property
    def stop_orbit(self) -> float:
        """Time the integration stopped at, in orbits (2π/n)."""
        return float(self.sim.stop_time * self.config.orbit_rate / (2 * np.pi))


@stage(("sim.h5", "sim_*.png"), as_config)
def run_simulate(config, progress=None, figures: bool | None = None, warn=None, *,
                 out: Path) -> tuple[SimulateResult, Path]:
    """Design (or reuse the design), simulate, write ``runs/<name>/sim.h5`` and the figures.

    Parameters
    ----------
    config : acmm.io.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    progress : callable, optional
        ``progress(name)``, called after each design point when designing.
    figures : bool, optional
        Write the figures (default: ``output.figures``).
    warn : callable, optional
        ``warn(message)`` when a design made first has an unstable scheduled loop
        (:func:`acmm.stages.design.design_for`).
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (:class:`SimulateResult`, pathlib.Path of ``sim.h5``).
    """
    cfg = as_config(config)
    want_figures = cfg.output.figures if figures is None else figures
    table, note = design_for(cfg, progress, figures, warn)
    sc = scenario.scenario_from_config(cfg, table)
    t0 = time.perf_counter()
    r = kernel.simulate(sc)
    wall = time.perf_counter() - t0
    stats = scenario.level_statistics(sc, r)
    items, attrs = sim_output.sim_items(cfg, sc, r, stats, table.design_hash, wall)
    items = define_units(in_system(items, cfg, {"levels/gain": "K", "drf": "drf"}), cfg.orbit_rate)
    write_results(out / "sim.h5", items, cfg, attrs, aux_coords=AUX_COORDS)
    if want_figures:
        draw_figures(sim_output.sim_figures_from_file(out / "sim.h5", out))
    return SimulateResult(cfg, sc, r, stats, note, wall), cfg.run_dir() / "sim.h5"
