"""Section gain schedules and pole maps (Figs 5.3–5.26; sector LQR and schedule of ch. 5.2–5.3)."""
from __future__ import annotations

import numpy as np

from acmm_qpp.results import h5_text
from acmm.design.dwell import NOT_COVERED
from acmm.design.regional_lmi import control_energy
from acmm.model.state_scaling import torque_scale
from acmm.report.constants import AXES, STAIRCASES
from acmm.report.context import SectionWriter
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from acmm.design.schedule import schedule_gain
from acmm.model import linearize as lin
from acmm.plots import design as design_plots
from matplotlib.ticker import MaxNLocator


def _summary(ctx: SectionWriter) -> None:
    """Part: design summary, conditioning and the schedule along the path (tables; sector LQR and schedule
    of ch. 5.2–5.3)."""
    ctx.section("schedule")
    d = ctx.data("acmm design:" + ctx.g.configs["staircase"].name)
    cfg = ctx.g.configs["staircase"]
    sc = d["schedule"]
    form = d["attrs"].get("schedule_form", "polynomial")
    order = sc["coef"].shape[0] - 1
    pts = [d["points"][k] for k in sorted(d["points"])]
    margins = np.array([float(p["sector_margin"]) for p in pts])
    resid = np.array([float(p["riccati_residual"]) for p in pts])
    backward = [float(p["riccati_backward_error"]) for p in pts if "riccati_backward_error" in p]
    if form == "table":
        how = ("then a table look-up schedule, each gain linear in θ2* between the design points (the form "
               "the report names beside its order-2 polynomial for claim 2, ch. 6)")
    else:
        how = (f"then an order-{order} polynomial schedule in θ2* (the report uses order 2), fitted by "
               f"{h5_text(sc.get('fit_method', b'least_squares'))}")
    lmi = all("lmi" in p for p in pts)
    route = ("regional pole placement by LMIs (every pole certified in the sector by a Lyapunov matrix, "
             "minimal H2 energy bound, coordinates pre-conditioned by the sector LQR; guide: 'The regional "
             "LMI route')" if lmi else "sector LQR")
    ctx.doc.p(f"{len(pts)} design points along the MB3 → AC blend, evenly spaced in pitch TEA from "
              f"{np.degrees(d['tea'][0, 1]):.2f}° to {np.degrees(d['tea'][-1, 1]):.2f}°; {route} "
              f"(Re λ ≤ −{cfg.design.sector.sigma}n, {cfg.design.sector.half_angle_deg:g}°) per point, "
              f"{how} (guide: docs/results/design.md, 'The gain schedule').")
    cm = np.asarray(sc["check_margin"])
    ctx.doc.table(["quantity", "value"], [
        ["worst sector margin of the point gains (units of n, > 0 inside)", f"{margins.min():+.4f}"],
    ] + ([["smallest margin certified by the LMI's Lyapunov matrices (units of n)",
           f"{min(float(p['lmi']['certified_margin']) for p in pts):+.4f}"]] if lmi else []) + [
        ["worst relative Riccati residual (scaled coordinates)" + (" of the pre-conditioning sector LQRs" if lmi else ""),
         f"{resid.max():.2e}"],
    ] + ([["worst Riccati backward error after refinement (the accepted quantity)", f"{max(backward):.1e}"]]
         if backward else []) + ([
        ["worst relative schedule fit residual (RMS / max|K_ij|)", f"{np.max(sc['rel_residual']):.3f}"]]
         if form != "table" else []) + [
        [f"scheduled gain on the local models: worst sector margin over {cm.size} checks (points and "
         "midpoints, units of n)",
         f"{cm.min():+.4f} ({'all in the sector' if cm.min() > 0 else 'NOT all in the 45° sector'})"],
    ] + ([["scheduled gain on the local models: largest closed-loop Re λ over the checks (units of n)",
           f"{np.max(sc['check_max_real']):+.4f} "
           f"({'stable at every check' if np.max(sc['check_max_real']) < 0 else 'UNSTABLE at some check'})"]]
         if "check_max_real" in sc else []), "Stair-case design summary")
    _conditioning(ctx, d, pts)
    if "dwell" in d and "jump_up" in d["dwell"]:       # (a single level has no switch to certify)
        _dwell(ctx, d["dwell"], cfg.orbit_rate)


