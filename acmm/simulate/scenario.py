"""Scenario and result of a nonlinear closed-loop simulation of the ACMM law (CR-185644 ch. 6):
the arrays the simulator needs (:class:`Scenario`, built from a config and its design table by
:func:`scenario_from_config`), the sampled trajectory (:class:`SimResult`) and its per-level
statistics (the stair-case of inertia levels, ch. 6).

Integrated state X (24): ω (rad/s), θ (rad), h (ft·lbf·s), ∫h (ft·lbf·s²), DRF states
(α̇1, α1, α̇2, α2, α̇3, α3, β̇1, β1, β̇2, β2, β̇3, β3) (eqs 3.1, 3.5, 3.8, 4.35–4.40).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm.model import kinematics as kin
from acmm.model.linearize import state_scales
from acmm_qpp.errors import ConfigError

PLAIN_STATE_NAMES = ["omega1", "omega2", "omega3", "theta1", "theta2", "theta3",
                     "h1", "h2", "h3", "int_h1", "int_h2", "int_h3",
                     "alpha1_dot", "alpha1", "alpha2_dot", "alpha2", "alpha3_dot", "alpha3",
                     "beta1_dot", "beta1", "beta2_dot", "beta2", "beta3_dot", "beta3"]

# Why a simulation stopped (:attr:`SimResult.stop_code`), returned by the compiled integrator of
# :mod:`acmm.simulate.kernel`.  Callers compare ``stop_code`` with these names; numba
# compiles their values into that module's cached machine code (its cache follows only that
# file): keep them.
#: ran to t_end
STOP_NONE = 0
#: |θ_i − θ̂*_i| exceeded ``Scenario.divergence`` after an accepted step
STOP_ANGLE = 1
#: a CMG axis stayed at its momentum limit longer than ``Scenario.max_saturation``
STOP_SATURATION = 2
#: a Dormand–Prince step produced a non-finite state
STOP_NONFINITE = 3
#: the step size fell below 1e-6 s after a rejected step
STOP_STEP = 4
STOP_REASONS = {
    STOP_NONE: "completed",
    STOP_ANGLE: "attitude error exceeded the divergence bound",
    STOP_SATURATION: "a CMG axis stayed saturated longer than the bound",
    STOP_NONFINITE: "the state became non-finite",
    STOP_STEP: "the integrator step size underflowed",
}


@dataclass(frozen=True)
class Scenario:
    """Everything the simulator needs, as arrays (one row per inertia level).

    Attributes
    ----------
    level_start : (L,) array, s
        Start time of each level (first is 0).
    inertia : (L, 3, 3) array, slug·ft²
        True plant inertia per level.
    bias : (L, 3) array, ft·lbf
        Bias torque per level (eq 3.9).
    theta_est : (L, 3) array, rad
        TEA estimate θ̂* the controller uses per level.
    gain : (L, 3, 24) array
        Gain K per level (u = −K x), in the units of eq 4.47.
    harmonic_a, harmonic_b : (3,) arrays, ft·lbf
        Amplitudes of sin(nt) and sin(2nt).
    n : float, rad/s
        Orbital rate.
    torque_limit : float, ft·lbf
        Commanded torque is clipped to ±torque_limit per axis (ch. 5.1: 150 ft·lbf).
    momentum_limit : float, ft·lbf·s
        CMG momentum limit per axis (ch. 5.1: 20 000 ft·lbf·s).
    drf_mode : str
        ``"attitude_hold"`` or ``"momentum_hold"`` (DRF inputs, ch. 5.1).
    t_end : float, s
        End of the simulation.
    sample_times : (S,) array, s
        Output times (include 0 and every level start).
    x0 : (24,) array
        Initial plain state X, in the units listed in the module docstring.
    rtol : float
        Relative tolerance of the integrator, dimensionless.
    atol : (24,) array
        Absolute tolerance per component of X, in the units of X.
    divergence : float, rad
        A run stops as diverged when |θ_i − θ̂*_i| exceeds this bound.
    max_saturation : float, s
        A run stops as diverged when a CMG axis stays saturated longer than this.
    theta_ref : (L, 3) array or None, rad
        Attitude per level that :class:`RunExtremes` measures the error from (a sweep: the
        perturbed plant's true TEA); None: ``theta_est``.
    """

    level_start: np.ndarray
    inertia: np.ndarray
    bias: np.ndarray
    theta_est: np.ndarray
    gain: np.ndarray
    harmonic_a: np.ndarray
    harmonic_b: np.ndarray
    n: float
    torque_limit: float
    momentum_limit: float
    drf_mode: str
    t_end: float
    sample_times: np.ndarray
    x0: np.ndarray
    rtol: float
    atol: np.ndarray
    divergence: float
    max_saturation: float
    theta_ref: np.ndarray | None = None


@dataclass(frozen=True)
class RunExtremes:
    """Extremes of a run over every accepted integrator step (not only its output samples).

    Attributes
    ----------
    peak_momentum : (3,) array
        max |h_i| per axis, ft·lbf·s.
    peak_error : (3,) array
        max |θ_i − θ_ref,i| per axis (``Scenario.theta_ref`` of the level in force), rad.
    steady_error : (3,) array
        The same over the steps at t ≥ t_end / 2, rad (NaN: the run stopped before).
    torque_saturation_time : float
        Time with the commanded torque clipped on any axis, s (each accepted step counted by
        its end state).
    momentum_saturation_time : float
        Time with any CMG axis at its momentum limit, s (likewise).
    """

    peak_momentum: np.ndarray
    peak_error: np.ndarray
    steady_error: np.ndarray
    torque_saturation_time: float
    momentum_saturation_time: float


@dataclass(frozen=True)
class SimResult:
    """Sampled trajectory and verdict.

    ``state`` rows follow :data:`PLAIN_STATE_NAMES`; ``u_cmd`` is −K x before saturation,
    ``u`` the torque delivered; ``torque_saturated``/``momentum_saturated`` flag each axis.

    Attributes
    ----------
    t : (S,) array
        Sample times, s (the last one is the stop time when the run stopped early).
    state : (S, 24) array
        Plain state X at each sample, in the units listed in the module docstring.
    u_cmd : (S, 3) array
        Commanded torque −K x (eq 5.1) before saturation, ft·lbf.
    u : (S, 3) array
        Torque delivered after saturation (``docs/ERRATA.md`` § Saturation), ft·lbf.
    w : (S, 3) array
        Disturbance torque of eq 3.9, ft·lbf.
    level : (S,) int array
        Index of the inertia level in force at each sample.
    torque_saturated : (S, 3) bool array
        Commanded torque clipped, per axis.
    momentum_saturated : (S, 3) bool array
        CMG momentum at its limit, per axis.
    stop_code : int
        One of the ``STOP_*`` codes (:data:`STOP_REASONS`); ``STOP_NONE`` when completed.
    stop_time : float
        Time reached, s.
    n_steps : int
        Accepted integrator steps.
    n_rejected : int
        Rejected integrator steps.
    level_peak_momentum : (L,) array or None
        Per level, max_i |h_i| over every accepted integrator step of the level, ft·lbf·s (NaN:
        not reached); None: from the samples.
    level_steady_error : (L, 3) array or None
        Per level, max |θ − θ̂*| over the accepted steps of the second half of its dwell, rad
        (NaN: the run did not reach the middle of that dwell); None: from the samples.
    run_extremes : RunExtremes or None
        The run's extremes over every accepted step; None: not tracked.
    """

    t: np.ndarray
    state: np.ndarray
    u_cmd: np.ndarray
    u: np.ndarray
    w: np.ndarray
    level: np.ndarray
    torque_saturated: np.ndarray
    momentum_saturated: np.ndarray
    stop_code: int
    stop_time: float
    n_steps: int
    n_rejected: int
    level_peak_momentum: np.ndarray | None = None
    level_steady_error: np.ndarray | None = None
    run_extremes: RunExtremes | None = None

    @property
    def diverged(self) -> bool:
        """True when the run stopped early (divergence is a result, not an error)."""
        return self.stop_code != STOP_NONE

    @property
    def verdict(self) -> str:
        """``"diverged"`` or ``"bounded"``."""
        return "diverged" if self.diverged else "bounded"

    @property
    def reason(self) -> str:
        """Why the run stopped, in words (:data:`STOP_REASONS`)."""
        return STOP_REASONS[self.stop_code]


def plain_scales(n: float, drf_mode: str, inertia=None) -> np.ndarray:
    """Nominal magnitudes of the plain state X (for absolute tolerances).

    The scales of :func:`acmm.model.linearize.state_scales` (``docs/ERRATA.md`` § Scaling) with ω2
    in place of θ̇2.

    Parameters
    ----------
    n : float
        Orbital rate, rad/s.
    drf_mode : {"attitude_hold", "momentum_hold"}
        DRF inputs (h1, δθ2, δθ3) or (h1, h2, δθ3).
    inertia : (3, 3) or (L, 3, 3) array, optional
        The station's inertia (or its levels'), slug·ft² (:func:`acmm.model.linearize.momentum_scale`).

    Returns
    -------
    (24,) array
        Nominal magnitudes, in the units of X (module docstring).
    """
    s = state_scales(n, drf_mode, inertia).copy()
    s[1] = s[0]            # ω2 instead of θ̇2: same rate scale
    return s


def scenario_from_config(cfg, table, *, orbits: float | None = None, rtol: float | None = None) -> Scenario:
    """The :class:`Scenario` of a config and its design table (``acmm.stages.runners.DesignTable``).

    Levels are the design points in order (the stair-case); each starts at the orbit given by
    ``simulation.levels`` or, by default, after an equal dwell.  The controller uses the TEA of
    each level's mass properties as its estimate θ̂* (report ch. 5.1) and the scheduled gain
    K(θ̂2*) when the design has a schedule, else the level's own LQR gain (eq 5.1, ch. 5.3).

    Parameters
    ----------
    cfg : acmm.io.config.Config
        Validated config (orbital rate rad/s, disturbance ft·lbf, actuator limits ft·lbf and
        ft·lbf·s, ``simulation`` settings).
    table : acmm.stages.runners.DesignTable
        Design points in order: inertia (slug·ft²), bias (ft·lbf), TEA (rad) and gains.
    orbits : float, optional
        Simulated duration in orbits (dimensionless); default ``simulation.orbits``.
    rtol : float, optional
        Relative tolerance (dimensionless); default ``simulation.rtol``.

    Returns
    -------
    Scenario
        The arrays the simulator needs.

    Raises
    ------
    ConfigError
        When ``simulation.levels`` and the design table differ in length.
    """
    sim = cfg.simulation
    n = cfg.orbit_rate
    orbit = 2 * np.pi / n
    total = sim.orbits if orbits is None else orbits
    rows = table.level_rows()
    P = rows.size
    levels = np.asarray(sim.levels, float) if sim.levels is not None else total * np.arange(P) / P
    if levels.size != P:
        raise ConfigError(f"simulation.levels has {levels.size} entries but the design has {P} levels")
    t_end = total * orbit
    level_start = levels * orbit
    keep = level_start < t_end
    level_start = level_start[keep]
    idx = rows[np.nonzero(keep)[0]]
    samples = np.union1d(np.arange(0.0, t_end, sim.sample_interval), np.append(level_start, t_end))
    theta0 = table.tea[rows[0]] + np.radians(sim.initial_offset)
    x0 = np.concatenate([kin.lvlh_rate_in_body(theta0, n), theta0, np.zeros(18)])
    return Scenario(
        level_start=level_start, inertia=table.inertia[idx], bias=table.bias[idx], theta_est=table.tea[idx],
        gain=np.array([table.gain_at(table.tea[k, 1], k) for k in idx]),
        harmonic_a=np.asarray(cfg.disturbance.A), harmonic_b=np.asarray(cfg.disturbance.B), n=n,
        torque_limit=cfg.actuators.torque_limit, momentum_limit=cfg.actuators.momentum_limit,
        drf_mode=cfg.design.drf_mode, t_end=t_end, sample_times=samples, x0=x0,
        rtol=sim.rtol if rtol is None else rtol, atol=plain_scales(n, cfg.design.drf_mode, table.inertia[idx]) * sim.atol_scale,
        divergence=np.radians(sim.divergence_deg), max_saturation=sim.max_saturation_orbits * orbit)


def attitude_error(sc: Scenario, r: SimResult) -> np.ndarray:
    """θ − θ̂* of the level in force at each sample (rad).

    Parameters
    ----------
    sc : Scenario
        The simulated scenario (its TEA estimates, rad).
    r : SimResult
        Its result.

    Returns
    -------
    (S, 3) array
        Attitude error, rad.
    """
    return r.state[:, 3:6] - sc.theta_est[r.level]


def level_statistics(sc: Scenario, r: SimResult) -> list[dict]:
    """Per level: steady attitude error (max |θ − θ̂*| over the second half of the dwell, deg)
    and peak CMG momentum (ft·lbf·s).

    The stair-case of inertia levels of report ch. 6 (claim 2).

    Parameters
    ----------
    sc : Scenario
        The simulated scenario.
    r : SimResult
        Its result.

    Returns
    -------
    list of dict
        One per level reached: ``level``, ``start_orbit`` (orbits), ``theta2_deg`` (deg, the
        TEA pitch estimate), ``steady_error_deg`` ((3,) array, deg) and ``peak_momentum``
        (ft·lbf·s).
    """
    err = np.degrees(attitude_error(sc, r))
    peaks = level_peak_momentum(sc, r)
    out = []
    ends = np.append(sc.level_start[1:], sc.t_end)
    orbit = 2 * np.pi / sc.n
    for k, (t0, t1) in enumerate(zip(sc.level_start, ends)):
        steady = (r.level == k) & (r.t >= 0.5 * (t0 + t1))
        tracked = r.level_steady_error is not None and bool(np.all(np.isfinite(r.level_steady_error[k])))
        if tracked:          # every integrator step, not the samples (a level may have no sample there)
            worst = np.degrees(r.level_steady_error[k])
        elif steady.any():
            worst = np.abs(err[steady]).max(axis=0)
        else:
            continue
        out.append({"level": k, "start_orbit": t0 / orbit, "theta2_deg": float(np.degrees(sc.theta_est[k, 1])),
                    "steady_error_deg": worst, "peak_momentum": float(peaks[k])})
    return out


def level_peak_momentum(sc: Scenario, r: SimResult) -> np.ndarray:
    """Peak CMG momentum max_i |h_i| over each level of the stair-case (ch. 6).

    Parameters
    ----------
    sc : Scenario
        The simulated scenario (its levels).
    r : SimResult
        Its result.

    Returns
    -------
    (L,) ndarray
        Per level, ft·lbf·s; NaN for a level the run did not reach.
    """
    if r.level_peak_momentum is not None:           # every integrator step, not the samples
        return np.asarray(r.level_peak_momentum, float).copy()
    hmag = np.abs(r.state[:, 6:9])
    return np.array([hmag[r.level == k].max() if np.any(r.level == k) else np.nan
                     for k in range(len(sc.level_start))])
