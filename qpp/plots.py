"""Figures of ``qpp design`` (Figs 13.1, 14.2–14.3) and ``qpp simulate`` (Figs 13.2–13.10, 14.4–14.6).

The examples of ch. 13 (SISO) and ch. 14 (two-link polar arm); the circle criterion of ch. 12.1.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from acmm_qpp.plot_style import agg_pyplot as _plt
from acmm_qpp.results import save_figure
from qpp.design.circle import critical_disc


def _save(plt, fig, path: Path) -> Path:
    """Write every qpp figure the same way (110 dpi, tight box) and close it; returns ``path``."""
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_circle(res, path: Path) -> list[Path]:
    """Gershgorin mean band of H(−a + jω) against the critical disc, one figure per channel.

    Parameters
    ----------
    res : qpp.design.certificate.DesignResult
        A design; its ``circle`` (:class:`qpp.design.circle.CircleResult`) is drawn.
    path : pathlib.Path
        Figure path; channel i is written to ``<stem>_ch<i>.png`` beside it.

    Returns
    -------
    list of pathlib.Path
        The figures written, one per channel.
    """
    from matplotlib.collections import EllipseCollection  # deferred: matplotlib start-up

    plt = _plt()
    c = res.circle
    out = []
    for i in range(c.centres.shape[0]):
        fig, ax = plt.subplots(figsize=(5.5, 5))
        h = c.centres[i]
        idx = np.unique(np.linspace(0, h.size - 1, 300).astype(int))
        d = 2 * c.radii[i, idx]                  # the band's circles: one collection, not 300 patches
        ax.add_collection(EllipseCollection(d, d, np.zeros(idx.size), units="xy", facecolors="none",
                                            edgecolors="0.6", linewidths=0.3,
                                            offsets=np.column_stack([h[idx].real, h[idx].imag]),
                                            offset_transform=ax.transData))
        ax.plot(h.real, h.imag, "b-", lw=1.2, label="h_ii(−a+jω), ω ≥ 0")
        ax.plot(h.real, -h.imag, "b--", lw=0.8, label="ω ≤ 0")
        al, be = c.alpha[i], c.beta[i]
        if al != 0 and be != 0:
            cc, R = critical_disc(al, be)
            ax.add_patch(plt.Circle((cc, 0), R, fill=False, color="r", lw=1.5, label=f"critical disc D({al:g}, {be:g})"))
            lim = 1.1 * max(abs(cc) + R, np.abs(h).max() + c.radii[i].max())
        else:
            lim = 1.1 * (np.abs(h).max() + c.radii[i].max() + 1)
        ax.set(xlim=(-lim, lim), ylim=(-lim, lim), aspect="equal", xlabel="Re", ylabel="Im")
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(0, color="k", lw=0.5)
        form = "" if c.method == "gershgorin" else "\n(coupled φ: decided by the small-gain form, not this disc)"
        ax.set_title(f"Circle criterion, channel {i + 1}: {'pass' if c.passed else 'FAIL'} "
                     f"(margin {c.margins[i]:.3g}){form}")
        ax.legend(fontsize=7, loc="upper right")
        out.append(_save(plt, fig, path.with_name(f"{path.stem}_ch{i + 1}.png")))
    return out


#: beyond this many outputs (controls) a scenario figure's legend names line styles, not channels
MAX_LABELLED_CHANNELS = 4


def _scenario_values(sim) -> str:
    """The scenario's uncertain values for a title: the expression kind's parameters by name
    (at most four), else γ."""
    if sim.parameters:
        items = [f"{k} = {v:g}" for k, v in sim.parameters.items()]
        return ", ".join(items[:4]) + (", …" if len(items) > 4 else "")
    return f"γ = {sim.gamma:g}"


def plot_scenario(sim, path: Path) -> Path:
    """r, r_o, y, y_o; tracking error |y − y_o| against β_o; control u.

    Parameters
    ----------
    sim : qpp.simulate.closed_loop.SimResult
        One simulated scenario (time in s, signals in the plant's output and control units).
    path : pathlib.Path
        Figure path.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    plt = _plt()
    p, m = sim.y.shape[0], sim.u.shape[0]
    # constrained layout: no gap under the title; the legends beside the panels, off the data
    fig, axes = plt.subplots(3, 1, figsize=(9, 8.5), sharex=True, layout="constrained")
    many = p > MAX_LABELLED_CHANNELS        # a legend of line styles, not of every channel's four lines
    for i in range(p):
        for s, v, style, lw in (("r", sim.r, "g:", None), ("r_o", sim.r_o, "k--", 0.8), ("y", sim.y, "b-", None),
                                ("y_o", sim.y_o, "r-", 0.8)):
            label = (f"{s} (all outputs)" if i == 0 else None) if many else f"{s}{i + 1}"
            axes[0].plot(sim.t, v[i], style, lw=lw, label=label)
    worst = int(np.argmax(sim.error_per_output))
    first_other = 1 if worst == 0 else 0
    for i in range(p):
        err = np.abs(sim.y[i] - sim.y_o[i])
        if not many:
            axes[1].plot(sim.t, err, label=f"|y{i + 1} − y_o{i + 1}|")
        elif i != worst:
            axes[1].plot(sim.t, err, color="0.6", lw=0.7, label="other outputs" if i == first_other else None)
    if many:                                # the output that sets ‖y − y_o‖∞, drawn last, named
        axes[1].plot(sim.t, np.abs(sim.y[worst] - sim.y_o[worst]), "C0",
                     label=f"|y{worst + 1} − y_o{worst + 1}| (largest)")
    outside = {"fontsize": 7, "loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0}
    axes[0].legend(**outside)
    axes[0].set_ylabel("reference / output")
    axes[1].axhline(sim.beta_o, color="r", ls="--", label=f"β_o = {sim.beta_o:g}")
    axes[1].set(ylabel="tracking error",
                title=f"‖y − y_o‖∞ = {sim.error_inf:.4g} ({'within' if sim.passed else 'OUTSIDE'} the sphere)")
    axes[1].legend(**outside)
    for j in range(m):
        if m > MAX_LABELLED_CHANNELS:
            axes[2].plot(sim.t, sim.u[j], lw=0.8, label=f"u1 … u{m}" if j == 0 else None)
        else:
            axes[2].plot(sim.t, sim.u[j], label=f"u{j + 1}")
    axes[2].set(ylabel="control u", xlabel="t, s")
    axes[2].legend(**outside)
    fig.suptitle(f"scenario {sim.name} ({_scenario_values(sim)})")
    return _save(plt, fig, path)


def plot_cartesian(sims, a: float, path: Path) -> Path:
    """Load path Y_A1 = (x1 + a) sin x2, Y_A2 = (x1 + a) cos x2 (Fig 14.5).

    Parameters
    ----------
    sims : list of qpp.simulate.closed_loop.SimResult
        Simulated scenarios of the polar arm (y1 radial extension in m, y2 angle in rad); the
        first one's nominal output y_o is drawn too.
    a : float
        Arm offset a of the polar-arm nonlinearity, in the units of y1 (m).
    path : pathlib.Path
        Figure path.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.5, 6))
    s0 = sims[0]
    ax.plot((s0.y_o[0] + a) * np.sin(s0.y_o[1]), (s0.y_o[0] + a) * np.cos(s0.y_o[1]), "k--", lw=0.8,
            label="nominal y_o")
    for s in sims:
        ax.plot((s.y[0] + a) * np.sin(s.y[1]), (s.y[0] + a) * np.cos(s.y[1]), label=f"{s.name} (M = {s.gamma:g} kg)")
    ax.set(aspect="equal", xlabel="Y_A1, m", ylabel="Y_A2, m",
           title="Load path in Cartesian coordinates (cf. Fig 14.5)")
    ax.legend(fontsize=7, loc="best")
    return _save(plt, fig, path)


def plot_iterations(res, path: Path) -> Path:
    """β1 and the threshold m versus the evaluation index of procedure 12.1 (circle verdict marked).

    Parameters
    ----------
    res : qpp.design.certificate.DesignResult
        A design; its ``iterations`` records are drawn.
    path : pathlib.Path
        Figure path.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    plt = _plt()
    its = [it for it in res.iterations if np.isfinite(it.get("beta1", np.nan))]
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    if its:
        k = np.arange(1, len(its) + 1)
        b1 = np.array([it["beta1"] for it in its])
        m = np.array([it["m"] for it in its])
        circ = np.array([it["circle"] for it in its], bool)
        style = "-" if k.size > 1 else ""
        ax.plot(k, b1, "b.", ls=style, ms=9, label="β1")
        ax.plot(k, m, "r.", ls=style, ms=9, label="m (12.1)")
        if (~circ).any():             # a legend entry only for what is drawn
            ax.plot(k[~circ], b1[~circ], "kx", ms=8, label="circle criterion fails")
        cert = np.array([bool(it.get("certified")) for it in its])
        if cert.any():
            ax.plot(k[cert], b1[cert], "go", mfc="none", ms=12, label="certified (β1 ≤ m, circle passes)")
        ax.set_xticks(k if k.size <= 30 else k[:: max(1, k.size // 15)])
        if k.size <= 3:               # a few evaluations: room around them, not two dots at the edges
            ax.set_xlim(0.5, k.size + 0.5)
    verdict = "certified" if res.certified else "NO certified design"
    ax.set(xlabel="evaluation of procedure 12.1", ylabel="β1, m",
           title=f"{verdict}: β1 = {res.beta1_ref:.4g}, m = {res.m_ref:.4g}")
    ax.legend(fontsize=8)
    return _save(plt, fig, path)
