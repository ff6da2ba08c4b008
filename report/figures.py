"""Every figure of the report (vector PDF + PNG, :mod:`report.figure_style`): the schedules and
pole maps of ch. 5, the simulations of ch. 6, the robustness claim of ch. 7 and the QPP examples of
ch. 13–14."""
from __future__ import annotations

from pathlib import Path

import numpy as np



AXES = ("roll", "pitch", "yaw")


def fig_gain_schedule(design: dict, drf_mode: str, figdir: Path):
    """K(i, j) vs pitch TEA for the 24 columns: LQR gains (markers) and the schedule (lines).

    Parameters
    ----------
    design : dict
        ``design.h5`` as read by :func:`common.results.read_h5` (K in ft·lbf per state unit,
        tea in rad, the ``schedule`` group).
    drf_mode : str
        DRF mode of the 24 states (their units).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    from acmm.linearize import STATE_NAMES, state_units
    from report.figure_style import COLORS, pyplot, save
    from acmm.schedule import schedule_gain

    plt = pyplot()
    K, tea = design["K"], design["tea"]
    sc = design["schedule"]
    form = design["attrs"].get("schedule_form", "polynomial")
    th = tea[:, 1]
    fine = np.linspace(th.min(), th.max(), 120)
    kf = np.array([schedule_gain(form, sc["coef"], sc["variable"], K, t) for t in fine])
    units = state_units(drf_mode)
    fig, axs = plt.subplots(6, 4, figsize=(11, 14), sharex=True)
    for j, ax in enumerate(axs.flat):
        for i in range(3):
            ax.plot(np.degrees(th), K[:, i, j], "o", ms=3, color=COLORS[i], label=f"K({i + 1},{j + 1}) LQR")
            ax.plot(np.degrees(fine), kf[:, i, j], "-", color=COLORS[i], lw=1,
                    label=f"K({i + 1},{j + 1}) schedule")
        ax.set_title(f"K(i,{j + 1}): {STATE_NAMES[j]}", fontsize=8)
        ax.set_ylabel(f"ft·lbf / ({units[j]})", fontsize=6.5)
        ax.tick_params(labelsize=6.5)
    for ax in axs[-1]:
        ax.set_xlabel("pitch TEA θ2* (deg)")
    handles, _ = axs[0, 0].get_legend_handles_labels()
    labels = [f"{kind}, row i = {i + 1} ({AXES[i]} torque)" for i in range(3) for kind in ("LQR gain", "schedule")]
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=7, bbox_to_anchor=(0.5, 0.985))
    fig.suptitle(f"Gain schedule vs TEA: LQR gains (markers) and the order-{sc['coef'].shape[0] - 1} "
                 f"{form} schedule (lines); rows i = roll, pitch, yaw torque", y=0.995, fontsize=9)
    # a fixed layout: tight_layout on 24 panels costs as much as drawing them (issue 16)
    fig.subplots_adjust(left=0.075, right=0.985, bottom=0.04, top=0.93, wspace=0.42, hspace=0.32)
    return save(fig, figdir, "gain_schedule")


def _sector(ax, sigma, half_angle_deg, xmin):
    t = np.tan(np.radians(half_angle_deg))
    x = np.linspace(xmin, -sigma, 50)
    ax.fill_between(x, t * x, -t * x, color="0.92", label="sector (Fig 5.2)", zorder=0)
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.6)
    ax.plot(x, t * x, "k-", lw=0.6)
    ax.plot(x, -t * x, "k-", lw=0.6)


def fig_pole_maps(stair: dict, mb3: dict, dec: dict, dec_true_poles, n, sector, figdir: Path):
    """Closed-loop poles / n: the stair-case schedule points, and the claim-1 designs.

    Parameters
    ----------
    stair : dict
        The stair-case ``design.h5`` (poles in rad/s, tea in rad).
    mb3 : dict
        The MB3 ``design.h5``.
    dec : dict
        The cross-inertia-free MB3 ``design.h5``.
    dec_true_poles : (24,) complex array
        Its gain's poles on the true coupled model, rad/s.
    n : float
        Orbit rate, rad/s.
    sector : tuple of float
        (σ in units of n, half-angle in deg).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    from report.figure_style import COLORS, pyplot, save

    plt = pyplot()
    sigma, phi = sector
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
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re λ / n (n = orbital rate)")
    ax.set_ylabel("Im λ / n")
    ax.set_title(f"Stair-case schedule: {len(pts)} design points")
    ax.legend(loc="upper left")
    ax = axs[1]
    pc = mb3["points"][sorted(mb3["points"])[0]]["poles"] / n
    pd = dec["points"][sorted(dec["points"])[0]]["poles"] / n
    pt = np.asarray(dec_true_poles) / n
    xmin = min(pc.real.min(), pd.real.min(), -2 * sigma) * 1.05
    _sector(ax, sigma, phi, xmin)
    ax.plot(pc.real, pc.imag, "x", color=COLORS[0], label="coupled design, coupled model")
    ax.plot(pd.real, pd.imag, "+", color=COLORS[2], label="no-cross-inertia design, its own model")
    ax.plot(pt.real, pt.imag, "o", mfc="none", color=COLORS[1], label="no-cross-inertia gain, true coupled model")
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re λ / n")
    ax.set_ylabel("Im λ / n")
    ax.set_title("Claim 1 (MB3): closed-loop poles")
    ax.legend(loc="upper left")
    fig.tight_layout()
    return save(fig, figdir, "pole_maps")


