"""Section ±30 % inertia robustness (the sweep of :mod:`acmm.sweep`); the claim of ch. 7."""
from __future__ import annotations

import numpy as np

from acmm_qpp.results import h5_text
from acmm.report.context import SectionWriter
from acmm.report.numbers import fmt_value
from acmm.report.figure_style import COLORS, fixed_layout, pyplot, save
from acmm.report.ledger import STATUS_EXPLAINED, PrintedNumber


def case_column(sweep: dict, label: str, key: str) -> np.ndarray:
    """A text column of the cases of one base of a ``sweep.h5`` (ch. 7's Monte Carlo).

    Parameters
    ----------
    sweep : dict
        The ``sweep.h5`` as read by :func:`acmm_qpp.results.read_h5`.
    label : str
        The base's label (``mb3``, ``ac``, ...).
    key : str
        The column (``verdict``, ``reason``).

    Returns
    -------
    str array
        Its cases' texts, in case order.
    """
    names = [h5_text(x) for x in np.atleast_1d(sweep["base_names"])]
    column = np.array([h5_text(x) for x in np.atleast_1d(sweep[key])])
    return column[np.atleast_1d(sweep["base"]) == names.index(label)]


def bounded_count(sweep: dict, label: str) -> tuple[int, int]:
    """How many cases of one base of a ``sweep.h5`` stayed bounded and settled, of how many: the
    count the report's robustness table and the README's claims table show.

    Parameters
    ----------
    sweep : dict
        The ``sweep.h5`` as read by :func:`acmm_qpp.results.read_h5`.
    label : str
        The base's label.

    Returns
    -------
    tuple of int
        (bounded cases, cases).
    """
    v = case_column(sweep, label, "verdict")
    return int(np.sum(v == "bounded")), int(v.size)


