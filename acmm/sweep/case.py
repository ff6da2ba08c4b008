"""Running one case: the base context, the perturbed plant (redesigned when asked), one
nonlinear closed-loop simulation and its metrics; the margin search of uniform inertia scaling.

The perturbed plant's TEA is that of eqs 4.1–4.3, its redesign the sector LQR (ch. 5.2) and
schedule (ch. 5.3) of the pipeline, and its simulation the nonlinear stair-case run of ch. 6.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from acmm_qpp.errors import ConvergenceError, DesignError
from acmm.model.inertia import perturb_inertia
from acmm.sweep.cases import unphysical_draw_reason, case_values
from acmm.sweep.spec import AXES
from acmm.simulate.scenario import scenario_from_config
from acmm.stages.design import compute_design, design_table
from acmm.design.schedule_points import PointSpec, schedule_specs
from acmm.design.settings import design_settings, schedule_settings
from acmm.design.design_core import design_schedule
from acmm.model import kinematics as kin
from acmm.simulate import kernel as sm, scenario as scen
from acmm.model.tea import NoEquilibriumError, resolve_bias, solve_tea_connected, solve_tea_fast


# ---------------------------------------------------------------------------------------------
# one case
# ---------------------------------------------------------------------------------------------
@dataclass
class BaseContext:
    """What a worker needs for every case of one base (picklable).

    Attributes
    ----------
    label : str
        The base's label in the sweep's output.
    config : acmm.io.config.Config
        The base config.
    table : acmm.stages.runners.DesignTable
        Its nominal design.
    scenario : acmm.simulate.kernel.Scenario
        Its nominal scenario, over the sweep's orbits.
    spec : acmm.sweep.config.SweepSpec
        The sweep specification.
    orbits : float
        Simulated length, orbits.
    """

    label: str
    config: object          # acmm.io.config.Config
    table: object           # acmm.stages.runners.DesignTable (nominal design)
    scenario: object        # acmm.simulate.kernel.Scenario of the nominal config (orbits of the sweep)
    spec: object            # SweepSpec
    orbits: float


def prepare_base(base, spec) -> BaseContext:
    """Design the base config once (nominal design) and build its nominal scenario.

    Parameters
    ----------
    base : acmm.sweep.config.Base
        A base of the sweep (its ``label`` and validated ``config``).
    spec : acmm.sweep.config.SweepSpec
        The sweep specification (``orbits`` overrides the config's ``simulation.orbits``).

    Returns
    -------
    BaseContext
        The base's context for every case.
    """
    cfg = base.config
    orbits = spec.orbits if spec.orbits is not None else cfg.simulation.orbits
    table = compute_design(cfg).table
    return BaseContext(base.label, cfg, table, scenario_from_config(cfg, table, orbits=orbits), spec, float(orbits))


def _redesigned_specs(cfg, values: dict, biases: np.ndarray) -> list:
    """The design points of the base config with the perturbed inertia and explicit (held) bias
    torques: ``biases[0]`` at the start, each other configuration's own bias plus the same
    added torque (``biases[0]`` minus the start's nominal bias)."""
    n = cfg.orbit_rate
    start = PointSpec(cfg.name, perturb_inertia(cfg.inertia.matrix(), values),
                      np.array([float(b) for b in biases[0]]), 0.0)
    if cfg.schedule is None:
        return [start]
    added = biases[0] - resolve_bias(cfg.disturbance, cfg.inertia.matrix(), n)

    def spec(point, s=float("nan")):
        m = point.inertia.matrix()
        bias = resolve_bias(point.disturbance, m, n) + added
        return PointSpec(point.name, perturb_inertia(m, values), np.array([float(b) for b in bias]), s)

    end = spec(cfg.schedule.to, 1.0) if cfg.schedule.to is not None else None
    return schedule_specs(start, end, [spec(p) for p in cfg.schedule.points], schedule_settings(cfg), n)


def empty_row() -> dict:
    """The metrics row of a case that has none yet (NaN and empty values).

    Returns
    -------
    dict
        The row's fields, NaN where a metric is a number (units of the metrics row: deg, s,
        ft·lbf·s, slug·ft², ft·lbf).
    """
    nan3 = [math.nan] * 3
    return {"verdict": "", "reason": "", "time_to_divergence": math.nan,
            "peak_attitude_error": nan3, "steady_attitude_error": nan3, "peak_momentum": nan3,
            "torque_saturation_time": math.nan, "momentum_saturation_time": math.nan,
            "tea_true": nan3, "tea_estimate": nan3, "inertia": [[math.nan] * 3] * 3, "bias": nan3,
            "n_steps": 0}


def simulate_values(ctx: BaseContext, values: dict) -> dict:
    """Simulate the base with the given parameter values; returns the metrics row (no case info).

    Parameters
    ----------
    ctx : BaseContext
        The base.
    values : dict
        Parameter name → value (``acmm.sweep.config.PARAMETERS``: relative inertia changes
        dimensionless, biases ft·lbf, offsets deg, ``inertia_scale``, ``harmonic_scale``).

    Returns
    -------
    dict
        ``verdict``, ``reason`` and the metrics: ``time_to_divergence`` (orbits), peak and steady
        attitude error (deg, per axis), ``peak_momentum`` (ft·lbf·s, per axis), saturation
        times (orbits), true and estimated TEA (deg), ``inertia`` (slug·ft²), ``bias``
        (ft·lbf), ``n_steps``.  An unphysical plant, a missing equilibrium, a failed design or
        TEA is a verdict, not an exception.
    """
    sc0, table, cfg, spec = ctx.scenario, ctx.table, ctx.config, ctx.spec
    row = empty_row()
    inertia = np.array([perturb_inertia(m, values) for m in sc0.inertia])
    bias = sc0.bias + np.array([values.get(f"bias_{a}", 0.0) for a in AXES])
    row.update(inertia=inertia[0].tolist(), bias=bias[0].tolist())
    why = unphysical_draw_reason(values, sc0.inertia)
    if why is not None:
        row.update(verdict="unphysical", reason=why)
        return row
    n = sc0.n
    hs = values.get("harmonic_scale", 1.0)
    offset = np.radians(np.asarray(cfg.simulation.initial_offset)
                        + np.array([values.get(f"offset_{a}", 0.0) for a in AXES]))
    tea_note = ""
    try:
        if spec.design == "redesign":
            # the core called directly on the perturbed design points with the base config's settings
            ds = design_schedule(_redesigned_specs(cfg, values, bias), design_settings(cfg), schedule_settings(cfg))
            # only the inertia and bias differ from the base config, and those come from the table
            # (the redesign's bias per point is the held nominal bias (+ offsets); the schedule's
            # levels are the perturbed design points)
            sc = scen.scenario_from_config(cfg, design_table(ds.points, ds.fit, ""), orbits=ctx.orbits)
            true = sc.theta_est.copy()
        else:
            true, tea_note = _perturbed_tea(sc0, inertia, bias)
            if spec.tea_estimate == "true":
                est = true
                rows = table.level_rows()
                gain = np.array([table.gain_at(t[1], r) for t, r in zip(true, rows)])
            else:
                est, gain = sc0.theta_est, sc0.gain
            sc = dataclasses.replace(sc0, inertia=inertia, bias=bias, theta_est=est, gain=gain)
    except NoEquilibriumError as exc:
        row.update(verdict="no_equilibrium", reason=str(exc).split(":")[0])
        return row
    except DesignError as exc:
        row.update(verdict="design_failed", reason=str(exc)[:200])
        return row
    except ConvergenceError as exc:
        # the TEA's own failures say "TEA ..."; a redesign's Riccati or sector LQR is the design's
        tea = spec.design != "redesign" or str(exc).startswith("TEA")
        row.update(verdict="tea_failed" if tea else "design_failed", reason=str(exc)[:200])
        return row
    theta0 = true[0] + offset
    x0 = np.concatenate([kin.lvlh_rate_in_body(theta0, n), theta0, np.zeros(18)])
    sc = dataclasses.replace(sc, x0=x0, theta_ref=true, harmonic_a=sc0.harmonic_a * hs, harmonic_b=sc0.harmonic_b * hs)
    r = sm.simulate(sc)
    row = _metrics(row, r, sc, true, n, spec)
    row["reason"] += tea_note
    return row


def _metrics(row: dict, r, sc, true: np.ndarray, n: float, spec) -> dict:
    """Fill ``row`` with the verdict and metrics of the simulation ``r`` of scenario ``sc``;
    ``true``: the plant's TEA per level (rad; the scenario's ``theta_ref``); ``n``: orbit rate
    (rad/s).  Peaks, steady errors and saturation times are taken over every accepted integrator
    step (:class:`acmm.simulate.scenario.RunExtremes`), not over the output samples, which under-reported
    them (by 2.3x for a stair-case's peak momentum at 300 s samples)."""
    ext = r.run_extremes
    steady = np.degrees(ext.steady_error)
    if not np.all(np.isfinite(steady)):          # stopped before t_end / 2: its last state
        steady = np.degrees(np.abs(r.state[-1, 3:6] - true[r.level[-1]]))
    orbit = 2 * np.pi / n
    reason = r.reason
    gap = np.abs(true - sc.theta_est).max()
    if r.stop_code == scen.STOP_ANGLE and gap >= sc.divergence:
        reason += f" (the plant's TEA is {np.degrees(gap):.1f} deg from the controller's estimate)"
    verdict = r.verdict
    if verdict == "bounded" and steady.max() > spec.settle_deg:
        # within the divergence bound of the controller's estimate, but not at the plant's TEA
        verdict = "not_settled"
        reason = (f"bounded, but the steady attitude error from the plant's TEA is {steady.max():.1f} deg "
                  f"(> settle_deg {spec.settle_deg:g})")
    row.update(
        verdict=verdict, reason=reason,
        time_to_divergence=r.stop_time / orbit if r.diverged else math.nan,
        peak_attitude_error=np.degrees(ext.peak_error).tolist(),
        steady_attitude_error=steady.tolist(),
        peak_momentum=np.asarray(ext.peak_momentum, float).tolist(),
        torque_saturation_time=float(ext.torque_saturation_time) / orbit,
        momentum_saturation_time=float(ext.momentum_saturation_time) / orbit,
        tea_true=np.degrees(true[0]).tolist(), tea_estimate=np.degrees(sc.theta_est[0]).tolist(),
        n_steps=int(r.n_steps))
    return row


def _perturbed_tea(sc0, inertia: np.ndarray, bias: np.ndarray) -> tuple[np.ndarray, str]:
    """The perturbed plant's TEA per level ((L, 3), rad) and a note (``""``, or which levels' design
    branch folded, appended to the case's reason), from the nominal scenario ``sc0`` (``n`` rad/s; per
    level ``inertia`` slug·ft², ``bias`` ft·lbf, design TEA ``theta_est`` rad) and the perturbed
    ``inertia`` (L, 3, 3) slug·ft² and ``bias`` (L, 3) ft·lbf: the equilibrium continuously connected
    to the design TEA (:func:`acmm.model.tea.solve_tea_connected`, compiled, ~0.1–1 ms); only where
    that branch folds between the two plants, the root continued from LVLH
    (:func:`acmm.model.tea.solve_tea_fast`, whose NoEquilibriumError or ConvergenceError it raises,
    naming the fold first).  It depends only on the case's plant and the nominal design, never on
    the cases run before, so a row is the same whatever executor, chunking or order runs it."""
    theta, folded = [], []    # a fallback's NoEquilibriumError says the design branch folded first
    for k in range(inertia.shape[0]):
        tea = solve_tea_connected(sc0.theta_est[k], sc0.inertia[k], sc0.bias[k], inertia[k], sc0.n, bias[k])
        if tea is None:
            folded.append(str(k))
            try:
                tea = solve_tea_fast(inertia[k], sc0.n, bias[k])
            except NoEquilibriumError as exc:
                raise NoEquilibriumError(f"the design TEA's equilibrium folds between the nominal and this "
                                         f"plant (level {k}), and there is {exc}", hint=exc.hint) from None
        theta.append(tea.theta)
    note = ""
    if folded:
        note = (f" [level {', '.join(folded)}: the design TEA's equilibrium folds between the nominal "
                "and this plant; started at the root continued from LVLH]")
    return np.array(theta), note


def run_case(ctx: BaseContext, index: int) -> dict:
    """Case ``index`` of a base: draw (or look up) its parameters, simulate, return its row.

    Parameters
    ----------
    ctx : BaseContext
        The base.
    index : int
        Case index within the base.

    Returns
    -------
    dict
        The row of :func:`simulate_values` plus ``kind="case"``, ``base``, ``index``,
        ``values`` and ``n_draws``.
    """
    values, draws, _ = case_values(ctx.spec, index, ctx.scenario.inertia)
    return {**simulate_values(ctx, values), "kind": "case", "base": ctx.label, "index": int(index),
            "values": values, "n_draws": int(draws)}


# ---------------------------------------------------------------------------------------------
# margin search on a uniform inertia scaling
# ---------------------------------------------------------------------------------------------
def margin_search(ctx: BaseContext, direction: str) -> dict:
    """Largest (``up``) or smallest (``down``) uniform inertia scaling s the design tolerates.

    Geometric scan from s = 1 towards ``margin.high`` (``low``) in ``scan_points`` steps, then
    bisection in log s between the last bounded and the first failing point until their ratio is
    below 1 + ``rel_tol``.  Assumes the bounded set is an interval around 1 between scanned
    points (a failure hidden between two bounded scan points would be missed).

    Parameters
    ----------
    ctx : BaseContext
        The base (its ``spec.margin`` settings).
    direction : {"up", "down"}
        Search towards larger or smaller inertia.

    Returns
    -------
    dict
        ``kind="margin"``, ``limit`` (largest/smallest bounded s, dimensionless; NaN when the
        nominal case is not bounded), ``first_failure``, its verdict and reason,
        ``reached_end``, ``search_end`` and every evaluated s with its verdict.
    """
    m = ctx.spec.margin
    end = m.high if direction == "up" else m.low
    evaluated: list[tuple[float, str, str]] = []

    def ok(s: float) -> bool:
        row = simulate_values(ctx, {"inertia_scale": s})
        evaluated.append((s, row["verdict"], row["reason"]))
        return row["verdict"] == "bounded"

    nominal = ok(1.0)
    good, bad = 1.0, None
    if nominal:
        for k in range(1, m.scan_points + 1):
            s = end ** (k / m.scan_points)
            if not ok(s):
                bad = s
                break
            good = s
        if bad is not None:
            while max(good, bad) / min(good, bad) > 1 + m.rel_tol:
                mid = math.sqrt(good * bad)
                good, bad = (mid, bad) if ok(mid) else (good, mid)
    fail = next((e for e in evaluated if e[0] == bad), None)
    return {"kind": "margin", "base": ctx.label, "direction": direction,
            "limit": good if nominal else math.nan, "first_failure": math.nan if bad is None else bad,
            "failure_verdict": fail[1] if fail else "", "failure_reason": fail[2] if fail else "",
            "reached_end": bool(nominal and bad is None), "search_end": end,
            "evaluated_s": [e[0] for e in evaluated], "evaluated_verdict": [e[1] for e in evaluated]}