def point_energy(p: dict, n: float) -> float:
    """The control energy bound of one stored design point (``design.h5: points/<k>``), the
    number the routes tables of the report and of the guide show
    (:func:`acmm.design.regional_lmi.control_energy`, ch. 5.2's sector LQR or the LMI gain).

    Parameters
    ----------
    p : dict
        The point's datasets as read by :func:`acmm_qpp.results.read_h5` (``A``, ``B``, ``K``,
        ``scales``).
    n : float
        Orbit rate, rad/s.

    Returns
    -------
    float
        The energy, in the units of :func:`acmm.design.regional_lmi.control_energy` (input
        scaled, time in 1/n).
    """
    A, B, K, scales = (np.asarray(p[k]) for k in ("A", "B", "K", "scales"))
    return control_energy(A, B, K, n, scales, torque_scale(scales))


def route_numbers(d: dict, sim: dict, n: float) -> dict:
    """What the stair-case routes tables of the report and of the guide show of one stair-case.

    Parameters
    ----------
    d, sim : dict
        Its ``design.h5`` and ``sim.h5`` as read by :func:`acmm_qpp.results.read_h5`.
    n : float
        Orbit rate, rad/s.

    Returns
    -------
    dict
        Over the design points: ``kappa``, the largest eigenvalue condition, and ``radius``, the
        smallest elementwise robustness radius (dimensionless), ``energy``, the largest
        :func:`point_energy`; ``peak``, the peak CMG momentum in ft·lbf·s (None: the run diverged,
        at orbit ``stop``); ``tau``, the certified dwell τ* in orbits (None: no certificate).
    """
    pts = [d["points"][k] for k in sorted(d["points"])]
    tau = float(d.get("dwell", {}).get("tau_star", np.nan))
    diverged = h5_text(sim["attrs"]["verdict"]) == "diverged"
    return {"kappa": max(float(p["max_eig_condition"]) for p in pts),
            "radius": min(float(p["robustness_radius_elementwise"]) for p in pts),
            "energy": max(point_energy(p, n) for p in pts),
            "peak": None if diverged else float(np.max(sim["levels"]["peak_momentum"])),
            "stop": float(sim["attrs"]["stop_time_orbits"]), "tau": tau if np.isfinite(tau) else None}


def _routes(ctx: SectionWriter) -> None:
    """Part: the packaged stair-case (normally regional LMI points, a table look-up schedule) beside it on
    the report's route (sector LQR points, the same form) and the report's quadratic converged on the path
    (:data:`acmm.report.gather.REPORT_VARIANTS`), judged on the same path TEAs, simulated and certified
    (issue 32 item 5, issue 41 item 4)."""
    cfgs = ctx.g.configs
    quad, why = _quadratic(ctx, ("design", "simulate"))
    rows = []
    for key in (k for k in STAIRCASES if k != "staircase_quadratic" or quad is not None):
        cfg = cfgs[key]
        d, sim = ctx.data("acmm design:" + cfg.name), ctx.data("acmm simulate:" + cfg.name)
        pts = [d["points"][k] for k in sorted(d["points"])]
        lmi = all("lmi" in p for p in pts)
        x, pa = route_numbers(d, sim, cfg.orbit_rate), d["schedule"].get("path", {})
        form = "table" if d["attrs"].get("schedule_form") == "table" else {
            "shifted_lqr": "quadratic converged on the path"}.get(
            h5_text(d["schedule"].get("fit_method", b"least_squares")), "quadratic, least squares")
        rows.append([("regional LMI points" if lmi else "sector LQR points") + f", {form} (`{cfg.name}`"
                     + {"staircase": ", packaged)", "staircase_lqr": ", the report's route)"}.get(key, ")"),
                     f"{x['kappa']:.2g}", f"{x['radius']:.1e}",
                     f"{min(float(p['lmi']['random_radius']) for p in pts):.1e}" if lmi else "—",
                     f"{x['energy']:.3g}",
                     f"{np.max(pa['max_real']):+.3f}" if "max_real" in pa else "—",
                     (f"{np.sum(np.asarray(pa['sector_margin']) >= 0)} of {np.size(pa['sector_margin'])}"
                      if "sector_margin" in pa else "—"),
                     f"{x['peak']:.0f}" if x["peak"] is not None else f"diverged at orbit {x['stop']:.1f}",
                     "—" if x["tau"] is None else f"{x['tau']:.2f} orbit"])
    ctx.doc.table(["stair-case (route, schedule)", "κ max (points)",
                   "robustness radius (first order, elementwise, min)", "radius (random re-check, min)",
                   "control energy (max over points)", "largest Re λ on the path (n)",
                   "path TEAs with every pole in the sector", "peak |h| (ft·lbf·s)", "certified dwell τ*"], rows,
                  "The design routes and schedule forms on the stair-case: the packaged table, the report's "
                  "route with the same table, and the report's quadratic form converged on the path; the ±30 % "
                  "Monte Carlo of each route's fixed MB3 and AC gains is in the guide (docs/results/robustness.md)"
                  + ("" if why is None else f"; {why}"))


