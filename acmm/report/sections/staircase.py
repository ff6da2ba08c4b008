"""Section claim 2: the MB3 → AC stair-case (Figs 6.14–6.30, ch. 6)."""
from __future__ import annotations

import numpy as np

from acmm.report.constants import FAST_ORBITS
from acmm.report.context import SectionWriter
from acmm.report.figures_staircase import fig_staircase_inertia, fig_staircase_levels, fig_staircase_responses


def _sim(ctx: SectionWriter) -> dict:
    return ctx.data("acmm simulate:" + ctx.g.configs["staircase"].name)


def summary(ctx: SectionWriter) -> None:
    """Text, per-level table and printed numbers of the stair-case (claim 2, ch. 6).

    Parameters
    ----------
    ctx : acmm.report.context.SectionWriter
        The section's inputs (the stair-case config and its ``sim.h5``) and output (document blocks, printed numbers, figures).
    """
    ctx.section("staircase")
    cfg = ctx.g.configs["staircase"]
    s = ctx.data("acmm simulate:" + cfg.name)
    a = s["attrs"]
    if ctx.fast:
        ctx.doc.p(f"FAST MODE (--fast): the stair-case is shortened to {FAST_ORBITS:g} orbits "
                  f"(about one orbit per level). Run `acmm report` without --fast for the report's 130 orbits.")
    lv = s["levels"]
    o = s["orbits"]
    ctx.doc.p(f"{len(lv['start'])} inertia levels over {o[-1]:.1f} orbits, scheduled gain K(θ̂2*) per level, "
              f"torque limit ±{cfg.actuators.torque_limit:g} ft·lbf, momentum limit "
              f"±{cfg.actuators.momentum_limit:g} ft·lbf·s. Verdict: {a['verdict'].upper()} ({a['reason']}).")
    orbit = 2 * np.pi / cfg.orbit_rate
    rows = []
    for k in range(len(lv["steady_error"])):
        rows.append([str(k), f"{lv['start'][k] / orbit:.1f}", f"{np.degrees(lv['tea_estimate'][k, 1]):+.2f}",
                     f"{lv['inertia'][k, 0, 0] / 1e6:.2f} / {lv['inertia'][k, 1, 1] / 1e6:.2f} / "
                     f"{lv['inertia'][k, 2, 2] / 1e6:.2f}",
                     " / ".join(f"{v:.3f}" for v in np.degrees(lv["steady_error"][k])),
                     f"{lv['peak_momentum'][k]:.0f}"])
    ctx.doc.table(["level", "start (orbit)", "θ2* (deg)", "I11 / I22 / I33 (10⁶ slug·ft²)",
                   "steady |θ − θ̂*| roll / pitch / yaw (deg)", "peak |h| (ft·lbf·s)"], rows,
                   "Per-level statistics (steady: second half of each dwell)")
    tsat = float(np.mean(np.any(s["torque_saturated"] > 0, axis=1)))
    msat = float(np.mean(np.any(s["momentum_saturated"] > 0, axis=1)))
    ctx.doc.p(f"Samples with a torque-saturated axis: {100 * tsat:.2f} %; with a momentum-saturated axis: "
              f"{100 * msat:.2f} %. Peak |u| = {np.abs(s['u']).max():.1f} ft·lbf (samples), peak |h| = "
              f"{np.nanmax(lv['peak_momentum']):.0f} ft·lbf·s (every integrator step; the samples show "
              f"{np.abs(s['h']).max():.0f}).")
    if not ctx.fast:
        ctx.ledger_add("Claim 2", "stair-case length", "130", o[-1], "orbit")
    i0, i1 = lv["inertia"][0], lv["inertia"][-1] if len(lv["inertia"]) else lv["inertia"][0]
    if not ctx.fast:
        off = [(0, 1), (0, 2), (1, 2)]
        var = max(100 * abs(i1[i, j] / i0[i, j] - 1) for i, j in off if i0[i, j] != 0)
        ctx.ledger_add("Claim 2", "largest cross-inertia variation MB3 → AC ('up to 1600 %')", "1600", var,
                       "%", bound="upper")


def figure_inertia(ctx: SectionWriter) -> None:
    """The inertia elements vs time (Figs 6.14–6.19, :func:`acmm.report.figures.fig_staircase_inertia`).

    Parameters
    ----------
    ctx : acmm.report.context.SectionWriter
        The section's inputs (the stair-case config and its ``sim.h5``) and output (document blocks, printed numbers, figures).
    """
    ctx.doc.fig("staircase_inertia", "Inertia elements vs time (Figs 6.14–6.19 analogue)",
                fig_staircase_inertia(_sim(ctx), ctx.figdir))


def figure_responses(ctx: SectionWriter) -> None:
    """Attitude error, rate, torque and momentum per axis (Figs 6.20–6.30,
    :func:`acmm.report.figures.fig_staircase_responses`).

    Parameters
    ----------
    ctx : acmm.report.context.SectionWriter
        The section's inputs (the stair-case config and its ``sim.h5``) and output (document blocks, printed numbers, figures).
    """
    ctx.doc.fig("staircase_responses", "Attitude error, rate, torque and momentum per axis (Figs 6.20–6.30 "
                "analogue)", fig_staircase_responses(_sim(ctx), ctx.figdir))


def figure_levels(ctx: SectionWriter) -> None:
    """Steady attitude error and peak momentum per inertia level (ch. 6,
    :func:`acmm.report.figures.fig_staircase_levels`).

    Parameters
    ----------
    ctx : acmm.report.context.SectionWriter
        The section's inputs (the stair-case config and its ``sim.h5``) and output (document blocks, printed numbers, figures).
    """
    ctx.doc.fig("staircase_levels", "Per-level steady error and peak momentum vs the level's pitch TEA",
                fig_staircase_levels(_sim(ctx), ctx.figdir))
