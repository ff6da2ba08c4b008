"""Section claim 1: MB3 coupled vs cross-inertia-free design (Figs 6.2–6.13, ch. 6)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm.report.context import SectionWriter
from acmm.report.numbers import fmt_value
from acmm.report.constants import AXES
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save


@dataclass(frozen=True)
class Claim1Numbers:
    """What the errata table quotes from claim 1.

    Attributes
    ----------
    div : float
        Time at which the cross-inertia-free design diverged, orbits.
    maxre : float
        Largest Re λ of its gain on the true coupled model, dimensionless (units of n).
    first : (3,) array
        Peak |attitude error| in the first orbit, coupled design, deg.
    late : (3,) array
        Peak |attitude error| from orbit 2 on, coupled design, deg (NaN when shorter).
    """

    div: float          #: orbit at which the cross-inertia-free design diverged
    maxre: float        #: largest Re λ of its gain on the true coupled model (units of n)
    first: np.ndarray   #: peak |error| in the first orbit, coupled design (deg)
    late: np.ndarray    #: peak |error| from orbit 2 on (deg)


def peak_errors(sim: dict) -> tuple[np.ndarray, np.ndarray]:
    """Peak |attitude error| of a simulation in its first orbit and from orbit 2 on: the numbers
    claim 1 and the README's claims table show of the coupled design.

    Parameters
    ----------
    sim : dict
        Its ``sim.h5`` as read by :func:`acmm_qpp.results.read_h5` (attitude error in rad).

    Returns
    -------
    tuple of (3,) arrays
        Roll, pitch, yaw, deg: the first orbit's, and from orbit 2 on (NaN for a shorter run).
    """
    o, err = sim["orbits"], np.degrees(np.abs(sim["attitude_error"]))
    late = err[o >= 2.0].max(axis=0) if (o >= 2.0).any() else np.full(3, np.nan)
    return err[o <= 1.0].max(axis=0), late


def _build(ctx: SectionWriter, dec_true_poles: np.ndarray) -> Claim1Numbers:
    """Part: claim 1 on the nonlinear MB3 model; ``dec_true_poles``: the schedule section's poles of the
    cross-inertia-free gain on the coupled model, rad/s; returns the :class:`Claim1Numbers`."""
    ctx.section("claim1")
    n = ctx.g.configs["mb3"].orbit_rate
    s_c, s_d = ctx.data("acmm simulate:mb3"), ctx.data("acmm simulate:mb3_decoupled")
    rows = []
    for lab, s, dkey in (("coupled (eq 4.46)", s_c, "mb3"), ("no cross-inertia (I12=I13=I23=0)", s_d,
                                                               "mb3_decoupled")):
        a = s["attrs"]
        dz = ctx.data(f"acmm design:{dkey}")
        p = dz["points"][sorted(dz["points"])[0]]
        rows.append([lab, f"{float(p['sector_margin']):+.3f}", f"{float(p['riccati_residual']):.1e}",
                     f"{float(p['riccati_backward_error']):.1e}" if "riccati_backward_error" in p else "—",
                     a["verdict"].upper(), f"{float(a['stop_time_orbits']):.3f}",
                     f"{np.degrees(np.abs(s['attitude_error'])).max():.2f}"])
    ctx.doc.table(["design model", "sector margin (n)", "Riccati residual", "Riccati backward error", "nonlinear verdict",
                   "stopped at (orbit)", "peak |θ − θ*| (deg)"], rows,
                   "Claim 1 on the nonlinear MB3 model (same TEA, initial condition and disturbances)")
    first, late = peak_errors(s_c)
    div = float(s_d["attrs"]["stop_time_orbits"])
    numbers = Claim1Numbers(div, dec_true_poles.real.max() / n, first, late)
    ctx.doc.ul([
        f"Cross-inertia-free design: {s_d['attrs']['verdict']} at {div:.3f} orbit "
        f"({div * 2 * np.pi / n / 60:.1f} min) — the report: 'unstable within less than one-tenth of an orbit'.",
        f"Its gain on the true coupled linear model: largest Re λ = {numbers.maxre:+.3f} n "
        f"({'unstable' if numbers.maxre > 0 else 'stable'}) although all its design-model poles lie in the sector.",
        f"Coupled design: {s_c['attrs']['verdict']}; peak |error| in the first orbit "
        f"{fmt_value(first, '{:.2f}')} deg (roll, pitch, yaw); from orbit 2 on {fmt_value(late, '{:.2f}')} deg.",
        f"Verdict: claim 1 {'REPRODUCED' if (div < 0.1 and s_c['attrs']['verdict'] == 'bounded') else 'NOT reproduced'}.",
    ])
    ctx.ledger_add("Claim 1", "divergence of the cross-inertia-free design", "0.1", div, "orbit",
                   bound="upper")
    # attitude error (rad, shown in deg), u (ft·lbf) and h (ft·lbf·s) per axis vs orbits
    plt = pyplot()
    fig, axs = plt.subplots(4, 3, figsize=(11, 10))
    for a in range(3):
        for d, lab, c, ls in ((s_c, "coupled design", COLORS[0], "-"),
                              (s_d, "no-cross-inertia design", COLORS[1], "--")):
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
    ctx.doc.fig("claim1_responses", "Claim 1: attitude error (full run and first 0.1 orbit), torque and "
                "momentum per axis (Figs 6.2–6.13 analogue)", save(fig, ctx.figdir, "claim1_responses"))
    return numbers


#: this section's parts, rows of :data:`acmm.report.plan.PARTS`
PARTS = [("claim1", "claim1", _build,
          ("design:mb3", "design:mb3_decoupled", "simulate:mb3", "simulate:mb3_decoupled"), ("poles",), 0.85)]
