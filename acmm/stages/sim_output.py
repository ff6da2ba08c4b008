"""What the simulation stage (:func:`acmm.stages.simulate.run_simulate`) writes: the ``sim.h5``
items and the figures of the report's ch. 6 simulations: attitude error, rates, torque and CMG
momentum per axis (Figs 6.2–6.13, 6.20–6.30), the inertia steps (Figs 6.14–6.19) and the
per-level statistics; the disturbance torque is that of eq 3.9.
"""
from __future__ import annotations

from functools import partial

import numpy as np

from acmm.model import kinematics as kin
from acmm.simulate import scenario as scen
from acmm.stages.common import AXES, UNIT_K, UNIT_STATE, stored_config, stored_in
from acmm_qpp.results import Dataset, h5_text
import h5py


def sim_items(cfg, sc, r, stats: list, design_hash: str, wall: float) -> tuple[dict, dict]:
    """The datasets and root attributes of ``sim.h5`` (imperial units; the stage converts).

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The run's config (orbit rate n, rad/s).
    sc : acmm.simulate.scenario.Scenario
        The simulated scenario (levels, gains).
    r : acmm.simulate.scenario.SimResult
        The trajectory.
    stats : list of dict
        :func:`acmm.simulate.scenario.level_statistics` of ``r``.
    design_hash : str
        Hash of the design the gains come from.
    wall : float
        Integration wall time, s.

    Returns
    -------
    items : dict
        Path → :class:`acmm_qpp.results.Dataset` (nested dicts are groups).
    attrs : dict
        Root attributes (verdict, stop time, step counts).
    """
    n = cfg.orbit_rate
    orbits = r.t * n / (2 * np.pi)
    err = scen.attitude_error(sc, r)
    rel_rate = np.degrees(r.state[:, 0:3] - kin.lvlh_rate_in_body(r.state[:, 3:6], n))
    # one row per level of the stair-case: NaN for a level never reached (a diverged run), and
    # a steady error only for a level that reached the second half of its dwell
    steady = np.full((len(sc.level_start), 3), np.nan)
    for st in stats:
        steady[st["level"]] = st["steady_error_deg"]
    peak = scen.level_peak_momentum(sc, r)
    items = {
        "t": Dataset(r.t, "s", "time", dims=("t",)),
        "orbits": Dataset(orbits, "orbit", "time in orbits (2π/n)", dims=("t",)),
        "theta": Dataset(r.state[:, 3:6], "rad", "attitude (roll, pitch, yaw), 2-3-1 from LVLH", AXES,
                         dims=("t", "axis")),
        "attitude_error": Dataset(err, "rad", "θ − θ̂* of the level in force", AXES, dims=("t", "axis")),
        "omega": Dataset(r.state[:, 0:3], "rad/s", "absolute body rate", AXES, dims=("t", "axis")),
        "rate_rel_lvlh": Dataset(rel_rate, "deg/s", "body rate relative to LVLH", AXES, dims=("t", "axis")),
        "h": Dataset(r.state[:, 6:9], "ft*lbf*s", "CMG momentum", AXES, dims=("t", "axis")),
        "int_h": Dataset(r.state[:, 9:12], "ft*lbf*s^2", "momentum integral (controller state)", AXES, dims=("t", "axis")),
        "drf": Dataset(r.state[:, 12:24], UNIT_STATE, "DRF states", scen.PLAIN_STATE_NAMES[12:],
                       dims=("t", "drf_state")),
        "u_cmd": Dataset(r.u_cmd, "ft*lbf", "commanded torque −K x (before saturation)", AXES, dims=("t", "axis")),
        "u": Dataset(r.u, "ft*lbf", "delivered torque (after torque and momentum saturation)", AXES, dims=("t", "axis")),
        "w": Dataset(r.w, "ft*lbf", "disturbance torque (eq 3.9)", AXES, dims=("t", "axis")),
        "level": Dataset(r.level, "1", "index of the inertia level in force", dims=("t",)),
        "torque_saturated": Dataset(r.torque_saturated, "1", "torque clipped per axis", AXES, dims=("t", "axis")),
        "momentum_saturated": Dataset(r.momentum_saturated, "1", "CMG axis at its momentum limit", AXES, dims=("t", "axis")),
        "levels": {
            "start": Dataset(sc.level_start, "s", "start time of each level", dims=("level",)),
            "inertia": Dataset(sc.inertia, "slug*ft^2", "plant inertia per level", dims=("level", "axis", "axis_col")),
            "bias": Dataset(sc.bias, "ft*lbf", "bias per level", AXES, dims=("level", "axis")),
            "tea_estimate": Dataset(sc.theta_est, "rad", "TEA estimate used by the controller", AXES,
                                    dims=("level", "axis")),
            "gain": Dataset(sc.gain, UNIT_K, "gain in use per level (u = −K x)",
                            dims=("level", "axis", "state")),
            "steady_error": Dataset(steady, "deg", "max |θ − θ̂*| over the second half of each level "
                                    "(NaN: the run ended before it)", AXES, dims=("level", "axis")),
            "peak_momentum": Dataset(peak, "ft*lbf*s", "peak |h_i| over each level (NaN: not reached)",
                                     dims=("level",)),
        },
        "wall_time": Dataset(wall, "s", "integration wall time"),
    }
    return items, {"stage": "simulate", "verdict": r.verdict, "reason": r.reason,
                   "stop_time_s": r.stop_time, "stop_time_orbits": r.stop_time * n / (2 * np.pi),
                   "design_hash": design_hash, "n_steps": r.n_steps, "n_rejected": r.n_rejected}


