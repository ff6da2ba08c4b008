"""What the design stage writes: the ``design.h5`` items and the design figures.

:func:`acmm.stages.design.run_design` calls these; the items (:func:`design_items`) are built
from a :class:`acmm.stages.design.DesignResult`, the figures from the ``design.h5`` just written
(:func:`design_figures_from_file`, as ``acmm plot`` draws them): the model of eq 4.46, the
sector LQR of ch. 5.2 and the gain schedule of ch. 5.3.
"""
from __future__ import annotations

from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

from acmm.io.units import state_factors
from acmm.model.linearize import STATE_NAMES
from acmm.stages.certify import UNIT_ROLES, certificate_items, compute_certificate
from acmm.stages.common import (AXES, UNIT_A, UNIT_B, UNIT_K, UNIT_P, UNIT_Q, UNIT_STATE, define_units, in_system,
                                stored_config)
from acmm_qpp.results import Dataset, h5_text
import h5py
from acmm.design.schedule import schedule_gain
from acmm.design.settings import design_settings

#: a point's datasets that describe the reference sector LQR of a robust or LMI gain, not the gain
_REFERENCE_LQR = ("Q", "P", "riccati_residual", "riccati_backward_error", "riccati_condition", "riccati_ill_conditioned")


def design_items(r, cfg) -> dict:
    """The items of ``design.h5``: the point groups, the table, the schedule (when fitted) and the
    dwell-time certificate, converted to the output unit system with their units defined.

    The certificate reuses the proof of the ``design.h5`` this design replaces where the same
    program found it for these loops (:func:`acmm.stages.certify.compute_certificate`).

    Parameters
    ----------
    r : acmm.stages.design.DesignResult
        The design.
    cfg : acmm.io.config.Config
        Its config (output unit system, orbit rate n in rad/s, run folder).

    Returns
    -------
    dict
        Name → :class:`acmm_qpp.results.Dataset` or group, as written (units stated per dataset).
    """
    pts = _point_items(r.points)
    items = _table_items(r, pts)
    # dataset path → role of acmm.io.units.state_space_in: what is converted per state, and as what
    roles = {"K": "K"}
    for key in pts:
        roles.update({f"points/{key}/{m}": m for m in ("A", "B", "G", "Q", "P", "K")})
        if "robust" in pts[key]:
            roles[f"points/{key}/robust/nominal_K"] = "K"
        roles[f"points/{key}/scales"] = "scales"
    if r.fit is not None:
        items["schedule"] = _schedule_items(r)
        roles.update({"schedule/coef": "K", "schedule/rms_residual": "K"})
    # the file this design replaces: its proof is reused where the same program found it for these loops
    items["dwell"] = certificate_items(compute_certificate(cfg, r.table, cfg.run_dir() / "design.h5", exact=True))
    roles.update({k: v for k, v in UNIT_ROLES.items() if k.split("/")[1] in items["dwell"]})
    return define_units(in_system(items, cfg, roles), cfg.orbit_rate)


