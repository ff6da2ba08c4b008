"""The QPP figures of the report (ch. 13–14): nonlinear closed-loop responses against the output
sphere (Figs 13.3–13.9, 14.4) and the circle criterion (Figs 13.1, 14.2–14.3).  Split from
:mod:`acmm.report.figures`."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import h5py
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from qpp.design.circle import critical_disc
from matplotlib.ticker import NullLocator
from matplotlib.collections import PatchCollection


def fig_qpp(sim_path: Path, design: dict, beta_o: float, name: str, figdir: Path, out_labels):
    """Per scenario: y and y_o; |y − y_o| against β_o (Figs 13.3–13.9, 14.4).

    Parameters
    ----------
    sim_path : pathlib.Path
        ``qpp_sim.h5`` (one group per scenario; t in s, outputs in the plant's units).
    design : dict
        ``qpp_design.h5`` as read by :func:`acmm_qpp.results.read_h5` (not used for drawing).
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
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
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
        # decades only: ~45 unlabelled minor ticks per axis cost a sixth of the figure (issue 16)
        axs[1, c].yaxis.set_minor_locator(NullLocator())
        axs[1, c].set_ylim(beta_o * 1e-5, beta_o * 3)
        axs[0, c].set_title(f"scenario {k}")
        axs[0, c].set_ylabel("output")
        axs[1, c].set_ylabel("tracking error |y − y_o|")
        for r in range(2):
            axs[r, c].set_xlabel("time t (s)")
        axs[0, c].legend(fontsize=6.5)
        axs[1, c].legend(fontsize=6.5, loc="lower right")
    fig.suptitle(f"{name}: nonlinear closed loop, output vs nominal output and the output sphere", fontsize=10)
    fixed_layout(fig, left=0.74, bottom=0.54, top=0.6, wspace=0.22, hspace=0.23)
    return save(fig, figdir, f"{name}_responses")


def fig_circle(design: dict, name: str, figdir: Path):
    """Circle criterion (lemma 1): h_ii(−a + jω) with Gershgorin mean radii and the critical disc
    (Figs 13.1, 14.2–14.3).

    Parameters
    ----------
    design : dict
        ``qpp_design.h5`` as read by :func:`acmm_qpp.results.read_h5`: the ``circle`` group (centres
        h_ii and Gershgorin radii, complex/float arrays of shape (channels, frequencies),
        dimensionless; margins per channel) and ``sector`` (α_i, β_i) per channel, dimensionless.
    name : str
        Config name (file stem prefix).
    figdir : pathlib.Path
        Folder of the figures.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}`` (:func:`acmm.report.figure_style.save`).
    """
    plt = pyplot()
    c = design["circle"]
    centres, radii, sector = np.atleast_2d(c["centres"]), np.atleast_2d(c["radii"]), design["sector"]
    m = centres.shape[0]
    fig, axs = plt.subplots(1, m, figsize=(4.6 * m, 4.4), squeeze=False)
    for i in range(m):
        ax = axs[0, i]
        h = centres[i]
        # the Gershgorin circles as one collection (one artist instead of 150, issue 16)
        ax.add_collection(PatchCollection([plt.Circle((h[k].real, h[k].imag), radii[i, k]) for k in
                                           np.unique(np.linspace(0, h.size - 1, 150).astype(int))],
                                          facecolor="none", edgecolor="0.7", linewidths=0.3))
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
    fixed_layout(fig, left=0.72, bottom=0.5, top=0.6, wspace=0.2)
    return save(fig, figdir, f"{name}_circle")