def _quadratic(ctx: SectionWriter, stages: tuple) -> tuple:
    """(config, None) of the report's quadratic stair-case when its ``stages`` (``"design"``,
    ``"simulate"``) ran, else (None, why: not designed by --fast, or its stage's one-line failure)."""
    cfg = ctx.g.configs.get("staircase_quadratic")
    if cfg is None:
        return None, ("the quadratic is not designed by a --fast report (its LMI points and refit are "
                      "another stair-case design)")
    for stage in stages:
        f = ctx.g.failed.get(f"{stage}:staircase_quadratic")
        if f is not None:
            return None, f"the quadratic's {stage} failed: {f.message}"
    return cfg, None


def _dwell(ctx: SectionWriter, g: dict, n: float) -> None:
    """The stair-case's dwell-time certificate (``design.h5`` group ``dwell``,
    :mod:`acmm.design.dwell`): the systematic procedure ch. 5.3 says does not exist, for the
    linearized switched system."""
    lam = float(g["decay_rate"])
    tau, dwell = float(g["tau_star"]), np.asarray(g["dwell"])
    certified = bool(np.all(dwell >= tau))
    ctx.doc.p("The stair-case as a switched system (guide: docs/results/design.md, 'Dwell-time certificate'): each level's frozen "
              "closed loop (the coupled model of eq 4.46 about the level's TEA, with the scheduled gain) has its own "
              "Lyapunov function, found by LMIs (Geromel and Colaneri): it decays at the rate λ while the level "
              "holds, and after a dwell τ* it is below the next level's, switches checked both ways; the smallest "
              "such τ* is found by bisection, and every matrix is re-checked by eigenvalues before it is accepted. "
              f"A certificate of the linearized switched system; not covered: {NOT_COVERED}.")
    ctx.doc.table(["quantity", "value"], [
        ["proved decay rate λ (units of n)", f"{lam / n:.4f}"],
        ["certified minimum dwell τ* (orbits)", f"{tau:.3f}"],
        ["shortest dwell of a level (orbits)", f"{dwell.min():.2f}"],
        ["verdict", "certified: every level is held at least τ*" if certified else "NOT certified"],
        ["TEA-step transient bound, |u| (ft·lbf) / |h − h*| (ft·lbf·s)",
         f"{np.max(g['u_bound']):.3g} / {np.max(g['h_bound']):.4g}"],
    ], "Dwell-time certificate of the stair-case")


def _true_poles(ctx: SectionWriter) -> np.ndarray:
    """Part, claim 1: the (24,) poles, rad/s, of the ``mb3_decoupled`` gain on the coupled linear model
    (ch. 4) at its TEA, eig(A − B K)."""
    dec = ctx.data("acmm design:mb3_decoupled")
    cfg_m = ctx.g.configs["mb3"]
    true = lin.design_point(cfg_m.inertia.matrix(), dec["tea"][0], cfg_m.orbit_rate, model="coupled",
                            drf_mode=cfg_m.design.drf_mode)
    return np.linalg.eigvals(true.A - true.B @ dec["K"][0])