def _point_items(points) -> dict:
    """The ``points/<k>_<name>`` groups of ``design.h5`` (model, weights and LQR of each
    :class:`acmm.design.schedule.PointDesign`; report units, stated per dataset)."""
    pts = {}
    for k, p in enumerate(points):
        res, ric = p.gain, p.gain.riccati
        g = pts[f"{k:03d}_{p.spec.name}"] = {
            "inertia": Dataset(p.spec.inertia, "slug*ft^2", "inertia of the design point", AXES,
                               dims=("axis", "axis_col")),
            "bias": Dataset(p.spec.bias, "ft*lbf", "bias torque", AXES, dims=("axis",)),
            "tea": Dataset(p.tea.theta, "rad", "torque-equilibrium attitude", AXES, dims=("axis",)),
            "A": Dataset(p.model.A, UNIT_A, "design model state matrix (eq 4.46)", STATE_NAMES,
                         dims=("state", "state_col")),
            "B": Dataset(p.model.B, UNIT_B, "input matrix", STATE_NAMES, dims=("state", "axis")),
            "G": Dataset(p.model.G, UNIT_B, "disturbance matrix", STATE_NAMES, dims=("state", "axis")),
            "Q": Dataset(ric.Q, UNIT_Q, "state weight for which K is the exact LQR gain of the shifted problem",
                         dims=("state", "state_col")),
            "R": Dataset(ric.R, "1/(ft*lbf)^2", "control weight", dims=("axis", "axis_col")),
            "P": Dataset(ric.P, UNIT_P, "Riccati solution (physical units)", dims=("state", "state_col")),
            "K": Dataset(res.K, UNIT_K, ("regional LMI gain" if res.lmi is not None else "LQR gain") + ", u = -K x",
                         STATE_NAMES, dims=("axis", "state")),
            "poles": Dataset(res.poles, "rad/s", "closed-loop poles of A - B K", dims=("pole",)),
            "sector_margin": Dataset(res.margin, "n", "worst pole distance into the sector (>0 inside)"),
            "riccati_residual": Dataset(ric.residual, "1", "relative CARE residual, scaled coordinates"),
            "riccati_backward_error": Dataset(ric.backward_error, "1",
                                              "CARE backward error after refinement (accepted quantity)"),
            "scales": Dataset(p.model.scales, UNIT_STATE, "state scaling used for the Riccati solve",
                              STATE_NAMES, dims=("state",)),
            "eig_condition": Dataset(res.eig_condition, "1",
                                     "eigenvalue condition number of each pole (order of 'poles'), scaled states",
                                     dims=("pole",)),
            "max_eig_condition": Dataset(res.max_eig_condition, "1",
                                         "largest eigenvalue condition number of A - B K, scaled states"),
            "robustness_radius": Dataset(res.robustness_radius, "1",
                                         "estimated smallest relative gain error ||dK||/||K|| (scaled) moving a pole "
                                         "out of the sector (first order)"),
            "robustness_radius_elementwise": Dataset(res.robustness_radius_elementwise, "1",
                                                     "same for elementwise relative errors max|dK_ij/K_ij|"),
            "riccati_condition": Dataset(ric.riccati_condition, "1",
                                         "relative condition estimate of the shifted CARE (acmm.design.riccati)"),
            "riccati_ill_conditioned": Dataset(np.int8(ric.riccati_ill_conditioned), "1",
                                               "1 if the CARE condition exceeds 1/sqrt(eps)"),
            "energy": Dataset(res.energy, "1", "H2 control energy tr(K W Kt) of the torque disturbance, scaled "
                              "input, time in 1/n (acmm.design.regional_lmi.control_energy)"),
        }
        if res.robust is not None:
            g["robust"] = _robust_items(res.robust)
            g["K"] = replace(g["K"], description="robust gain for the family of design.robust (group robust), u = -K x")
            for key in _REFERENCE_LQR:
                g[key] = replace(g[key], description=g[key].description + " of the route's reference sector LQR "
                                 "(not of the robust gain K)")
            for key in ("robustness_radius", "robustness_radius_elementwise"):
                g[key] = replace(g[key], description=g[key].description + " (0 when K has a pole outside the sector)")
        if res.lmi is not None:
            g["lmi"] = _lmi_items(res.lmi)
            for key in _REFERENCE_LQR:
                g[key] = replace(g[key], description=g[key].description + " of the reference sector LQR (the LMI "
                                 "design's pre-conditioner)")
    return pts