def sim_figures_from_file(path, out_dir) -> list:
    """The simulation figures (Figs 6.2–6.30 of ch. 6) drawn from a ``sim.h5`` alone (by the
    simulation stage after it wrote the file, and by ``acmm plot``): the stored time series at
    full resolution, the per-level table and the inertia levels, read in the report's units
    whatever units the file is in and drawn in ``output.units``; nothing is simulated again.

    Parameters
    ----------
    path : pathlib.Path
        The ``sim.h5`` (imperial or SI).
    out_dir : pathlib.Path
        Folder of the figures: ``sim_axes.png``, ``sim_summary.png`` and, with more than one
        inertia level, ``sim_inertia.png``.

    Returns
    -------
    list of functools.partial
        The figure calls, for :func:`acmm_qpp.results.draw_figures`.
    """
    from acmm.plots import simulation as sim_plots  # deferred: matplotlib start-up

    with h5py.File(path, "r") as f:
        attrs = {k: f.attrs[k] for k in f.attrs}
        orbits = np.asarray(f["orbits"][()], float)
        err_deg = np.degrees(stored_in(f, "attitude_error", "rad"))
        rate = stored_in(f, "rate_rel_lvlh", "deg/s")
        u = stored_in(f, "u", "ft*lbf")
        h = stored_in(f, "h", "ft*lbf*s")
        level = np.asarray(f["level"][()], int)
        start = stored_in(f, "levels/start", "s")
        tea_est = stored_in(f, "levels/tea_estimate", "rad")
        steady = np.degrees(stored_in(f, "levels/steady_error", "rad"))
        peak = stored_in(f, "levels/peak_momentum", "ft*lbf*s")
        inertia = stored_in(f, "levels/inertia", "slug*ft^2")
    cfg = stored_config(attrs)
    verdict = h5_text(attrs["verdict"])
    orbit = 2 * np.pi / cfg.orbit_rate
    # the levels level_statistics reported: those with a steady error (NaN: not reached)
    stats = [{"level": k, "start_orbit": start[k] / orbit, "theta2_deg": float(np.degrees(tea_est[k, 1])),
              "steady_error_deg": steady[k], "peak_momentum": float(peak[k])}
             for k in range(len(start)) if np.all(np.isfinite(steady[k]))]
    units = cfg.output.units
    title = f"{cfg.name}: {cfg.design.model} design — {verdict}"
    calls = [partial(sim_plots.axis_histories, orbits, err_deg, rate, u, h, title, out_dir / "sim_axes.png",
                     units=units),
             partial(sim_plots.summary, orbits, err_deg, h, u, stats, verdict, cfg.name, out_dir / "sim_summary.png",
                     units=units)]
    if len(start) > 1:
        calls.append(partial(sim_plots.inertia_histories, orbits, inertia[level], out_dir / "sim_inertia.png",
                             units=units))
    return calls
