"""The stair-case figures of the report (ch. 6, Figs 6.14–6.30): inertia steps MB3 → AC, the
gain-scheduled responses and the per-level statistics."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from acmm.report.constants import AXES
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from matplotlib.collections import LineCollection


def fig_staircase_inertia(sim: dict, figdir: Path):
    """Inertia elements vs time (Figs 6.14–6.19).

    Parameters
    ----------
    sim : dict
        ``sim.h5`` of the stair-case run as read by :func:`acmm_qpp.results.read_h5` (orbits, t in s,
        ``level`` index per sample, ``levels/inertia`` of shape (levels, 3, 3) in slug·ft²).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
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
    fixed_layout(fig1, left=0.72, bottom=0.54, top=0.44, wspace=0.27, hspace=0.09)
    return save(fig1, figdir, "staircase_inertia")


def fig_staircase_responses(sim: dict, figdir: Path):
    """Attitude error, rate, torque and momentum per axis (Figs 6.20–6.30).

    Parameters
    ----------
    sim : dict
        ``sim.h5`` of the stair-case run as read by :func:`acmm_qpp.results.read_h5` (orbits, t in s,
        attitude_error in rad, rate_rel_lvlh in rad/s, u in ft·lbf, h in ft·lbf·s, each of shape
        (samples, 3); ``levels/start`` in s).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
    plt = pyplot()
    o = sim["orbits"]
    fig2, axs = plt.subplots(4, 3, figsize=(11, 10), sharex=True)
    rows = [(np.degrees(sim["attitude_error"]), "attitude error θ − θ̂* (deg)"),
            (np.degrees(sim["rate_rel_lvlh"]), "body rate rel. LVLH (deg/s)"),   # stored in rad/s
            (sim["u"], "control torque (ft·lbf)"), (sim["h"], "CMG momentum (ft·lbf·s)")]
    changes = sim["levels"]["start"][1:] * sim["orbits"][-1] / max(sim["t"][-1], 1e-300)   # orbits
    for r, (data, label) in enumerate(rows):
        for a in range(3):
            axs[r, a].plot(o, data[:, a], color=COLORS[a], lw=0.6, label=AXES[a])
            if r == 0:
                axs[r, a].set_title(AXES[a])
            if a == 0:
                axs[r, a].set_ylabel(label)
            # the level changes as one collection per panel, full height, not 11 axvline artists (issue 16)
            axs[r, a].add_collection(LineCollection([[(s, 0.0), (s, 1.0)] for s in changes], colors="0.7",
                                                    linewidths=0.4, linestyles=":",
                                                    transform=axs[r, a].get_xaxis_transform()), autolim=False)
        axs[r, 0].legend(loc="upper right")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig2.suptitle("Gain-scheduled responses, inertia MB3 → AC (Figs 6.20–6.30 analogue; dotted: level changes)",
                  fontsize=10)
    fig2.subplots_adjust(left=0.08, right=0.985, bottom=0.055, top=0.94, wspace=0.28, hspace=0.12)  # issue 16
    return save(fig2, figdir, "staircase_responses")


def fig_staircase_levels(sim: dict, figdir: Path):
    """Steady attitude error and peak momentum per inertia level (the stair-case run of ch. 6).

    Parameters
    ----------
    sim : dict
        ``sim.h5`` of the stair-case run as read by :func:`acmm_qpp.results.read_h5` (orbits, t in s,
        ``levels/tea_estimate`` in rad, ``levels/steady_error`` in rad of shape (levels, 3),
        ``levels/peak_momentum`` in ft·lbf·s).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
    plt = pyplot()
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
    fixed_layout(fig3, left=0.62, bottom=0.54, top=0.33, wspace=0.16)
    return save(fig3, figdir, "staircase_levels")
