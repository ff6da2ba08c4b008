"""The numbers README.md and the guide (docs/) quote about the packaged configs of Parts II and III,
each block of text computed from the stages' results (:mod:`acmm.report.page_runs`) and written
with the report's own formatting (:mod:`acmm.report.numbers`).

Each block is the text between ``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->`` in
README.md or one page of docs/ (``scripts/readme_numbers.py`` rewrites or checks them): the
claims of ch. 6, the per-level statistics of the stair-case, the design points' margins and
conditioning, the schedule along the path, the dwell-time certificate, the design routes, the
±30 % Monte Carlo counts of ch. 7 and the inertia-scaling margins; the qpp blocks of ch. 13–14
are in :mod:`acmm.report.page_blocks_qpp`.  Numbers are rounded to the digits that mean something
(3 significant digits for momenta and attitude errors, 3 decimals for margins in units of n, 2
significant digits for condition numbers and robustness radii), so the text does not change
between machines.
"""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from acmm.design.regional_lmi import random_gain_radius
from acmm.model import tea
from acmm.report.numbers import decoded, fixed, markdown_table, sci, sig
from acmm.report.page_blocks_qpp import (block_qpp_bullet, block_qpp_certificates, block_qpp_examples,
                                         block_qpp_reproduced, block_qpp_search)
from acmm.report.page_runs import run_stages
from acmm.report.sections.robustness import bounded_count, case_column
from acmm.report.sections.schedule import point_energy
from acmm.report.sections.table1 import table1_teas
from acmm.model.tea import NoEquilibriumError


def _wie_pitch_fold(cfg, pitch_bias: float = 4.0) -> float | None:
    """The largest pitch bias (ft·lbf) on the branch the TEA continuation follows from LVLH, for
    a pure pitch bias of ``pitch_bias`` that has no equilibrium; None when it has one.

    The continuation of :func:`acmm.model.tea.solve_tea` (products of inertia, then the bias) and its
    fold refinement, i.e. the bias its ``NoEquilibriumError`` names.
    """
    inertia, n = cfg.inertia.matrix(), cfg.orbit_rate
    bias = np.array([0.0, pitch_bias, 0.0])
    try:
        tea.solve_tea(inertia, n, bias)
        return None
    except NoEquilibriumError:
        pass
    lam = tea.bias_fold(inertia, n, bias)
    return None if lam is None else lam * pitch_bias


def block_table1_tea(r: dict) -> str:
    """The Table 1 TEA bullet: MB3 and AC TEAs, their residuals, MB3's zero-bias roots and the
    largest pitch bias with an MB3 equilibrium.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        One Markdown bullet.
    """
    def angles(t):
        return "(" + ", ".join(fixed(v, 2) for v in t.theta_deg) + ")°"

    teas = {k: table1_teas(r[f"config:{k}"]) for k in ("mb3", "ac")}       # the report's Table 1 numbers
    t, zero = {k: v[0] for k, v in teas.items()}, teas["mb3"][1]
    cfg = r["config:mb3"]
    roots = tea.all_equilibria(cfg.inertia.matrix(), cfg.orbit_rate, np.zeros(3))
    other = [x for x in roots if np.max(np.abs(x.theta - zero.theta)) > 1e-6]
    fold = _wie_pitch_fold(cfg)

    def bound(x):
        return "≤ " + sci(10.0 ** math.ceil(math.log10(max(x, 1e-16))), 1)     # 0: round-off level
    text = ("* **Table 1 TEA** (bias back-solved from eq 4.1 at the printed attitude, continuation branch):\n"
            f"  MB3 {angles(t['mb3'])}, residual {bound(t['mb3'].residual)} ft·lbf; "
            f"AC {angles(t['ac'])}, residual {bound(t['ac'].residual)} ft·lbf.\n"
            f"  MB3 with zero bias: {fixed(zero.theta_deg[1], 2)}° pitch")
    if other:
        text += (f" ({fixed(other[0].theta_deg[1], 2, sign=True)}° is the other principal-axis root, "
                 "`acmm tea mb3 --all`)")
    text += ".\n"
    text += ("  The 4 ft·lbf pitch bias of Wie et al. has " + (
        f"no MB3 equilibrium: largest pitch bias {sig(fold, 4)} ft·lbf.\n" if fold is not None
        else "an MB3 equilibrium.\n"))
    return text