def _build(ctx: SectionWriter) -> None:
    """Part: the ±30 % inertia Monte Carlo (``ctx.g.robustness``, ch. 7), or why it is not available."""
    ctx.section("robustness")
    ctx.doc.p("The report (ch. 7): 'the closed-loop system remains stable for up to ±30 % variations in "
              "the SSF inertia matrix'. It does not say which variations (elements, scaling), which TEA "
              "estimate or which design were used.")
    r = ctx.g.robustness
    if r is None:
        ctx.doc.p(f"Not available in this run: {ctx.g.robustness_note}. "
                  "(The sweep of issue 7, acmm.sweep.run_sweep with configs/sweep_inertia30.yaml, provides it.)")
        ctx.ledger.append(PrintedNumber("Robustness", "stable for ±30 % inertia variation", "30", None, "%",
                                        STATUS_EXPLAINED, "not evaluated in this run: " + ctx.g.robustness_note))
        return
    d = r["data"]
    names = [h5_text(x) for x in np.atleast_1d(d["base_names"])]
    verdict = np.array([h5_text(x) for x in np.atleast_1d(d["verdict"])])
    base = np.atleast_1d(d["base"])
    peak = np.degrees(np.atleast_2d(d["peak_attitude_error"]))   # stored in rad
    params = d["parameters"]
    if r["fast"]:
        ctx.doc.p(f"FAST MODE: reduced sweep, {r['n_runs']} Monte Carlo runs per base of {r['orbits']:g} orbits, "
                  "no margin search. Run without --fast for the 200-run sweep of configs/sweep_inertia30.yaml.")
    start = ("each case starts at its plant's equilibrium connected to the design TEA, or at the root "
             "continued from LVLH where that branch folds (guide: docs/howto/sweeps.md, 'The perturbed plant')"
             if r["design"] == "fixed" else "each case redesigned about its plant's TEA")
    knows = ("is redesigned for the perturbed plant" if r["design"] != "fixed" else
             "does not know the perturbation" if r["tea_estimate"] == "nominal" else
             "knows the perturbed plant's TEA, not its inertia")
    ctx.doc.p(f"Sweep {r['run'].config}: every inertia element multiplied by (1 + δ), δ ~ U(−0.3, 0.3) "
              f"independently (unphysical draws redrawn), seed {r['seed']}, {r['n_runs']} runs per base, "
              f"{r['orbits']:g} orbits each; design '{r['design']}', TEA estimate '{r['tea_estimate']}' "
              f"(the controller {knows}); bias torque held at its nominal value; {start}.")
    rows, fracs, mg = [], {}, d.get("margin", {})
    for k, lab in enumerate(names):
        sel = base == k
        v = verdict[sel]
        nb, nv = bounded_count(d, lab)
        fracs[lab] = nb / max(1, nv)
        others = ", ".join(f"{x} {int(np.sum(v == x))}" for x in sorted(set(v)) if x != "bounded")
        pk = peak[sel][v == "bounded"]
        med = fmt_value(np.median(pk, axis=0), "{:.2f}") if pk.size else "—"
        mx = fmt_value(np.max(pk, axis=0), "{:.2f}") if pk.size else "—"
        lim = (f"[{float(mg[f'{lab}_down']['limit']):.3f}, {float(mg[f'{lab}_up']['limit']):.3f}]"
               if f"{lab}_down" in mg and f"{lab}_up" in mg else "—")
        rows.append([lab.upper(), f"{nb}/{nv} ({100 * fracs[lab]:.0f} %)", others or "—", med, mx, lim])
    ctx.doc.table(["base", "bounded", "other verdicts", "median peak |err| r/p/y (deg), bounded",
                   "max peak |err| r/p/y (deg), bounded", "uniform scaling s tolerated"], rows,
                   "±30 % inertia Monte Carlo with the fixed nominal designs")
    verdict_txt = ("REPRODUCED" if all(f == 1.0 for f in fracs.values()) else
                   "NOT reproduced for arbitrary ±30 % element variations with the fixed nominal design "
                   "and nominal TEA estimate")
    ctx.doc.p(f"Verdict: the ±30 % robustness statement is {verdict_txt}.")
    ctx.ledger.append(PrintedNumber(
        "Robustness", "stable for ±30 % inertia variation", "30", None, "%", STATUS_EXPLAINED,
        "bounded fraction of the ±30 % element draws: " +
        ", ".join(f"{k.upper()} {100 * v:.0f} %" for k, v in fracs.items()) +
        ("" if all(f == 1.0 for f in fracs.values()) else
         "; the report does not define its variations, estimate or design, so the statement cannot be "
         "checked as printed; this is the strictest reading (unknown perturbation, fixed gains)")))
    # peak attitude error (deg, worst axis) vs max_k |δ_k| (relative inertia changes) per case
    plt = pyplot()
    keys = [k for k in ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23") if k in params]
    dmax = np.max(np.abs(np.column_stack([params[k] for k in keys])), axis=1) if keys else np.zeros(len(base))
    pk = np.full(len(base), np.nan)
    finite = np.isfinite(peak).any(axis=1)
    pk[finite] = np.nanmax(peak[finite], axis=1)
    fig, axs = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.0), squeeze=False)
    for k, lab in enumerate(names):
        ax = axs[0, k]
        sel = base == k
        ok = sel & (verdict == "bounded")
        bad = sel & (verdict != "bounded")
        ax.plot(100 * dmax[ok], pk[ok], "o", ms=3.5, color=COLORS[0], label="bounded")
        top = np.nanmax(pk[ok]) * 1.5 if ok.any() and np.isfinite(pk[ok]).any() else 60.0
        # fmin: a non-finite peak is drawn at the top
        ax.plot(100 * dmax[bad], np.fmin(pk[bad], top), "x", ms=4, color=COLORS[1],
                label="diverged / no equilibrium (clipped)")
        ax.set_yscale("log")
        ax.set_xlabel("largest inertia-element perturbation max|δ| (%)")
        ax.set_ylabel("peak attitude error, worst axis (deg)")
        ax.set_title(f"{lab.upper()}: {int(ok.sum())}/{int(sel.sum())} bounded")
        ax.legend(loc="lower right")
    fixed_layout(fig, left=0.72, bottom=0.54, top=0.33, wspace=0.2)
    files = save(fig, ctx.figdir, "robustness")
    ctx.doc.fig("robustness", "±30 % inertia Monte Carlo: peak attitude error vs the largest element "
                "perturbation per case (bounded: filled; diverged or no equilibrium: crosses)", files)


#: this section's parts, rows of :data:`acmm.report.plan.PARTS`
PARTS = [("robustness", "robustness", _build, ("sweep",), (), 0.55)]