def _gain_figure(ctx: SectionWriter) -> None:
    """Part: the 72 gains K(i, j) (ft·lbf per state unit) of the stair-case points (markers), their
    schedule (lines) and the report's quadratic (dashed) vs pitch TEA, one panel per column j (Figs
    5.3–5.26)."""
    cfg = ctx.g.configs["staircase"]
    quad, _ = _quadratic(ctx, ("design",))
    other = None if quad is None else ctx.data("acmm design:" + quad.name)
    design = ctx.data("acmm design:" + cfg.name)
    plt = pyplot()
    K, th = design["K"], design["tea"][:, 1]
    fine = np.linspace(th.min(), th.max(), 120)

    def gains(d):       # the schedule of a design.h5 on the fine grid
        return np.array([schedule_gain(d["attrs"].get("schedule_form", "polynomial"), d["schedule"]["coef"],
                                       d["schedule"]["variable"], d["K"], t) for t in fine])
    kf, ko = gains(design), None if other is None else gains(other)
    units = lin.state_units(cfg.design.drf_mode)
    fig, axs = plt.subplots(6, 4, figsize=(11, 14), sharex=True)
    for j, ax in enumerate(axs.flat):
        for i in range(3):
            ax.plot(np.degrees(th), K[:, i, j], "o", ms=3, color=COLORS[i], label=f"K({i + 1},{j + 1}) point")
            ax.plot(np.degrees(fine), kf[:, i, j], "-", color=COLORS[i], lw=1,
                    label=f"K({i + 1},{j + 1}) schedule")
            if ko is not None:
                ax.plot(np.degrees(fine), ko[:, i, j], "--", color=COLORS[i], lw=0.8,
                        label=f"K({i + 1},{j + 1}) other")
        ax.set_title(f"K(i,{j + 1}): {lin.STATE_NAMES[j]}", fontsize=8)
        ax.set_ylabel(f"ft·lbf / ({units[j]})", fontsize=6.5)
        ax.tick_params(labelsize=6.5)
        # ≤ 6 gain ticks (the default gives up to 9): each tick costs a label and a grid line (issue 16)
        ax.yaxis.set_major_locator(MaxNLocator(5, steps=[1, 2, 2.5, 5, 10]))
    for ax in axs[-1]:
        ax.set_xlabel("pitch TEA θ2* (deg)")
    handles, _ = axs[0, 0].get_legend_handles_labels()
    kinds = ("point gain", "schedule") + (() if ko is None else ("other schedule (dashed)",))
    labels = [f"{kind}, row i = {i + 1} ({AXES[i]} torque)" for i in range(3) for kind in kinds]
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=7, bbox_to_anchor=(0.5, 0.985))
    beside = "" if ko is None else f";\nother schedule: {_form_name(other)} (dashed)"
    fig.suptitle(f"Gain schedule vs TEA: the design points' gains (markers), {_form_name(design)} (lines){beside}; "
                 "rows i = roll, pitch, yaw torque", y=0.998, fontsize=9)
    # a fixed layout: tight_layout on 24 panels costs as much as drawing them (issue 16)
    fig.subplots_adjust(left=0.075, right=0.985, bottom=0.04, top=0.93, wspace=0.42, hspace=0.32)
    files = save(fig, ctx.figdir, "gain_schedule")
    ctx.doc.fig("gain_schedule", "Gain schedule: the 72 gains K(i, j) vs pitch TEA (Figs 5.3–5.26 analogue)"
                + ("" if quad is None else ", the packaged schedule and the report's quadratic form converged on "
                   "the path (dashed)"), files)