def block_claims(r: dict) -> str:
    """Claims 1 and 2 of ch. 6, the sector designs, the schedule along the path, the ±30 % sweep.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    s_c, s_d = r["simulate:mb3"], r["simulate:mb3_decoupled"]
    o, err = s_c["orbits"], np.degrees(np.abs(s_c["attitude_error"]))
    first, late = err[o <= 1.0].max(axis=0), err[o >= 2.0].max(axis=0)
    rows = [
        ["1", "cross-inertia-free MB3 design (`mb3_decoupled`) on the nonlinear model",
         f"{decoded(s_d['attrs']['verdict'])} at **{sig(s_d['attrs']['stop_time_orbits'], 2)} orbit**"],
        ["1", "fully coupled MB3 design (`mb3`)",
         f"{decoded(s_c['attrs']['verdict'])} over {sig(o[-1], 2)} orbits"],
        ["1", "its peak attitude error in the first orbit, roll / pitch / yaw",
         " / ".join(sig(v) for v in first) + "°"],
        ["1", "its peak attitude error after orbit 2, roll / pitch / yaw",
         " / ".join(sig(v) for v in late) + "°"],
    ]
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    dwell = np.diff(np.append(lv["start"], st["t"][-1])) / orbit
    pitch = np.degrees(lv["tea_estimate"][:, 1])
    steady = np.degrees(lv["steady_error"]).max(axis=0)
    pk = np.asarray(lv["peak_momentum"])
    rows += [
        ["2", f"stair-case MB3 → AC (`staircase`): {len(pk)} levels, pitch TEA "
              f"{sig(pitch[0])}° … {sig(pitch[-1], 2)}°, dwell {sig(dwell.mean())} orbits",
         f"{decoded(st['attrs']['verdict'])} over {sig(st['orbits'][-1])} orbits"],
        ["2", "largest steady attitude error of a level, roll / pitch / yaw",
         " / ".join(sig(v, 2) for v in steady) + "°"],
        ["2", "peak CMG momentum per level (every integrator step)",
         f"{sig(pk.min())} … {sig(pk.max())} ft·lbf·s (AC level {sig(pk[-1])}; "
         f"limit {sig(cfg.actuators.momentum_limit)})"],
    ]
    d = r["design:staircase"]
    pa = d["schedule"]["path"]
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    margins = [float(np.min(r[f"design:{k}"]["sector_margin"])) for k in ("mb3", "ac", "staircase")]
    conds = [float(np.max(r[f"design:{k}"]["max_eig_condition"])) for k in ("mb3", "ac", "staircase")]
    rows += [
        ["sector", f"smallest sector margin of the MB3, AC and {len(d['sector_margin'])} stair-case design points "
                   f"({int(np.sum(d['level']))} levels and the table's nodes)",
         f"{fixed(min(margins))}n"],
        ["sector", "relative Riccati residual of the sector LQRs (scaled; MB3, AC and the stair-case's "
                   "pre-conditioning designs), decade above the largest",
         "≤ " + sci(10.0 ** math.ceil(math.log10(max(float(p["riccati_residual"]) for k in ("mb3", "ac", "staircase")
                                                      for p in r[f"design:{k}"]["points"].values()))), 1)],
        ["sector", "largest eigenvalue condition of A − BK (scaled): AC / MB3 / any stair-case point",
         f"{sci(conds[1])} / {sci(conds[0])} / {sci(conds[2])}"],
        ["schedule", f"largest Re λ of the scheduled loop over {mr.size} path TEAs", f"**{fixed(mr.max())}n**"],
        ["schedule", "worst sector margin along the path", f"{fixed(mg.min(), 2)}n"],
        ["schedule", "smallest disk margin α at the plant input", fixed(dm.min())],
    ]
    w = r["sweep"]
    counts = [(lab.upper(), *bounded_count(w, lab)) for lab in (decoded(x) for x in np.atleast_1d(w["base_names"]))]
    rows.append(["ch. 7", "±30 % inertia element draws bounded with the fixed nominal gain "
                          "(`sweep_inertia30`)", ", ".join(f"{lab} **{ok}/{n}**" for lab, ok, n in counts)])
    return markdown_table(["claim", "quantity", "computed"], rows)


def block_staircase_levels(r: dict) -> str:
    """Per-level statistics of the 130-orbit stair-case (``sim.h5: levels/*``).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per level.
    """
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    rows = []
    for k in range(len(lv["start"])):
        rows.append([str(k), sig(lv["start"][k] / orbit), fixed(np.degrees(lv["tea_estimate"][k, 1]), 1),
                     " / ".join(sig(v, 2) for v in np.degrees(lv["steady_error"][k])),
                     sig(lv["peak_momentum"][k])])
    return markdown_table(["level", "start (orbit)", "θ2* (deg)", "steady \\|θ − θ̂*\\| roll / pitch / yaw (deg)",
                           "peak \\|h\\| (ft·lbf·s)"], rows, "rrrrr")


def block_design_points(r: dict) -> str:
    """Per design point of the stair-case: sector margin, conditioning, robustness radius.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per design point.
    """
    d = r["design:staircase"]
    n = r["config:staircase"].orbit_rate
    keys = sorted(d["points"])
    lmi = all("lmi" in d["points"][key] for key in keys)
    rows = []
    for k, name in enumerate(d["names"]):
        p = d["points"][keys[k]]
        row = [decoded(name), fixed(np.degrees(d["tea"][k, 1]), 1), fixed(d["sector_margin"][k]),
               sci(d["max_eig_condition"][k]), sci(d["robustness_radius"][k]),
               sci(d["robustness_radius_elementwise"][k])]
        if lmi:
            row += [fixed(float(p["lmi"]["certified_margin"])), sci(float(p["lmi"]["random_radius"])),
                    sig(point_energy(p, n), 3)]
        rows.append(row + [sci(d["riccati_condition"][k])])
    head = ["point", "θ2* (deg)", "sector margin (n)", "eigenvalue condition (scaled)",
            "robustness radius ‖δK̃‖/‖K̃‖", "same, max \\|δK_ij/K_ij\\|"]
    if lmi:
        head += ["margin certified by X (n)", "radius (random re-check)", "energy"]
    head.append("κ_CARE of the pre-conditioning LQR" if lmi else "κ_CARE")
    return markdown_table(head, rows, "l" + "r" * (len(head) - 1))


def block_schedule_path(r: dict) -> str:
    """The scheduled gain on the local loop along the path (``design.h5: schedule/path/*``).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    d = r["design:staircase"]
    sc, pa = d["schedule"], d["schedule"]["path"]
    th = np.degrees(np.asarray(pa["theta2"]))
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    i = int(np.argmin(dm))
    form = decoded(d["attrs"]["schedule_form"]) if "attrs" in d and "schedule_form" in d["attrs"] else (
        "polynomial" if "refit_converged" in sc else "table")
    rows = [["schedule form", "table look-up, K linear in θ2* between the design points" if form == "table"
             else "2nd-order polynomial in θ2*"]]
    if "refit_converged" in sc:
        rows += [
            ["least-squares fit before the refit: largest Re λ over the refit's "
             f"{int(sc['refit_n_tea'])} TEAs", f"{fixed(sc['refit_max_real_before'], 2, sign=True)}n"],
            ["converged quadratic (homotopy stages, Newton steps to the step tolerance)",
             f"{int(sc['refit_homotopy_stages'])}, {int(sc['refit_iterations'])}"]]
    rows += [
        ["largest Re λ of the scheduled local loop", f"**{fixed(mr.max())}n**"],
        ["worst sector margin", f"{fixed(mg.min(), 2)}n"],
        ["fraction of the path with every pole in the sector", fixed(np.mean(mg >= 0))],
        ["smallest disk margin α at the plant input (skew 0)",
         f"{fixed(dm[i])} at θ2* = {fixed(th[i], 1)}° (±{sig(pa['disk_gain_margin'][i], 2)} dB, "
         f"±{sig(np.degrees(pa['disk_phase_margin'][i]), 2)}°)"],
    ]
    if "refit_converged" in sc:
        rows.append(["largest RMS deviation of a refined polynomial from the LQR gains, / max\\|K_ij\\| "
                     "(`schedule/rel_residual`)", sig(np.max(sc["rel_residual"]), 2)])
    return markdown_table([f"along the path ({th.size} TEAs, {fixed(th[0], 1)}° … {fixed(th[-1], 1)}°)", "value"], rows)


def block_dwell_certificate(r: dict) -> str:
    """The stair-case's dwell-time certificate (``design.h5: dwell/*``, :mod:`acmm.design.dwell`).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    g = r["design:staircase"]["dwell"]
    n = r["config:staircase"].orbit_rate
    dwell, tau = np.asarray(g["dwell"]), float(g["tau_star"])
    rows = [["levels (frozen closed loops: coupled model about each TEA, scheduled gain)", str(dwell.size + 1)],
            ["decay rate λ every admissible switching sequence is proved to keep (1/64 of the slowest level's)",
             f"{sig(float(g['decay_rate']) / n, 2)}n"],
            ["certified minimum dwell τ* (Geromel–Colaneri LMIs per level, switches both ways, bisection)",
             f"**{fixed(tau, 2)} orbit**"],
            ["shortest dwell of a level in the scenario", f"{fixed(dwell.min(), 2)} orbit"],
            ["verdict", "certified: every level is held at least τ*" if np.all(dwell >= tau) else "NOT certified"],
            ["TEA-step transient bound (certified ellipsoids): \\|u\\|, \\|h − h*\\|",
             f"{sig(np.max(g['u_bound']))} ft·lbf, {sig(np.max(g['h_bound']))} ft·lbf·s"]]
    return markdown_table(["dwell-time certificate (`acmm certify staircase`)", "value"], rows)


def block_design_routes(r: dict) -> str:
    """The LQR route (sector LQR, the report's method) and the regional LMI route side by side at
    MB3 and AC: margin, conditioning, robustness, energy, fastest pole, and the ±30 % Monte Carlo
    and inertia-scaling margin of each fixed gain on the same draws.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    def point(d):
        return d["points"][sorted(d["points"])[0]]

    def margin_range(sw, label, decimals=3):
        lo, hi = sw["margin"][f"{label}_down"], sw["margin"][f"{label}_up"]
        return f"{fixed(lo['limit'], decimals)} … {fixed(hi['limit'], decimals)}"

    rows = []
    for name, label in (("mb3", "MB3"), ("ac", "AC")):
        n = r[f"config:{name}"].orbit_rate
        for route, d, sw, base in (("sector LQR", r[f"design:{name}"], r["sweep"], name),
                                   ("regional LMI", r[f"design:{name}_lmi"], r["sweep_lmi"], f"{name}_lmi"),
                                   ("robust gain for the ±30 % family (from the LMI gain)",
                                    r[f"design:{name}_robust"], r["sweep_robust"], f"{name}_robust")):
            p = point(d)
            A, B, K = (np.asarray(p[k]) for k in ("A", "B", "K"))
            fastest = float(np.max(-np.real(np.asarray(p["poles"])))) / n
            rr = (float(p["lmi"]["random_radius"]) if "lmi" in p and "robust" not in p
                  else random_gain_radius(A, B, K, n))
            ok, tot = bounded_count(sw, base)
            if "robust" in p:
                # a nonsmooth search: its gain moves with the BLAS kernel (docs/reproducibility.md),
                # so only what stays to these digits under Haswell and Prescott is printed
                loose = "— (kernel-dependent)"
                rows.append([f"{label}, {route}", fixed(float(p["sector_margin"]), 1), loose, "— (outside)",
                             "— (outside)", loose, loose, f"{ok}/{tot}", margin_range(sw, base, 1)])
                continue
            inside = float(p["sector_margin"]) > 0          # a radius is the distance to leaving the sector
            rows.append([f"{label}, {route}", fixed(float(p["sector_margin"])), sig(float(p["max_eig_condition"]), 2),
                         sci(float(p["robustness_radius_elementwise"])) if inside else "— (outside)",
                         sci(rr) if inside else "— (outside)",
                         sig(point_energy(p, n), 3), fixed(fastest, 1), f"{ok}/{tot}",
                         margin_range(sw, base)])
    return markdown_table(["station, route", "margin (n)", "κ max", "radius (first order, elementwise)",
                           "radius (random re-check)", "energy", "fastest pole (n)", "±30 % bounded and settled",
                           "tolerated inertia scaling s"], rows)


def block_robust_family(r: dict) -> str:
    """The robust route's family and per-plant certificates at MB3 and AC (``design.robust``), and
    its gain on the packaged sweep's draws: how many of them have an equilibrium connected to the
    design TEA, and how many of those stay bounded and settled.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    rows = []
    for name, label in (("mb3", "MB3"), ("ac", "AC")):
        p = r[f"design:{name}_robust"]["points"]
        g = p[sorted(p)[0]]["robust"]
        decay = np.asarray(g["certified_decay"], float)
        cone = np.degrees(np.asarray(g["certified_cone"], float))
        verdict = case_column(r["sweep_robust"], f"{name}_robust", "verdict")
        folded = np.array(["folds" in x for x in case_column(r["sweep_robust"], f"{name}_robust", "reason")])
        # (two digits of the decay and whole degrees: what stays under another BLAS kernel)
        rows.append([label, str(decay.size), f"{sig(float(decay.min()), 2)}n",
                     f"{fixed(float(cone.max()), 0)}°", f"{int(np.sum(np.asarray(g['sector_held'])))}/{decay.size}",
                     f"{int(np.sum(~folded))}/{folded.size}",
                     f"{int(np.sum(verdict[~folded] == 'bounded'))}/{int(np.sum(~folded))}",
                     f"{int(np.sum(verdict == 'bounded'))}/{verdict.size}"])
    return markdown_table(["station", "plants in the family", "decay every plant is certified to keep",
                           "cone every plant is certified in", "plants certified in the sector",
                           "packaged draws with an equilibrium connected to the design TEA",
                           "of those, bounded and settled", "all draws bounded and settled"], rows)


def block_staircase_routes(r: dict) -> str:
    """The packaged stair-case and its variants (:data:`STAIRCASE_VARIANTS`), each judged on a
    1 001-TEA path: path stability and sector, disk margin, the point designs'
    conditioning, robustness and energy, the nonlinear run's peak CMG momentum and the dwell-time
    certificate.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    labels = {"staircase": "regional LMI points, table (packaged)",
              "staircase_lqr": "sector LQR points (the report's route), table",
              "staircase_lqr_quadratic": "sector LQR points, the report's quadratic by least squares (ch. 5.3)",
              "staircase_quadratic": "regional LMI points, quadratic converged on the path's shifted LQR cost"}
    rows = []
    for name, label in labels.items():
        d, sim = r[f"design:{name}"], r[f"simulate:{name}"]
        n = r[f"config:{name}"].orbit_rate
        pa, sc, g = d["schedule"]["path"], d["schedule"], d.get("dwell")
        energy = [point_energy(d["points"][key], n) for key in sorted(d["points"])]
        tau = "no certificate" if g is None or "tau_star" not in g or not np.isfinite(float(g["tau_star"])) else (
            f"{fixed(float(g['tau_star']), 2)} orbit" + ("" if np.all(np.asarray(g["dwell"]) > float(g["tau_star"]))
                                                         else " (NOT certified)"))
        refit = ""
        if "refit_converged" in sc and decoded(sc["fit_method"]) == "shifted_lqr":
            refit = (f" (from the least-squares fit's {fixed(float(sc['refit_max_real_before']), 2, sign=True)}n; "
                     f"Re λ < −{fixed(float(sc['refit_decay']), 2)}n and the {fixed(float(sc['refit_cone_deg']), 0)}° "
                     "cone at " + f"{int(sc['refit_n_tea'])} TEAs; "
                     + ("Newton's method converged" if float(sc["refit_converged"]) else
                        "NOT converged: " + decoded(sc["refit_message"])) + ")")
        verdict = decoded(sim["attrs"]["verdict"])
        peak = sig(np.max(sim["levels"]["peak_momentum"])) if verdict != "diverged" else (
            f"diverged at orbit {fixed(float(sim['attrs']['stop_time_orbits']), 1)}")
        inside = int(np.sum(np.asarray(pa["sector_margin"]) >= 0))
        loop = [f"{fixed(np.max(pa['max_real']), sign=True)}n", f"{fixed(np.min(pa['sector_margin']), 2)}n ({inside})",
                fixed(np.min(pa["disk_margin"])), peak, tau]
        rows.append([label + refit, f"{np.asarray(pa['theta2']).size}", *loop[:3],
                     sig(np.max(d["max_eig_condition"]), 2), sci(np.min(d["robustness_radius_elementwise"])),
                     sig(max(energy), 3), *loop[3:]])
    return markdown_table(["stair-case (route, schedule)", "path TEAs", "largest Re λ on the path",
                           "worst sector margin on the path (TEAs with every pole in the sector)", "smallest disk margin", "κ max (points)",
                           "radius (first order, elementwise, min over points)", "energy (max over points)",
                           "peak \\|h\\| (ft·lbf·s)", "τ* (dwell 10.8 orbit)"], rows)


def block_sweep_monte_carlo(r: dict) -> str:
    """Verdict counts of the ±30 % inertia Monte Carlo (``sweep_inertia30``, ``sweep.h5``).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    names = [decoded(x) for x in np.atleast_1d(w["base_names"])]
    verdict = np.array([decoded(x) for x in np.atleast_1d(w["verdict"])])
    base, draws = np.atleast_1d(w["base"]), np.atleast_1d(w["n_draws"])
    peak = np.degrees(np.atleast_2d(w["peak_attitude_error"]))
    rows = []
    for k, lab in enumerate(names):
        sel = base == k
        v = verdict[sel]
        nd = int(draws[sel].sum())
        ok = peak[sel][v == "bounded"]
        med = " / ".join(sig(x, 2) for x in np.median(ok, axis=0)) if ok.size else "—"
        rows.append([lab.upper(), str(v.size), f"**{int(np.sum(v == 'bounded'))}**",
                     str(int(np.sum(v == "not_settled"))), str(int(np.sum(v == "diverged"))),
                     str(int(np.sum(v == "no_equilibrium"))),
                     f"{nd - v.size} ({100 * v.size / nd:.0f} % of draws physical)", med])
    return markdown_table(["base", "cases", "bounded", "not settled", "diverged", "no equilibrium",
                           "unphysical draws redrawn", "median peak error of the bounded, r / p / y (deg)"],
                          rows, "lrrrrrrr")


def block_sweep_diverged(r: dict) -> str:
    """Where the diverged cases' plants have their equilibrium (``sweep.h5: tea_true``,
    ``tea_estimate``).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    verdict = np.array([decoded(x) for x in np.atleast_1d(w["verdict"])])
    base = np.atleast_1d(w["base"])
    rows = []
    for k, lab in enumerate(decoded(x) for x in np.atleast_1d(w["base_names"])):
        sel = (base == k) & (verdict == "diverged")
        true = np.degrees(np.atleast_2d(w["tea_true"])[sel, 1])
        est = np.degrees(np.atleast_2d(w["tea_estimate"])[sel, 1])
        lo, hi = np.percentile(true, [5, 95])
        rows.append([lab.upper(), str(int(sel.sum())), f"{sig(lo, 2)}° … {sig(hi, 2)}°",
                     f"{sig(np.median(np.abs(true - est)), 2)}°",
                     f"{sig(np.min(np.atleast_1d(w['time_to_divergence'])[sel]), 2)}"])
    return markdown_table(["base", "diverged", "plant's pitch TEA (5–95 %)", "median \\|TEA − estimate\\| (pitch)",
                           "earliest divergence (orbit)"], rows, "lrrrr")


def block_sweep_margin(r: dict) -> str:
    """The tolerated uniform inertia scaling of each fixed design (``sweep.h5: margin/*``).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table, one row per base.
    """
    w = r["sweep"]
    mg = w["margin"]
    rows = []
    for lab in (decoded(x) for x in np.atleast_1d(w["base_names"])):
        lo, hi = mg[f"{lab}_down"], mg[f"{lab}_up"]
        why = {"bounded": "not settled", "attitude": "diverged"}

        def reason(m):
            text = decoded(m["failure_reason"])
            return next((v for k, v in why.items() if text.startswith(k)), text)
        rows.append([lab.upper(), f"{fixed(lo['limit'])} … {fixed(hi['limit'])}",
                     f"{fixed(lo['first_failure'])} ({reason(lo)}) and {fixed(hi['first_failure'])} ({reason(hi)})"])
    return markdown_table(["design", "tolerated s", "first failure"], rows)


#: every generated block (each once, in README.md or one page of docs/), name → its function
BLOCKS = {"table1_tea": block_table1_tea, "qpp_bullet": block_qpp_bullet, "claims": block_claims,
          "staircase_levels": block_staircase_levels, "design_points": block_design_points,
          "schedule_path": block_schedule_path, "dwell_certificate": block_dwell_certificate,
          "design_routes": block_design_routes, "robust_family": block_robust_family,
          "staircase_routes": block_staircase_routes, "sweep_monte_carlo": block_sweep_monte_carlo,
          "sweep_diverged": block_sweep_diverged, "sweep_margin": block_sweep_margin,
          "qpp_reproduced": block_qpp_reproduced, "qpp_examples": block_qpp_examples,
          "qpp_certificates": block_qpp_certificates, "qpp_search": block_qpp_search}


def compute_blocks(r: dict) -> dict[str, str]:
    """Every generated block from the results of :func:`acmm.report.page_runs.run_stages`.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    dict
        Block name (:data:`BLOCKS`) → its Markdown text.
    """
    return {name: block(r) for name, block in BLOCKS.items()}


def fresh_blocks(workers: int | None = None) -> dict[str, str]:
    """Run the stages into a temporary results root and compute every block.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the sweep.

    Returns
    -------
    dict
        Block name → Markdown text.
    """
    with tempfile.TemporaryDirectory(prefix="readme-numbers-") as tmp:
        return compute_blocks(run_stages(Path(tmp), workers))