def _robust_items(r) -> dict:
    """The ``points/<k>/robust`` group: the family, the start and one certificate per plant
    (:mod:`acmm.design.robust`)."""
    c = r.certificates
    return {
        "plant": Dataset(np.array(r.family.labels, dtype=object), "1", "plant of the family: nominal, draw <k> "
                         "(index among all draws), scale <s>", dims=("plant",)),
        "inertia": Dataset(r.family.inertia, "slug*ft^2", "inertia of each plant", dims=("plant", "axis", "axis_col")),
        "tea": Dataset(r.family.theta, "rad", "each plant's TEA, connected to the design TEA", AXES,
                       dims=("plant", "axis")),
        "X": Dataset(np.array([x.X for x in c]), "1", "Lyapunov certificate of each plant's closed loop, scaled "
                     "states, time in 1/n", dims=("plant", "state", "state_col")),
        "certified_decay": Dataset(np.array([x.decay for x in c]), "n", "decay proved by X: every pole Re <= -it",
                                   dims=("plant",)),
        "certified_cone": Dataset(np.radians([x.cone_deg for x in c]), "rad", "cone proved by X: every pole "
                                  "|arg(-pole)| <= it", dims=("plant",)),
        "max_real": Dataset(np.array([x.max_real for x in c]), "n", "largest real part of the computed poles",
                            dims=("plant",)),
        "sector_held": Dataset(r.sector_held().astype(np.int8), "1",
                               "1: the plant is certified in the sector of design.sector", dims=("plant",)),
        "nominal_K": Dataset(r.nominal_K, UNIT_K, "the route's gain for the nominal plant (the search's start)",
                             STATE_NAMES, dims=("axis", "state")),
        "worst_abscissa": Dataset(r.worst_abscissa, "n", "largest pole real part over the family with the robust gain",
                                  attrs={"start_abscissa_n": r.start_abscissa, "restarts": r.restarts, "stop": r.stop,
                                         "draws": r.family.draws, "unphysical_draws": r.family.unphysical,
                                         "folded": r.family.folded}),
        "solve_time": Dataset(r.solve_time, "s", "wall time of the family, the search and the certificates"),
    }


def _lmi_items(r) -> dict:
    """The ``points/<k>/lmi`` group: the regional LMI design of a point (:mod:`acmm.design.regional_lmi`)."""
    return {
        "X": Dataset(r.X, "1", "Lyapunov certificate of the regions, scaled states, time in 1/n",
                     dims=("state", "state_col")),
        "X2": Dataset(r.X2, "1", "H2 matrix of the dilated energy bound, scaled states", dims=("state", "state_col")),
        "certified_margin": Dataset(r.certified_margin, "n", "sector margin proved by X"),
        "random_radius": Dataset(r.random_radius, "1", "smallest relative elementwise gain error found to move a "
                                 "pole out of the sector (random re-check)"),
        "energy": Dataset(r.energy, "1", "H2 control energy tr(K W Kt), scaled input, time in 1/n"),
        "cost_bound": Dataset(r.cost_bound, "1", "tr W, the upper bound of the energy from the cost LMIs (energy <= it checked)"),
        "solver_tolerance": Dataset(r.tol, "1", "the solver's gap tolerance of the final pass",
                                    attrs={"solver": r.solver, "status": r.status, "iterations": list(r.iterations),
                                           "rejected": "; ".join(r.rejected) or "none"}),
        "lmi_residual": Dataset(r.lmi_residual, "1", "largest eigenvalue of the cost LMIs relative to their norm "
                                "(accepted <= 1e-6)"),
        "solve_time": Dataset(r.solve_time, "s", "wall time of every LMI solve tried"),
    }


def _table_items(r, pts: dict) -> dict:
    """The top-level datasets of ``design.h5`` (the table, per-point summaries; report units,
    stated per dataset) around the point groups ``pts`` (nested under ``points``)."""
    return {
        "points": pts,
        "names": Dataset(np.array(r.table.names, dtype="S"), "1", "design point names in order", dims=("point",)),
        "point": Dataset(np.array(r.table.names, dtype=object), "1", "design point name", dims=("point",)),
        "inertia": Dataset(r.table.inertia, "slug*ft^2", "inertia per point", dims=("point", "axis", "axis_col")),
        "bias": Dataset(r.table.bias, "ft*lbf", "bias per point", AXES, dims=("point", "axis")),
        "tea": Dataset(r.table.tea, "rad", "TEA per point", AXES, dims=("point", "axis")),
        "level": Dataset(np.isin(np.arange(len(r.table.names)), r.table.level_rows()).astype(np.int8),
                         "1", "1: the point is a level of the stair-case; 0: a table node added between levels "
                         "where the scheduled loop left the sector (schedule.refine_points)", dims=("point",)),
        "K": Dataset(r.table.gain, UNIT_K, "design gain per point (u = -K x; sector LQR or regional LMI: design.pole_method)",
                     dims=("point", "axis", "state")),
        "state_names": Dataset(np.array(STATE_NAMES, dtype="S"), "1", "state order of eq 4.47", dims=("state",)),
        "state_units": Dataset(np.array(r.points[0].model.state_units, dtype="S"), "1",
                               "unit of each state (the state_units of the unit strings)", dims=("state",)),
        "wall_time": Dataset(r.wall_time, "s", "design wall time"),
        "sector_margin": Dataset(np.array([p.gain.margin for p in r.points]), "n",
                                 "worst pole distance into the sector per point (>0 inside)", dims=("point",)),
        "max_eig_condition": Dataset(np.array([p.gain.max_eig_condition for p in r.points]), "1",
                                     "largest eigenvalue condition number of A - B K per point, scaled states",
                                     dims=("point",)),
        "robustness_radius": Dataset(np.array([p.gain.robustness_radius for p in r.points]), "1",
                                     "sector robustness radius per point (relative gain error, normwise, scaled)",
                                     dims=("point",)),
        "robustness_radius_elementwise": Dataset(
            np.array([p.gain.robustness_radius_elementwise for p in r.points]), "1",
            "sector robustness radius per point (elementwise relative gain error)", dims=("point",)),
        "riccati_condition": Dataset(np.array([p.gain.riccati.riccati_condition for p in r.points]), "1",
                                     "CARE condition estimate per point" + (
                                         " (of the reference sector LQR, the LMI design's pre-conditioner)"
                                         if any(p.gain.lmi is not None for p in r.points) else ""),
                                     dims=("point",)),
    }


