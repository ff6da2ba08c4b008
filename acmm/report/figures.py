"""Every figure of the report (vector PDF + PNG, :mod:`acmm.report.figure_style`): the schedules and
pole maps of ch. 5, the simulations of ch. 6, the robustness claim of ch. 7 and the QPP examples of
ch. 13–14."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from acmm.report.constants import AXES
from acmm.model.linearize import STATE_NAMES, state_units
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from acmm.report.numbers import decoded
from acmm.design.schedule import schedule_gain
from matplotlib.ticker import MaxNLocator


def fig_gain_schedule(design: dict, drf_mode: str, figdir: Path, other: dict | None = None):
    """K(i, j) vs pitch TEA for the 24 columns: the design points' gains (markers) and the
    schedule (lines), and another schedule of the same path (dashed), e.g. the quadratic beside
    the table.

    Parameters
    ----------
    design : dict
        ``design.h5`` as read by :func:`acmm_qpp.results.read_h5` (K in ft·lbf per state unit,
        tea in rad, the ``schedule`` group).
    drf_mode : str
        DRF mode of the 24 states (their units).
    figdir : pathlib.Path
        Folder of the figures.
    other : dict, optional
        Another ``design.h5`` of the same path, its schedule drawn dashed.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
    plt = pyplot()
    K, tea = design["K"], design["tea"]
    sc = design["schedule"]
    form = design["attrs"].get("schedule_form", "polynomial")
    th = tea[:, 1]
    fine = np.linspace(th.min(), th.max(), 120)
    kf = np.array([schedule_gain(form, sc["coef"], sc["variable"], K, t) for t in fine])
    ko = None if other is None else np.array([
        schedule_gain(other["attrs"].get("schedule_form", "polynomial"), other["schedule"]["coef"],
                      other["schedule"]["variable"], other["K"], t) for t in fine])
    units = state_units(drf_mode)
    fig, axs = plt.subplots(6, 4, figsize=(11, 14), sharex=True)
    for j, ax in enumerate(axs.flat):
        for i in range(3):
            ax.plot(np.degrees(th), K[:, i, j], "o", ms=3, color=COLORS[i], label=f"K({i + 1},{j + 1}) point")
            ax.plot(np.degrees(fine), kf[:, i, j], "-", color=COLORS[i], lw=1,
                    label=f"K({i + 1},{j + 1}) schedule")
            if ko is not None:
                ax.plot(np.degrees(fine), ko[:, i, j], "--", color=COLORS[i], lw=0.8,
                        label=f"K({i + 1},{j + 1}) other")
        ax.set_title(f"K(i,{j + 1}): {STATE_NAMES[j]}", fontsize=8)
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
    return save(fig, figdir, "gain_schedule")


def _form_name(design: dict) -> str:
    """What the schedule of ``design`` (``design.h5`` as read) is, in words."""
    sc = design["schedule"]
    if design["attrs"].get("schedule_form", "polynomial") == "table":
        return f"the table look-up (K linear in θ2* between its {len(design['tea'])} nodes)"
    how = {"shifted_lqr": ", converged on the path"}.get(decoded(sc.get("fit_method", b"least_squares")), "")
    return f"the order-{sc['coef'].shape[0] - 1} polynomial{how}"


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
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
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
    fixed_layout(fig, left=0.72, bottom=0.54, top=0.34, wspace=0.16)
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
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
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
    fixed_layout(fig, left=0.8, bottom=0.54, top=0.61, wspace=0.24, hspace=0.32)
    return save(fig, figdir, "claim1_responses")


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
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
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
    fixed_layout(fig, left=0.72, bottom=0.54, top=0.33, wspace=0.2)
    return save(fig, figdir, "robustness")


# =============================================================================================
