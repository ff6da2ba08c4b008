"""Section claim 2: the MB3 → AC stair-case (Figs 6.14–6.30, ch. 6)."""
from __future__ import annotations

import numpy as np

from acmm.report.constants import AXES, FAST_ORBITS
from acmm.report.context import SectionWriter
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from matplotlib.collections import LineCollection


def _sim(ctx: SectionWriter) -> dict:
    return ctx.data("acmm simulate:" + ctx.g.configs["staircase"].name)


def _summary(ctx: SectionWriter) -> None:
    """Part: text, per-level table and printed numbers of the stair-case (claim 2, ch. 6)."""
    ctx.section("staircase")
    cfg = ctx.g.configs["staircase"]
    s = _sim(ctx)
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
    rows = [[str(k), f"{lv['start'][k] / orbit:.1f}", f"{np.degrees(lv['tea_estimate'][k, 1]):+.2f}",
             " / ".join(f"{lv['inertia'][k, i, i] / 1e6:.2f}" for i in range(3)),
             " / ".join(f"{v:.3f}" for v in np.degrees(lv["steady_error"][k])), f"{lv['peak_momentum'][k]:.0f}"]
            for k in range(len(lv["steady_error"]))]
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
        i0, i1 = lv["inertia"][0], lv["inertia"][-1]
        var = max(100 * abs(i1[i, j] / i0[i, j] - 1) for i, j in [(0, 1), (0, 2), (1, 2)] if i0[i, j] != 0)
        ctx.ledger_add("Claim 2", "largest cross-inertia variation MB3 → AC ('up to 1600 %')", "1600", var,
                       "%", bound="upper")


def _figure_inertia(ctx: SectionWriter) -> None:
    """Part: the inertia elements (``levels/inertia`` of each sample's level, slug·ft², shown in 10⁶
    slug·ft²) vs orbits (Figs 6.14–6.19)."""
    sim = _sim(ctx)
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
    ctx.doc.fig("staircase_inertia", "Inertia elements vs time (Figs 6.14–6.19 analogue)",
                save(fig1, ctx.figdir, "staircase_inertia"))


def _figure_responses(ctx: SectionWriter) -> None:
    """Part: attitude error (rad) and rate relative to LVLH (rad/s), both shown in deg, torque (ft·lbf)
    and momentum (ft·lbf·s) per axis vs orbits, level changes dotted (Figs 6.20–6.30)."""
    sim = _sim(ctx)
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
    ctx.doc.fig("staircase_responses", "Attitude error, rate, torque and momentum per axis (Figs 6.20–6.30 "
                "analogue)", save(fig2, ctx.figdir, "staircase_responses"))


def _figure_levels(ctx: SectionWriter) -> None:
    """Part: steady attitude error (``levels/steady_error``, rad, shown in deg; second half of each dwell)
    and peak momentum (ft·lbf·s) per level vs its pitch TEA (ch. 6)."""
    sim = _sim(ctx)
    plt = pyplot()
    fig3, axs = plt.subplots(1, 2, figsize=(11, 3.8))
    th = np.degrees(sim["levels"]["tea_estimate"][:, 1])[: len(sim["levels"]["steady_error"])]
    for a in range(3):
        axs[0].plot(th, np.degrees(sim["levels"]["steady_error"][:, a]), "o-", color=COLORS[a], label=AXES[a])
    axs[0].set_ylabel("steady |θ − θ̂*| (deg)")
    axs[0].set_title("Steady attitude error per level (second half of each dwell)")
    axs[1].plot(th, sim["levels"]["peak_momentum"], "s-", color=COLORS[3], label="peak |h_i| over the level")
    axs[1].set_ylabel("peak CMG momentum (ft·lbf·s)")
    axs[1].set_title("Peak momentum per level")
    for ax in axs:
        ax.set_xlabel("pitch TEA of the level θ2* (deg)")
        ax.legend()
    fixed_layout(fig3, left=0.62, bottom=0.54, top=0.33, wspace=0.16)
    ctx.doc.fig("staircase_levels", "Per-level steady error and peak momentum vs the level's pitch TEA",
                save(fig3, ctx.figdir, "staircase_levels"))


#: this section's parts, rows of :data:`acmm.report.plan.PARTS`
PARTS = [
    ("staircase", "staircase", _summary, ("simulate:staircase",), (), 0.1),
    ("staircase/inertia", "staircase", _figure_inertia, ("simulate:staircase",), (), 0.5),
    ("staircase/responses", "staircase", _figure_responses, ("simulate:staircase",), (), 0.95),
    ("staircase/levels", "staircase", _figure_levels, ("simulate:staircase",), (), 0.3),
]