def fig_claim1(mb3: dict, dec: dict, figdir: Path):
    """Attitude error, torque and momentum per axis: coupled vs cross-inertia-free (Figs 6.2–6.13).

    Parameters
    ----------
    mb3 : dict
        ``sim.h5`` of the coupled design (orbits, attitude error in rad, u in ft·lbf, h in
        ft·lbf·s).
    dec : dict
        ``sim.h5`` of the cross-inertia-free design (same units).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    from report.figure_style import COLORS, pyplot, save

    plt = pyplot()
    fig, axs = plt.subplots(4, 3, figsize=(11, 10))
    for a in range(3):
        for d, lab, c, ls in ((mb3, "coupled design", COLORS[0], "-"),
                              (dec, "no-cross-inertia design", COLORS[1], "--")):
            o = d["orbits"]
            axs[0, a].plot(o, np.degrees(d["attitude_error"][:, a]), ls, color=c, label=lab)
            early = o <= 0.1
            axs[1, a].plot(o[early], np.degrees(d["attitude_error"][early, a]), ls, color=c, label=lab)
            axs[2, a].plot(o, d["u"][:, a], ls, color=c, label=lab)
            axs[3, a].plot(o, d["h"][:, a], ls, color=c, label=lab)
        axs[0, a].set_title(AXES[a])
        for r in range(4):
            axs[r, a].set_xlabel("time (orbits)")
    axs[0, 0].set_ylabel("attitude error θ − θ* (deg)")
    axs[1, 0].set_ylabel("attitude error, first 0.1 orbit (deg)")
    axs[2, 0].set_ylabel("control torque (ft·lbf)")
    axs[3, 0].set_ylabel("CMG momentum (ft·lbf·s)")
    axs[0, 0].legend()
    fig.suptitle("Claim 1, MB3: fully coupled vs cross-inertia-free design on the nonlinear model", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, "claim1_responses")


def fig_staircase(sim: dict, figdir: Path):
    """Inertia steps (Figs 6.14–6.19) and the responses (Figs 6.20–6.30).

    Parameters
    ----------
    sim : dict
        The stair-case ``sim.h5`` (t in s, orbits, attitude error in rad, rates in rad/s, u in
        ft·lbf, h in ft·lbf·s, the ``levels`` group).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    tuple of dict
        The inertia, response and per-level figures, each ``{"pdf": path, "png": path}``.
    """
    from report.figure_style import COLORS, pyplot, save

    plt = pyplot()
    o = sim["orbits"]
    inertia = sim["levels"]["inertia"][sim["level"]]
    fig1, axs = plt.subplots(2, 3, figsize=(11, 5.5), sharex=True)
    for ax, (i, j) in zip(axs.flat, [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
        ax.step(o, inertia[:, i, j] / 1e6, where="post", color=COLORS[0], label=f"I({i + 1},{j + 1})")
        ax.set_ylabel(f"I({i + 1},{j + 1}) (10⁶ slug·ft²)")
        ax.legend(loc="best")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig1.suptitle("Inertia variation MB3 → AC (Figs 6.14–6.19 analogue)", fontsize=10)
    fig1.tight_layout()
    f1 = save(fig1, figdir, "staircase_inertia")
    fig2, axs = plt.subplots(4, 3, figsize=(11, 10), sharex=True)
    rows = [(np.degrees(sim["attitude_error"]), "attitude error θ − θ̂* (deg)"),
            (np.degrees(sim["rate_rel_lvlh"]), "body rate rel. LVLH (deg/s)"),   # stored in rad/s
            (sim["u"], "control torque (ft·lbf)"), (sim["h"], "CMG momentum (ft·lbf·s)")]
    for r, (data, label) in enumerate(rows):
        for a in range(3):
            axs[r, a].plot(o, data[:, a], color=COLORS[a], lw=0.6, label=AXES[a])
            if r == 0:
                axs[r, a].set_title(AXES[a])
            if a == 0:
                axs[r, a].set_ylabel(label)
            for s in sim["levels"]["start"][1:] * sim["orbits"][-1] / max(sim["t"][-1], 1e-300):
                axs[r, a].axvline(s, color="0.7", lw=0.4, ls=":")
        axs[r, 0].legend(loc="upper right")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig2.suptitle("Gain-scheduled responses, inertia MB3 → AC (Figs 6.20–6.30 analogue; dotted: level changes)",
                  fontsize=10)
    fig2.subplots_adjust(left=0.08, right=0.985, bottom=0.055, top=0.94, wspace=0.28, hspace=0.12)  # issue 16
    f2 = save(fig2, figdir, "staircase_responses")
    fig3, axs = plt.subplots(1, 2, figsize=(11, 3.8))
    th = np.degrees(sim["levels"]["tea_estimate"][:, 1])[: len(sim["levels"]["steady_error"])]
    for a in range(3):
        axs[0].plot(th, np.degrees(sim["levels"]["steady_error"][:, a]), "o-", color=COLORS[a], label=AXES[a])
    axs[0].set_xlabel("pitch TEA of the level θ2* (deg)")
    axs[0].set_ylabel("steady |θ − θ̂*| (deg)")
    axs[0].set_title("Steady attitude error per level (second half of each dwell)")
    axs[0].legend()
    axs[1].plot(th, sim["levels"]["peak_momentum"], "s-", color=COLORS[3], label="peak |h_i| over the level")
    axs[1].set_xlabel("pitch TEA of the level θ2* (deg)")
    axs[1].set_ylabel("peak CMG momentum (ft·lbf·s)")
    axs[1].set_title("Peak momentum per level")
    axs[1].legend()
    fig3.tight_layout()
    f3 = save(fig3, figdir, "staircase_levels")
    return f1, f2, f3


def fig_robustness(params: dict, base, verdict, peak, names, figdir: Path):
    """Peak attitude error (deg) vs max_k |δ_k| per Monte Carlo case, one panel per base.

    Parameters
    ----------
    params : dict
        Swept parameter → (N,) array (relative inertia changes ``dI11`` … ``dI23``,
        dimensionless).
    base : (N,) int array
        Base index of each case.
    verdict : (N,) str array
        Verdict of each case.
    peak : (N, 3) array
        Peak attitude error per axis, deg.
    names : list of str
        Base names.
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    from report.figure_style import COLORS, pyplot, save

    plt = pyplot()
    keys = [k for k in ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23") if k in params]
    dmax = np.max(np.abs(np.column_stack([params[k] for k in keys])), axis=1) if keys else np.zeros(len(base))
    fig, axs = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.0), squeeze=False)
    for k, lab in enumerate(names):
        ax = axs[0, k]
        sel = base == k
        ok = sel & (verdict == "bounded")
        bad = sel & (verdict != "bounded")
        pk = np.full(len(base), np.nan)
        finite = np.isfinite(peak).any(axis=1)
        pk[finite] = np.nanmax(peak[finite], axis=1)
        ax.plot(100 * dmax[ok], pk[ok], "o", ms=3.5, color=COLORS[0], label="bounded")
        top = np.nanmax(pk[ok]) * 1.5 if ok.any() and np.isfinite(pk[ok]).any() else 60.0
        yb = np.where(np.isfinite(pk[bad]), pk[bad], top)
        ax.plot(100 * dmax[bad], np.minimum(yb, top), "x", ms=4, color=COLORS[1],
                label="diverged / no equilibrium (clipped)")
        ax.set_yscale("log")
        ax.set_xlabel("largest inertia-element perturbation max|δ| (%)")
        ax.set_ylabel("peak attitude error, worst axis (deg)")
        ax.set_title(f"{lab.upper()}: {int(ok.sum())}/{int(sel.sum())} bounded")
        ax.legend(loc="lower right")
    fig.tight_layout()
    return save(fig, figdir, "robustness")