def _schedule_items(r) -> dict:
    """The ``schedule`` group of ``design.h5`` (fit, its checks, the path check; units stated per
    dataset) of a design with a schedule (``r.fit`` set)."""
    sched = {
        "coef": Dataset(r.fit.coef, UNIT_K + "/rad^k", "K_ij(θ2*) = Σ coef[k,i,j] θ2*^k" if r.fit.form == "polynomial"
                        else "least-squares polynomial of the gains, for reference (form table: K linear in θ2* "
                             "between the design points)", dims=("power", "axis", "state")),
        "variable": Dataset(r.fit.variable, "rad", "scheduling variable: pitch TEA θ2* per point", dims=("point",)),
        "rms_residual": Dataset(r.fit.rms_residual, UNIT_K, "RMS fit residual per element", dims=("axis", "state")),
        "rel_residual": Dataset(r.fit.rel_residual, "1", "RMS residual / max |K_ij|", dims=("axis", "state")),
        "check_names": Dataset(np.array(r.check.names, dtype="S"), "1", "where the scheduled gain was checked",
                               dims=("check",)),
        "check_theta2": Dataset(r.check.theta2, "rad", "pitch TEA of each check", dims=("check",)),
        "check_margin": Dataset(r.check.margin, "n", "sector margin of the scheduled gain (>0 inside)",
                                dims=("check",)),
        "check_max_real": Dataset(r.check.max_real, "n", "largest closed-loop Re λ with the scheduled gain",
                                  dims=("check",)),
        "fit_method": Dataset(np.array(r.fit.method, dtype="S"), "1",
                              "least_squares, or shifted_lqr (the quadratic converged on the path's "
                              "shifted LQR cost)"),
    }
    for key, val in r.fit.refit_info.items():
        value = np.array(val.encode("utf-8"), dtype="S") if isinstance(val, str) else float(val)
        # (the cone's half-angle keeps its degrees: a dataset in "deg" is written in rad)
        unit = "n" if key.startswith("max_real") or key == "decay" else "1"
        sched[f"refit_{key}"] = Dataset(value, unit, f"refit on the path: {key.replace('_', ' ')}")
    rf = r.refinement
    if rf is not None:
        sched["refine_added"] = Dataset(rf.added, "1", "table nodes added between the levels where the scheduled "
                                        "loop left the sector at a path TEA (schedule.refine_points)",
                                        attrs={"rounds": rf.rounds, "limit": rf.limit, "margin_n": rf.margin,
                                               "met": int(rf.met)})
    pc = r.path_check
    if pc is not None:
        sched["path"] = {
            "theta2": Dataset(pc.theta2, "rad", "pitch TEA of each path check (evenly spaced)", dims=("path",)),
            "s": Dataset(pc.s, "1", "blend parameter of each path check", dims=("path",)),
            "max_real": Dataset(pc.max_real, "n", "largest Re λ of the scheduled local loop", dims=("path",)),
            "sector_margin": Dataset(pc.margin, "n", "worst sector margin of the scheduled local loop (>0 inside)", dims=("path",)),
            "disk_margin": Dataset(pc.disk_margin, "1",
                                   "balanced multiloop disk margin alpha at the plant input (loop broken at u)", dims=("path",)),
            "disk_gain_margin": Dataset(pc.disk_gain_margin_db, "dB", "gain variation guaranteed by the disk", dims=("path",)),
            "disk_phase_margin": Dataset(np.deg2rad(pc.disk_phase_margin_deg), "rad", "phase variation guaranteed by the disk", dims=("path",)),
            "poles": Dataset(pc.poles, "rad/s", "closed-loop poles of the scheduled local loop", dims=("path", "pole")),
            "fraction_in_sector": Dataset(pc.fraction_in_sector, "1", "fraction of path TEAs with every pole in the sector"),
        }
    return sched