def _form_name(design: dict) -> str:
    """What the schedule of ``design`` (``design.h5`` as read) is, in words."""
    sc = design["schedule"]
    if design["attrs"].get("schedule_form", "polynomial") == "table":
        return f"the table look-up (K linear in θ2* between its {len(design['tea'])} nodes)"
    how = {"shifted_lqr": ", converged on the path"}.get(h5_text(sc.get("fit_method", b"least_squares")), "")
    return f"the order-{sc['coef'].shape[0] - 1} polynomial{how}"


def _sector(ax, sigma, half_angle_deg, xmin):
    """Shade the sector of Fig 5.2 (Re λ/n ≤ −σ, |arg| within the half-angle in deg) from ``xmin`` on."""
    t = np.tan(np.radians(half_angle_deg))
    x = np.linspace(xmin, -sigma, 50)
    ax.fill_between(x, t * x, -t * x, color="0.92", label="sector (Fig 5.2)", zorder=0)
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.6)
    ax.plot(x, t * x, "k-", lw=0.6)
    ax.plot(x, -t * x, "k-", lw=0.6)


def _pole_figure(ctx: SectionWriter, ev: np.ndarray) -> None:
    """Part: pole maps (poles / n) in the sector of Fig 5.2: the stair-case points; claim 1's MB3 designs
    with ``ev``, the :func:`_true_poles` in rad/s."""
    cfg = ctx.g.configs["staircase"]
    stair = ctx.data("acmm design:" + cfg.name)
    mb3 = ctx.data("acmm design:mb3")
    dec = ctx.data("acmm design:mb3_decoupled")
    n = cfg.orbit_rate
    sigma, phi = cfg.design.sector.sigma, cfg.design.sector.half_angle_deg
    plt = pyplot()
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.6))
    ax = axs[0]
    pts = [stair["points"][k] for k in sorted(stair["points"])]
    allp = np.concatenate([p["poles"] for p in pts]) / n
    _sector(ax, sigma, phi, min(allp.real.min() * 1.05, -2 * sigma))
    cmap = plt.get_cmap("viridis")
    th = np.degrees(stair["tea"][:, 1])
    for k, p in enumerate(pts):
        q = p["poles"] / n
        ax.plot(q.real, q.imag, "x", ms=4, color=cmap(k / max(1, len(pts) - 1)),
                label=f"θ2* = {th[k]:.1f}°" if k in (0, len(pts) - 1) else None)
    ax.set_xlabel("Re λ / n (n = orbital rate)")
    ax.set_title(f"Stair-case schedule: {len(pts)} design points")
    ax = axs[1]
    pc = mb3["points"][sorted(mb3["points"])[0]]["poles"] / n
    pd = dec["points"][sorted(dec["points"])[0]]["poles"] / n
    pt = np.asarray(ev) / n
    xmin = min(pc.real.min(), pd.real.min(), -2 * sigma) * 1.05
    _sector(ax, sigma, phi, xmin)
    ax.plot(pc.real, pc.imag, "x", color=COLORS[0], label="coupled design, coupled model")
    ax.plot(pd.real, pd.imag, "+", color=COLORS[2], label="no-cross-inertia design, its own model")
    ax.plot(pt.real, pt.imag, "o", mfc="none", color=COLORS[1], label="no-cross-inertia gain, true coupled model")
    ax.set_xlabel("Re λ / n")
    ax.set_title("Claim 1 (MB3): closed-loop poles")
    for ax in axs:
        ax.axvline(0, color="k", lw=0.5)
        ax.set_ylabel("Im λ / n")
        ax.legend(loc="upper left")
    fixed_layout(fig, left=0.72, bottom=0.54, top=0.34, wspace=0.16)
    ctx.doc.fig("pole_maps", "Closed-loop poles (units of n) and the sector of Fig 5.2: every stair-case "
                "design point (left); the claim-1 designs and the cross-inertia-free gain on the true "
                "coupled MB3 model (right)", save(fig, ctx.figdir, "pole_maps"))