def fig_qpp(sim_path: Path, design: dict, beta_o: float, name: str, figdir: Path, out_labels):
    """Per scenario: y and y_o; |y − y_o| against β_o (Figs 13.3–13.9, 14.4).

    Parameters
    ----------
    sim_path : pathlib.Path
        ``qpp_sim.h5`` (one group per scenario; t in s, outputs in the plant's units).
    design : dict
        ``qpp_design.h5`` as read by :func:`common.results.read_h5` (not used for drawing).
    beta_o : float
        Radius β_o of the output sphere, in the output units.
    name : str
        Config name (file stem prefix).
    figdir : pathlib.Path
        Folder of the figures.
    out_labels : list of str
        Label of each output.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    import h5py

    from report.figure_style import COLORS, pyplot, save

    plt = pyplot()
    with h5py.File(sim_path, "r") as f:
        scen = [k for k in f.keys() if isinstance(f[k], h5py.Group)]
        data = {k: {d: f[k][d][()].T for d in ("t", "y", "y_o", "r", "u")} for k in scen}   # stored (t, channel)
    p = next(iter(data.values()))["y"].shape[0]
    fig, axs = plt.subplots(2, len(scen), figsize=(3.8 * len(scen) + 1, 6.5), squeeze=False)
    for c, k in enumerate(scen):
        d = data[k]
        for i in range(p):
            axs[0, c].plot(d["t"], d["y"][i], "-", color=COLORS[i], label=f"y{i + 1} ({out_labels[i]})")
            axs[0, c].plot(d["t"], d["y_o"][i], "--", color=COLORS[i], lw=0.8, label=f"y_o{i + 1} nominal")
            axs[1, c].plot(d["t"], np.abs(d["y"][i] - d["y_o"][i]), color=COLORS[i],
                           label=f"|y{i + 1} − y_o{i + 1}| ({out_labels[i]})")
        axs[1, c].axhline(beta_o, color="k", ls=":", lw=0.8, label=f"β_o = {beta_o:g}")
        axs[1, c].set_yscale("log")
        axs[1, c].set_ylim(beta_o * 1e-5, beta_o * 3)
        axs[0, c].set_title(f"scenario {k}")
        axs[0, c].set_ylabel("output")
        axs[1, c].set_ylabel("tracking error |y − y_o|")
        for r in range(2):
            axs[r, c].set_xlabel("time t (s)")
        axs[0, c].legend(fontsize=6.5)
        axs[1, c].legend(fontsize=6.5, loc="lower right")
    fig.suptitle(f"{name}: nonlinear closed loop, output vs nominal output and the output sphere", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, f"{name}_responses")


def fig_circle(design: dict, name: str, figdir: Path):
    """Circle criterion (lemma 1): h_ii(−a + jω) with Gershgorin mean radii and the critical disc.

    Parameters
    ----------
    design : dict
        ``qpp_design.h5`` as read by :func:`common.results.read_h5` (its ``circle`` group and
        ``sector``; h_ii dimensionless).
    name : str
        Config name (file stem prefix).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`report.figure_style.save`).
    """
    from report.figure_style import COLORS, pyplot, save
    from qpp.circle import critical_disc

    plt = pyplot()
    c = design["circle"]
    centres, radii, sector = np.atleast_2d(c["centres"]), np.atleast_2d(c["radii"]), design["sector"]
    m = centres.shape[0]
    fig, axs = plt.subplots(1, m, figsize=(4.6 * m, 4.4), squeeze=False)
    for i in range(m):
        ax = axs[0, i]
        h = centres[i]
        for k in np.unique(np.linspace(0, h.size - 1, 150).astype(int)):
            ax.add_patch(plt.Circle((h[k].real, h[k].imag), radii[i, k], fill=False, lw=0.3, color="0.7"))
        ax.plot(h.real, h.imag, color=COLORS[0], label="h_ii(−a + jω), ω ≥ 0")
        ax.plot(h.real, -h.imag, "--", color=COLORS[0], lw=0.7, label="ω ≤ 0")
        al, be = sector[i]
        cc, R = critical_disc(al, be)
        ax.add_patch(plt.Circle((cc, 0), R, fill=False, color=COLORS[1], lw=1.4))
        ax.plot([], [], color=COLORS[1], label=f"critical disc D({al:g}, {be:g})")
        lim = 1.1 * max(abs(cc) + R, np.abs(h).max() + radii[i].max())
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("Re h_ii (dimensionless)")
        ax.set_ylabel("Im h_ii")
        ax.set_title(f"channel {i + 1}: margin {np.atleast_1d(c['margins'])[i]:.3g}")
        ax.legend(fontsize=6.5, loc="upper right")
    fig.suptitle(f"{name}: circle criterion (Figs 13.1, 14.2–14.3 analogue)", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, f"{name}_circle")


# =============================================================================================