def design_figures_from_file(path: Path, out_dir: Path) -> list:
    """The figures of a design drawn from its ``design.h5`` alone (by the design stage after it
    wrote the file, and by ``acmm plot``): the points' pole map with the sector of ch. 5.2
    (Fig 5.2), the gain schedule (Figs 5.3–5.26, in the file's unit system) and the path check
    (margins, scheduled poles), read from the file and its stored config; nothing is designed again.

    Parameters
    ----------
    path : pathlib.Path
        The ``design.h5`` (imperial or SI).
    out_dir : pathlib.Path
        Folder of the figures: ``design_poles.png``, ``design_gains.png``,
        ``design_path_margins.png``, ``design_path_poles.png``.

    Returns
    -------
    list of functools.partial
        The figure calls, for :func:`acmm_qpp.results.draw_figures`.
    """
    from acmm.plots import design as design_plots  # deferred: matplotlib start-up
    from acmm.plots.base import state_units  # deferred: matplotlib start-up

    with h5py.File(path, "r") as f:
        attrs = {k: f.attrs[k] for k in f.attrs}
        names = list(map(h5_text, np.atleast_1d(f["names"][()])))
        poles = [np.asarray(f[f"points/{k}/poles"][()]) for k in sorted(f["points"])]
        tea = np.asarray(f["tea"][()], float)
        K = np.asarray(f["K"][()], float)
        sched = None
        if "schedule" in f:
            g = f["schedule"]
            sched = {"coef": np.asarray(g["coef"][()], float), "variable": np.asarray(g["variable"][()], float)}
            if "path" in g:
                sched["path"] = {k: np.asarray(g[f"path/{k}"][()]) for k in
                                 ("theta2", "max_real", "sector_margin", "disk_margin", "poles")}
    cfg = stored_config(attrs)
    s = design_settings(cfg)
    system = h5_text(attrs.get("unit_system", "imperial"))
    calls = [partial(design_plots.pole_map, poles, names, s.orbit_rate, s.sector.sigma, s.sector.half_angle_deg,
                     out_dir / "design_poles.png")]
    if sched is not None:
        form = h5_text(attrs.get("schedule_form", "polynomial"))
        theta2 = tea[:, 1]
        fine = np.linspace(theta2.min(), theta2.max(), 60)
        sampled = design_plots.SampledSchedule(
            form, fine, np.array([schedule_gain(form, sched["coef"], sched["variable"], K, t) for t in fine]))
        # the 24 state units and the torque unit as the gain figure's labels print them (Figs 5.3–5.26)
        if system == "imperial":
            units, torque = list(state_units(s.drf_mode)), "ft·lbf"
        else:
            units, torque = [u.replace("*", "·") for u in state_factors(s.drf_mode, system)[1]], "N·m"
        calls.append(partial(design_plots.gain_schedule_grid, theta2, K, sampled, STATE_NAMES,
                             out_dir / "design_gains.png", units=units, torque_unit=torque))
        pc = sched.get("path")
        if pc is not None:
            calls.append(partial(design_plots.schedule_path_check, pc["theta2"], pc["max_real"], pc["sector_margin"],
                                 pc["disk_margin"], out_dir / "design_path_margins.png"))
            calls.append(partial(design_plots.scheduled_pole_map, pc["poles"], pc["theta2"], s.orbit_rate,
                                 s.sector.sigma, s.sector.half_angle_deg, out_dir / "design_path_poles.png"))
    return calls