def _conditioning(ctx: SectionWriter, d, pts):
    """Per-point conditioning and robustness; the scheduled gain along the whole path (tables)."""
    if "max_eig_condition" in pts[0]:
        lmi = all("lmi" in p for p in pts)
        rows = [[h5_text(name), f"{np.degrees(float(p['tea'][1])):.2f}",
                 f"{float(p['sector_margin']):+.3f}", f"{float(p['max_eig_condition']):.2e}",
                 f"{float(p['robustness_radius']):.1e}", f"{float(p['robustness_radius_elementwise']):.1e}"]
                + ([f"{float(p['lmi']['random_radius']):.1e}"] if lmi else [])
                + [f"{float(p['riccati_condition']):.1e}"]
                for name, p in zip(d["names"], pts)]
        ctx.doc.table(["point", "θ2* (deg)", "sector margin (n)", "max eigenvalue condition (scaled)",
                       "sector robustness radius ‖δK‖/‖K‖", "radius, elementwise"]
                      + (["radius, random re-check"] if lmi else [])
                      + ["CARE condition" + (" (pre-conditioning LQR)" if lmi else "")],
                       rows, "Design points: conditioning of the closed loop and the estimated smallest "
                             "relative gain error that moves a pole out of the sector (first order)")
    sc = d["schedule"]
    if "path" not in sc:
        return
    pa = sc["path"]
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    ctx.doc.table(["quantity along the path", "value"], [
        ["TEAs checked (evenly spaced, first to last design point)", f"{mr.size}"],
        ["largest Re λ of the scheduled local loop (units of n)", f"{mr.max():+.3f}"],
        ["worst sector margin (units of n)", f"{mg.min():+.3f}"],
        ["fraction of the path with every pole in the sector", f"{float(np.mean(mg >= 0)):.3f}"],
        ["smallest disk margin α at the plant input (skew 0)", f"{dm.min():.3f}"],
    ], f"The {'table look-up' if d['attrs'].get('schedule_form') == 'table' else 'order-2'} schedule "
       "judged on the closed loop at every path TEA")


def _path_figures(ctx: SectionWriter) -> None:
    """Part: the scheduled gain along the path, margins and poles in the sector of Fig 5.2 (figures of
    :mod:`acmm.plots`); nothing without a ``schedule/path`` group."""
    cfg = ctx.g.configs["staircase"]
    pa = ctx.data("acmm design:" + cfg.name)["schedule"].get("path")
    if pa is None:
        return
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    f1 = design_plots.schedule_path_check(pa["theta2"], mr, mg, dm, ctx.figdir / "schedule_path_margins", vector=True)
    ctx.doc.fig("schedule_path_margins", "Scheduled gain on the local model along the path: largest Re λ, "
                "worst sector margin and disk margin at the plant input vs pitch TEA",
                {"png": f1[0], "pdf": f1[1]})
    f2 = design_plots.scheduled_pole_map(pa["poles"], pa["theta2"], cfg.orbit_rate, cfg.design.sector.sigma,
                                  cfg.design.sector.half_angle_deg, ctx.figdir / "schedule_path_poles",
                                  vector=True)
    ctx.doc.fig("schedule_path_poles", "Poles of the scheduled loop at every path TEA with the sector of "
                "Fig 5.2", {"png": f2[0], "pdf": f2[1]})


#: this section's parts, rows of :data:`acmm.report.plan.PARTS`
PARTS = [
    ("schedule", "schedule", _summary, ("design:staircase",), (), 0.2),
    ("schedule/paths", "schedule", _path_figures, ("design:staircase",), (), 0.75),
    ("schedule/routes", "schedule", _routes,
     ("design:staircase", "design:staircase_lqr", "design:staircase_quadratic", "simulate:staircase",
      "simulate:staircase_lqr", "simulate:staircase_quadratic"), (), 0.1),
    ("poles", "schedule", _true_poles, ("design:mb3", "design:mb3_decoupled"), (), 0.05),
    ("schedule/gains", "schedule", _gain_figure, ("design:staircase", "design:staircase_quadratic"), (), 1.8),
    ("schedule/poles", "schedule", _pole_figure, ("design:staircase", "design:mb3", "design:mb3_decoupled"),
     ("poles",), 0.3),
]
