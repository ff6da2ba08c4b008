"""Figures of the simulation stage (ch. 6): attitude error, rate, torque and CMG momentum per axis
(Figs 6.2–6.13, 6.20–6.30), the inertia steps of the stair-case (Figs 6.14–6.19) and a one-page
summary with the per-level statistics.

Each function takes arrays, draws one figure and saves it as PNG (and PDF when asked) under the
given path.  Split from :mod:`acmm.plots` (issue 12), which re-exports these names.
"""
from __future__ import annotations

import numpy as np

from acmm.plot_base import (
    _BUILDERS,
    AXES,
    _few_ticks,
    _layout,
    _plt,
    _premake_ticks,
    _save,
    decimate,
)


def _axis_histories_layout(units: str):
    from common.units import pretty, shown

    plt = _plt()
    fig, axs = plt.subplots(4, 3, figsize=(13, 10), sharex=True)
    uu, hu = shown(1.0, "ft*lbf", units)[1], shown(1.0, "ft*lbf*s", units)[1]
    labels = ["attitude error θ−θ̂* (deg)", "body rate rel. LVLH (deg/s)",
              f"control torque ({pretty(uu)})", f"CMG momentum ({pretty(hu)})"]
    for r, label in enumerate(labels):
        for a in range(3):
            ax = axs[r, a]
            _few_ticks(ax, 6, 4)
            if r == 0:
                ax.set_title(AXES[a])
            ax.set_ylabel(label, fontsize=8 if a == 0 else 7)
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    # a fixed layout: tight_layout plus bbox 'tight' draw the 12 panels three times
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.06, top=0.93, wspace=0.25, hspace=0.12)
    _premake_ticks(axs.flat)
    return fig, axs


def axis_histories(orbits, err_deg, rate, u, h, title, path, vector=False, units="imperial"):
    """Angle error, rate, delivered torque and CMG momentum per axis vs orbit (Figs 6.2–6.13, 6.20–6.30).

    ``u`` (ft·lbf) and ``h`` (ft·lbf·s) are shown in the unit system ``units``.

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    err_deg : (N, 3) array
        Attitude error θ − θ̂*, deg.
    rate : (N, 3) array
        Body rate relative to LVLH, deg/s.
    u : (N, 3) array
        Delivered torque, ft·lbf.
    h : (N, 3) array
        CMG momentum, ft·lbf·s.
    title : str
        Figure title.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    from common.units import shown

    fig, axs = _layout("axis_histories", units)
    u = shown(np.asarray(u), "ft*lbf", units)[0]
    h = shown(np.asarray(h), "ft*lbf*s", units)[0]
    for r, data in enumerate((err_deg, rate, u, h)):
        for a in range(3):
            axs[r, a].plot(*decimate(orbits, data[:, a]), lw=0.7)
    fig.suptitle(title)
    return _save(fig, path, vector, tight=False)


def _inertia_layout(units: str):
    from common.units import pretty, shown

    iu = shown(1.0, "slug*ft^2", units)[1]
    plt = _plt()
    fig, axs = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    for ax, (i, j) in zip(axs.flat, _INERTIA_ELEMENTS):
        ax.set_title(f"I({i + 1},{j + 1})")
        ax.set_ylabel(f"inertia I{i + 1}{j + 1} (10⁶ {pretty(iu)})")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig.suptitle("Inertia variation MB3 → AC (cf. Figs 6.14–6.19)")
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.09, top=0.9, wspace=0.3, hspace=0.25)
    _premake_ticks(axs.flat)
    return fig, axs


_INERTIA_ELEMENTS = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]


def inertia_histories(orbits, inertia, path, vector=False, units="imperial"):
    """The six inertia elements vs orbit (Figs 6.14–6.19), in the unit system ``units``.

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    inertia : (N, 3, 3) array
        Inertia in force, slug·ft².
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    from common.units import shown

    inertia = shown(np.asarray(inertia), "slug*ft^2", units)[0]
    fig, axs = _layout("inertia_histories", units)
    for ax, (i, j) in zip(axs.flat, _INERTIA_ELEMENTS):
        ax.step(orbits, inertia[:, i, j] / 1e6, where="post")
    return _save(fig, path, vector, tight=False)


def _summary_layout(units: str):
    from common.units import pretty, shown

    hu, uu = shown(1.0, "ft*lbf*s", units)[1], shown(1.0, "ft*lbf", units)[1]
    plt = _plt()
    fig = plt.figure(figsize=(11, 8.5))
    gs = fig.add_gridspec(3, 2)
    top = fig.add_subplot(gs[0, :])
    top.set_ylabel("attitude error (deg)")
    top.set_xlabel("time (orbits)")
    mid = []
    for col, label in enumerate((f"CMG momentum ({pretty(hu)})", f"delivered torque ({pretty(uu)})")):
        ax = fig.add_subplot(gs[1, col])
        ax.set_ylabel(label)
        ax.set_xlabel("time (orbits)")
        mid.append(ax)
    table = fig.add_subplot(gs[2, :])
    table.axis("off")
    _premake_ticks([top, *mid])
    return fig, (top, mid, table)


def summary(orbits, err_deg, h, u, level_stats, verdict, title, path, vector=False, units="imperial"):
    """One-page summary: errors, momentum, torque and per-level statistics (``units``: imperial | SI).

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    err_deg : (N, 3) array
        Attitude error, deg.
    h : (N, 3) array
        CMG momentum, ft·lbf·s.
    u : (N, 3) array
        Delivered torque, ft·lbf.
    level_stats : list of dict
        Per-level statistics (:func:`acmm.scenario.level_statistics`).
    verdict : str
        The run's verdict.
    title : str
        Figure title.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    from common.units import pretty, shown

    h, hu = shown(np.asarray(h), "ft*lbf*s", units)
    u = shown(np.asarray(u), "ft*lbf", units)[0]
    k_h = shown(1.0, "ft*lbf*s", units)[0]
    fig, (ax, mid, tab_ax) = _layout("summary", units)
    for a in range(3):
        ax.plot(*decimate(orbits, err_deg[:, a]), lw=0.7, label=AXES[a])
    ax.legend(fontsize=7)
    ax.set_title(f"{title} — verdict: {verdict}")
    for ax, data in zip(mid, (h, u)):
        for a in range(3):
            ax.plot(*decimate(orbits, data[:, a]), lw=0.7, label=AXES[a])
        ax.legend(fontsize=7)
    if level_stats:
        header = ["level", "start (orbit)", "θ2* est (deg)", "steady |err| max (deg) r/p/y", f"peak |h| ({pretty(hu)})"]
        rows = [[str(s["level"]), f"{s['start_orbit']:.1f}", f"{s['theta2_deg']:.2f}",
                 " / ".join(f"{v:.3f}" for v in s["steady_error_deg"]), f"{s['peak_momentum'] * k_h:.0f}"]
                for s in level_stats]
        tab = tab_ax.table(cellText=rows, colLabels=header, loc="center", cellLoc="center")
        tab.auto_set_font_size(False)
        tab.set_fontsize(7)
    # after the table: its cells are sized on the axes as placed by the default parameters
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.02, top=0.95, wspace=0.25, hspace=0.35)
    return _save(fig, path, vector, tight=False)


_BUILDERS.update({"axis_histories": _axis_histories_layout, "inertia_histories": _inertia_layout,
                  "summary": _summary_layout})
