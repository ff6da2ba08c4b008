"""Nonlinear closed-loop simulation of the ACMM law (CR-185644 ch. 6).

Plant: eqs 3.1, 3.5, 3.8 with the disturbance of eq 3.9 (per-level bias).  Controller: the
integral ∫h and the twelve DRF states (eqs 4.35–4.40, fed by deviations) are integrated with
the plant; u = −K(θ̂*)·x (eq 5.1) with x of eq 4.47 built from the nonlinear state around the
current TEA estimate θ̂* (θ̇2 from the nonlinear kinematics).  Saturation (ch. 5.1,
``docs/ERRATA.md`` § Saturation):
the commanded torque is clipped to ±torque_limit per axis; a CMG axis at |h_i| ≥ momentum_limit
delivers only the torque that stops |h_i| growing, and the body receives exactly the torque the
CMG absorbs, so I ω̇ + ḣ + ω×(Iω + h) = τ_gg + w holds along every trajectory.

The integrator is an adaptive Dormand–Prince 5(4) pair compiled with numba and cached on disk
(:mod:`acmm.model.compiled_cache`); :mod:`acmm.simulate.reference` is its plain-numpy reference.

Integrated state X (24): ω (rad/s), θ (rad), h (ft·lbf·s), ∫h (ft·lbf·s²), DRF states
(α̇1, α1, α̇2, α2, α̇3, α3, β̇1, β1, β̇2, β2, β̇3, β3).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin
from acmm.model.compiled_cache import njit_cached
from acmm.model.linearize import DRF_INPUTS
from acmm.simulate.scenario import (STOP_ANGLE, STOP_NONE, STOP_NONFINITE, STOP_SATURATION, STOP_STEP,
                                    RunExtremes, Scenario, SimResult)


# ----------------------------------------------------------------------------------------------
# the bundles the compiled kernel takes (numba types a NamedTuple of arrays and floats)
# ----------------------------------------------------------------------------------------------
class LevelSchedule(NamedTuple):
    """The per-level arrays of a run (one row per inertia level of the stair-case, ch. 6).

    Attributes
    ----------
    level_start : (L,) array, s
        Start time of each level (the first is 0).
    level_mid : (L,) array, s
        Middle of each level's dwell: its steady error is measured from there on.
    inertia : (L, 3, 3) array, slug·ft²
        True plant inertia per level (eq 3.1).
    inertia_inv : (L, 3, 3) array, 1/(slug·ft²)
        Its inverse.
    bias : (L, 3) array, ft·lbf
        Bias torque per level (eq 3.9).
    theta_est : (L, 3) array, rad
        TEA estimate θ̂* the controller linearizes about (eq 4.47).
    omega_est : (L, 3) array, rad/s
        Body rate of the LVLH frame at θ̂* (eq 3.5).
    gain : (L, 3, 24) array
        Gain K per level (u = −K x, eq 5.1), in the units of eq 4.47.
    theta_ref : (L, 3) array, rad
        Attitude the run's extremes are measured from (:class:`~acmm.simulate.scenario.RunExtremes`).
    run_mid : float, s
        t_end / 2: the run's steady error is measured from there on.
    """

    level_start: np.ndarray
    level_mid: np.ndarray
    inertia: np.ndarray
    inertia_inv: np.ndarray
    bias: np.ndarray
    theta_est: np.ndarray
    omega_est: np.ndarray
    gain: np.ndarray
    theta_ref: np.ndarray
    run_mid: float


class Level(NamedTuple):
    """The rows of :class:`LevelSchedule` of the level in force (built by :func:`_level`): its
    fields of the same names and units, and ``mid`` = ``level_mid[level]`` (s)."""

    inertia: np.ndarray
    inertia_inv: np.ndarray
    bias: np.ndarray
    theta_est: np.ndarray
    omega_est: np.ndarray
    gain: np.ndarray
    theta_ref: np.ndarray
    mid: float


class LoopConstants(NamedTuple):
    """The constants of the plant, controller and integrator (the same at every level).

    Attributes
    ----------
    ha, hb : (3,) array, ft·lbf
        Amplitudes of the disturbance's sin(nt) and sin(2nt) (eq 3.9).
    n : float, rad/s
        Orbital rate.
    tmax : float, ft·lbf
        Torque limit per axis (ch. 5.1).
    hmax : float, ft·lbf·s
        CMG momentum limit per axis (ch. 5.1).
    drf_idx : (6,) int array
        Index in x (eq 4.47) of each DRF's input (eqs 4.35–4.40), the filters at n then at 2n.
    rtol : float
        Relative tolerance of the integrator, dimensionless.
    atol : (24,) array
        Absolute tolerance per component of X, in the units of X.
    divergence : float, rad
        The run stops (:data:`~acmm.simulate.scenario.STOP_ANGLE`) when |θ_i − θ̂*_i| exceeds it.
    max_sat : float, s
        The run stops (:data:`~acmm.simulate.scenario.STOP_SATURATION`) when a CMG axis stays
        saturated longer.
    C : (7,) array
        Dormand–Prince 5(4) nodes, dimensionless.
    A : (7, 6) array
        Dormand–Prince 5(4) stage coefficients, dimensionless.
    B5 : (7,) array
        Weights of the 5th-order solution, dimensionless.
    E : (7,) array
        Weights of the error estimate (5th minus 4th order), dimensionless.
    """

    ha: np.ndarray
    hb: np.ndarray
    n: float
    tmax: float
    hmax: float
    drf_idx: np.ndarray
    rtol: float
    atol: np.ndarray
    divergence: float
    max_sat: float
    C: np.ndarray
    A: np.ndarray
    B5: np.ndarray
    E: np.ndarray


class KernelOutputs(NamedTuple):
    """What the kernel writes: the output samples and the extremes over every accepted step.

    Attributes
    ----------
    state : (S, 24) array
        Plain state X at each sample, in the units of the module docstring (NaN after a stop).
    u_cmd : (S, 3) array, ft·lbf
        Commanded torque −K x (eq 5.1).
    u : (S, 3) array, ft·lbf
        Torque the CMGs deliver after saturation (ch. 5.1).
    flags : (S, 6) array
        1.0 where an axis is torque-saturated (first 3) or at its momentum limit (last 3), else
        0.0, dimensionless.
    level : (S,) int array
        Level in force at each sample.
    peak_h : (L,) array, ft·lbf·s
        Per level, max_i |h_i| (NaN: not reached).
    steady : (L, 3) array, rad
        Per level, max |θ_i − θ̂*_i| from the middle of its dwell on (NaN: not reached).
    run : (11,) array
        Over the run: peak |h_i| (ft·lbf·s), peak |θ_i − θ_ref,i| (rad), the same from t_end / 2
        on (rad), the time with any axis torque-saturated (s), the time with any axis
        momentum-saturated (s).
    """

    state: np.ndarray
    u_cmd: np.ndarray
    u: np.ndarray
    flags: np.ndarray
    level: np.ndarray
    peak_h: np.ndarray
    steady: np.ndarray
    run: np.ndarray


class Workspace(NamedTuple):
    """Scratch buffers of the kernel (built by :func:`_workspace`).

    Attributes
    ----------
    K : (7, 24) array
        Dormand–Prince stages Ẋ, in the units of X per s.
    y : (24,) array
        A stage's state, then the step's 5th-order solution, in the units of X.
    x : (24,) array
        Controller state x of eq 4.47, in its units.
    u : (3,) array, ft·lbf
        Torque delivered after saturation (ch. 5.1).
    u_cmd : (3,) array, ft·lbf
        Commanded torque −K x (eq 5.1).
    flags : (6,) array
        Saturation flags, as :attr:`KernelOutputs.flags`, dimensionless.
    sat_time : (3,) array, s
        How long each CMG axis has been at its momentum limit.
    """

    K: np.ndarray
    y: np.ndarray
    x: np.ndarray
    u: np.ndarray
    u_cmd: np.ndarray
    flags: np.ndarray
    sat_time: np.ndarray


# ----------------------------------------------------------------------------------------------
# compiled kernel.  The right-hand side (:func:`closed_loop_rhs`, :func:`_torque`) is inlined into its
# callers (``inline="always"``, numba's own inlining: the arithmetic is unchanged): called
# apart, it re-reads the bundles' arrays at every stage with their reference counts, ~15 % of
# the integration time.
# ----------------------------------------------------------------------------------------------
@njit_cached()
def _workspace():
    """Fresh scratch buffers (:class:`Workspace`): uninitialized state scratch, zeroed flags."""
    return Workspace(np.empty((7, 24)), np.empty(24), np.empty(24), np.empty(3), np.empty(3),
                     np.zeros(6), np.zeros(3))


@njit_cached()
def _level(sched, level):
    """The rows of ``sched`` (:class:`LevelSchedule`) of level ``level``, as a :class:`Level`."""
    return Level(sched.inertia[level], sched.inertia_inv[level], sched.bias[level], sched.theta_est[level],
                 sched.omega_est[level], sched.gain[level], sched.theta_ref[level], sched.level_mid[level])


@njit_cached()
def _level_at(sched, level, t):
    """The level in force at t, from ``level`` on: a time at a level start belongs to the new level."""
    while level + 1 < sched.level_start.shape[0] and sched.level_start[level + 1] <= t + 1e-9:
        level += 1
    return level


@njit_cached(fastmath=False, inline="always")
def _torque(X, th2d, lv, loop, w):
    """Controller state x (eq 4.47) into ``w.x``, commanded and delivered torque (eq 5.1,
    saturation) into ``w.u_cmd`` and ``w.u``, saturation flags into ``w.flags``; returns ω × h."""
    x, u, u_cmd, flags = w.x, w.u, w.u_cmd, w.flags
    theta_est, omega_est, gain = lv.theta_est, lv.omega_est, lv.gain
    tmax, hmax = loop.tmax, loop.hmax
    w1, w2, w3 = X[0], X[1], X[2]
    t1, t2, t3 = X[3], X[4], X[5]
    h1, h2, h3 = X[6], X[7], X[8]
    # controller state x of eq 4.47 around the TEA estimate
    x[0] = w1 - omega_est[0]
    x[1] = th2d
    x[2] = w3 - omega_est[2]
    x[3] = t1 - theta_est[0]
    x[4] = t2 - theta_est[1]
    x[5] = t3 - theta_est[2]
    for i in range(6, 24):
        x[i] = X[i]
    for i in range(3):
        acc = 0.0
        for j in range(24):
            acc -= gain[i, j] * x[j]
        u_cmd[i] = acc
        if acc > tmax:
            acc = tmax
            flags[i] = 1.0
        elif acc < -tmax:
            acc = -tmax
            flags[i] = 1.0
        else:
            flags[i] = 0.0
        u[i] = acc
    # CMG momentum saturation: an axis at the limit delivers only the torque that stops |h_i| growing
    wxh0 = w2 * h3 - w3 * h2
    wxh1 = w3 * h1 - w1 * h3
    wxh2 = w1 * h2 - w2 * h1
    wxh = (wxh0, wxh1, wxh2)
    hh = (h1, h2, h3)
    for i in range(3):
        flags[3 + i] = 0.0
        if abs(hh[i]) >= hmax:
            flags[3 + i] = 1.0
            if (u[i] - wxh[i]) * hh[i] > 0.0:
                u[i] = wxh[i]
    return wxh0, wxh1, wxh2


@njit_cached(fastmath=False, inline="always")
def closed_loop_rhs(t, X, lv, loop, out, w):
    """Closed-loop Ẋ at (t, X) into ``out`` (eqs 3.1, 3.5, 3.8, 3.9, 4.35–4.40, 5.1) at the level
    ``lv`` (:class:`Level`); x, u, u_cmd and the flags into ``w`` (:class:`Workspace`).

    Parameters
    ----------
    t : float
        Time, s.
    X : ndarray
        The state (24: body rates rad/s, attitude rad, momentum ft·lbf·s, controller states in
        their units of :func:`acmm.model.linearize.state_units`).
    lv : Level
        The inertia level (its inertia, bias, gain and estimate).
    loop : LoopConstants
        The plant, controller and integrator constants.
    out : ndarray
        Ẋ, written in place (units of X per s).
    w : Workspace
        Scratch buffers, written in place.
    """
    inertia, inertia_inv, bias = lv.inertia, lv.inertia_inv, lv.bias
    ha, hb, n, drf_idx = loop.ha, loop.hb, loop.n, loop.drf_idx
    x, u = w.x, w.u
    w1, w2, w3 = X[0], X[1], X[2]
    t1, t2, t3 = X[3], X[4], X[5]
    h1, h2, h3 = X[6], X[7], X[8]
    s1, c1 = np.sin(t1), np.cos(t1)
    s2, c2 = np.sin(t2), np.cos(t2)
    s3, c3 = np.sin(t3), np.cos(t3)
    # kinematics, eq 3.5/3.6 (corrected)
    d2 = (c1 * w2 - s1 * w3) / c3
    th1d = w1 - s3 * d2
    th2d = d2 + n
    th3d = s1 * w2 + c1 * w3
    wxh0, wxh1, wxh2 = _torque(X, th2d, lv, loop, w)
    # disturbance, eq 3.9
    sn, s2n = np.sin(n * t), np.sin(2.0 * n * t)
    # gravity gradient, eqs 3.3-3.4
    cn0 = -s2 * c3
    cn1 = c1 * s2 * s3 + s1 * c2
    cn2 = -s1 * s2 * s3 + c1 * c2
    ic0 = inertia[0, 0] * cn0 + inertia[0, 1] * cn1 + inertia[0, 2] * cn2
    ic1 = inertia[1, 0] * cn0 + inertia[1, 1] * cn1 + inertia[1, 2] * cn2
    ic2 = inertia[2, 0] * cn0 + inertia[2, 1] * cn1 + inertia[2, 2] * cn2
    k = 3.0 * n * n
    iw0 = inertia[0, 0] * w1 + inertia[0, 1] * w2 + inertia[0, 2] * w3
    iw1 = inertia[1, 0] * w1 + inertia[1, 1] * w2 + inertia[1, 2] * w3
    iw2 = inertia[2, 0] * w1 + inertia[2, 1] * w2 + inertia[2, 2] * w3
    tq0 = -(w2 * iw2 - w3 * iw1) + k * (cn1 * ic2 - cn2 * ic1) + bias[0] + ha[0] * sn + hb[0] * s2n - u[0]
    tq1 = -(w3 * iw0 - w1 * iw2) + k * (cn2 * ic0 - cn0 * ic2) + bias[1] + ha[1] * sn + hb[1] * s2n - u[1]
    tq2 = -(w1 * iw1 - w2 * iw0) + k * (cn0 * ic1 - cn1 * ic0) + bias[2] + ha[2] * sn + hb[2] * s2n - u[2]
    for i in range(3):
        out[i] = inertia_inv[i, 0] * tq0 + inertia_inv[i, 1] * tq1 + inertia_inv[i, 2] * tq2
    out[3] = th1d
    out[4] = th2d
    out[5] = th3d
    out[6] = u[0] - wxh0
    out[7] = u[1] - wxh1
    out[8] = u[2] - wxh2
    out[9:12] = X[6:9]
    # DRFs, eqs 4.35-4.40: d(α̇)/dt = −ω_f² α + input, dα/dt = α̇
    for j in range(6):
        wf = n if j < 3 else 2.0 * n
        out[12 + 2 * j] = -wf * wf * X[13 + 2 * j] + x[drf_idx[j]]
        out[13 + 2 * j] = X[12 + 2 * j]


# Dormand–Prince 5(4) coefficients
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.array([
    [0, 0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
])
_B5 = np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0])
_B4 = np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])
_E = _B5 - _B4


@njit_cached()
def _dp_attempt(X, t, h, lv, loop, w):
    """One Dormand–Prince 5(4) step of length h from (t, X): stages into ``w.K``, the 5th-order
    solution into ``w.y``; returns (RMS of the scaled error estimate, all finite)."""
    nx = 24
    K, y, C, A, B5, E = w.K, w.y, loop.C, loop.A, loop.B5, loop.E
    atol, rtol = loop.atol, loop.rtol
    # stages
    for st in range(7):
        for i in range(nx):
            acc = X[i]
            for j in range(st):
                acc += h * A[st, j] * K[j, i]
            y[i] = acc
        closed_loop_rhs(t + C[st] * h, y, lv, loop, K[st], w)
    # error estimate (RMS of scaled error)
    err = 0.0
    finite = True
    for i in range(nx):
        y5 = X[i]
        e = 0.0
        for j in range(7):
            y5 += h * B5[j] * K[j, i]
            e += h * E[j] * K[j, i]
        y[i] = y5
        sc = atol[i] + rtol * max(abs(X[i]), abs(y5))
        err += (e / sc) ** 2
        if not np.isfinite(y5):
            finite = False
    err = np.sqrt(err / nx)
    return err, finite


@njit_cached()
def _bounds_stop(X, theta_est, loop, step_len, sat_time):
    """Divergence checks after an accepted step: :data:`STOP_ANGLE` (|θ_i − θ̂*_i| above
    ``loop.divergence``), :data:`STOP_SATURATION` (a CMG axis at its limit longer than
    ``loop.max_sat``; it wins over the angle) or :data:`STOP_NONE`; updates the saturation clocks
    ``sat_time``."""
    stop = STOP_NONE
    for i in range(3):
        if abs(X[3 + i] - theta_est[i]) > loop.divergence:
            stop = STOP_ANGLE
        if abs(X[6 + i]) >= loop.hmax * (1.0 - 1e-9):
            sat_time[i] += step_len
            if sat_time[i] > loop.max_sat:
                stop = STOP_SATURATION
        else:
            sat_time[i] = 0.0
    return stop


@njit_cached()
def _track(X, t, level, lv, run_mid, out, flags, step_len):
    """Extremes at every accepted step (not only at the output samples) into ``out``
    (:class:`KernelOutputs`).  Per level: peak max_i |h_i|, and max |θ_i − θ̂*_i| from the middle
    of its dwell on.  Over the run (``out.run``): peak |h_i|, peak |θ_i − θ_ref,i| and the same
    from ``run_mid`` on, per axis; then the time with any axis torque-saturated and any axis
    momentum-saturated (the step's end state)."""
    peak_h, steady, run = out.peak_h, out.steady, out.run
    hm = max(abs(X[6]), abs(X[7]), abs(X[8]))
    if not (peak_h[level] >= hm):          # NaN (not reached yet) or smaller
        peak_h[level] = hm
    for i in range(3):
        e = abs(X[3 + i] - lv.theta_est[i])
        if t >= lv.mid - 1e-9 and not (steady[level, i] >= e):
            steady[level, i] = e
        a = abs(X[6 + i])
        if not (run[i] >= a):
            run[i] = a
        e = abs(X[3 + i] - lv.theta_ref[i])
        if not (run[3 + i] >= e):
            run[3 + i] = e
        if t >= run_mid - 1e-9 and not (run[6 + i] >= e):
            run[6 + i] = e
    if flags[0] > 0.0 or flags[1] > 0.0 or flags[2] > 0.0:
        run[9] += step_len
    if flags[3] > 0.0 or flags[4] > 0.0 or flags[5] > 0.0:
        run[10] += step_len


@njit_cached()
def _window_entry(X0, K, X1, t0, h, mid, ref, worst):
    """Where the step (t0, X0) → (t0 + h, X1) crosses ``mid`` (a window of :func:`_track` opens),
    |θ_i(mid) − ref_i| into ``worst`` (max), θ(mid) by the cubic Hermite interpolant of the
    step's end states and slopes (``K[0]``, ``K[6]``: Dormand–Prince's first and last stage), so
    that a window does not open only at the first step end after ``mid``."""
    if not (t0 < mid - 1e-9 and mid < t0 + h - 1e-9):
        return
    s = (mid - t0) / h
    h00, h10 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s
    h01, h11 = -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
    for i in range(3):
        th = h00 * X0[3 + i] + h10 * h * K[0, 3 + i] + h01 * X1[3 + i] + h11 * h * K[6, 3 + i]
        e = abs(th - ref[i])
        if not (worst[i] >= e):
            worst[i] = e


@njit_cached()
def _record(out, s, t, X, lv, loop, level, w):
    """Sample ``s`` of ``out`` (:class:`KernelOutputs`): the state X at t, the torques and
    saturation flags of the closed loop there (:func:`closed_loop_rhs` at the level ``lv``) and the level in
    force."""
    closed_loop_rhs(t, X, lv, loop, w.y, w)
    out.state[s] = X
    out.u[s] = w.u
    out.u_cmd[s] = w.u_cmd
    out.flags[s] = w.flags
    out.level[s] = level


@njit_cached()
def _integrate(sample_times, x0, sched, loop, out):
    """Integrate the closed loop from (sample_times[0] s, plain state x0) by adaptive Dormand–Prince
    5(4) steps into ``out``, sampling at every ``sample_times`` (s; they include every level start,
    so no step crosses one), until the last or a stop: (last sample index, ``STOP_*`` code of
    :mod:`acmm.simulate.scenario`, time reached s, accepted steps, rejected steps)."""
    X = x0.copy()
    w = _workspace()
    t = sample_times[0]
    dt = 10.0
    n_steps, n_rej, stop = 0, 0, STOP_NONE
    # sample 0, at level 0 (an int64, not the literal 0, for which numba would compile each helper
    # once more)
    first = level = np.int64(0)
    lv = _level(sched, level)
    _record(out, first, t, X, lv, loop, level, w)
    _track(X, t, level, lv, sched.run_mid, out, w.flags, 0.0)
    last = 0
    for s in range(1, sample_times.shape[0]):
        t_target = sample_times[s]
        level = _level_at(sched, level, t)
        lv = _level(sched, level)
        while t < t_target - 1e-9:
            h = min(dt, t_target - t)
            err, finite = _dp_attempt(X, t, h, lv, loop, w)
            if not finite:
                stop = STOP_NONFINITE
                break
            if err <= 1.0:
                # accept
                _window_entry(X, w.K, w.y, t, h, lv.mid, lv.theta_est, out.steady[level])
                _window_entry(X, w.K, w.y, t, h, sched.run_mid, lv.theta_ref, out.run[6:9])
                t += h
                X[:] = w.y
                n_steps += 1
                _track(X, t, level, lv, sched.run_mid, out, w.flags, h)
                fac = 0.9 * err ** (-0.2) if err > 0 else 5.0
                dt = h * min(5.0, max(0.2, fac))
                stop = _bounds_stop(X, lv.theta_est, loop, h, w.sat_time)
                if stop != STOP_NONE:
                    break
            else:
                n_rej += 1
                dt = h * max(0.1, 0.9 * err ** (-0.25))
                if dt < 1e-6:
                    stop = STOP_STEP
                    break
        # record the sample (the last state reached, also when stopping) with the level in force
        # from t on: a sample at a level start belongs to the new level
        level = _level_at(sched, level, t)
        lv = _level(sched, level)
        _record(out, s, t, X, lv, loop, level, w)
        last = s
        if stop != STOP_NONE:
            break
    return last, stop, t, n_steps, n_rej


def _schedule(sc: Scenario) -> LevelSchedule:
    """The per-level arrays of ``sc`` for the kernel (contiguous float64)."""
    L = sc.level_start.shape[0]
    level_start = np.ascontiguousarray(sc.level_start, float)
    inertia = np.ascontiguousarray(sc.inertia, float)
    omega_est = np.array([kin.lvlh_rate_in_body(th, sc.n) for th in sc.theta_est]).reshape(L, 3)
    ends = np.append(np.asarray(sc.level_start, float)[1:], sc.t_end)
    theta_ref = np.ascontiguousarray(sc.theta_est if sc.theta_ref is None else sc.theta_ref, float)
    return LevelSchedule(level_start=level_start, level_mid=0.5 * (np.asarray(sc.level_start, float) + ends),
                         inertia=inertia, inertia_inv=np.linalg.inv(inertia),
                         bias=np.ascontiguousarray(sc.bias, float),
                         theta_est=np.ascontiguousarray(sc.theta_est, float), omega_est=omega_est,
                         gain=np.ascontiguousarray(sc.gain, float), theta_ref=theta_ref.reshape(L, 3),
                         run_mid=0.5 * float(sc.t_end))


def _loop_constants(sc: Scenario) -> LoopConstants:
    """The plant, controller and integrator constants of ``sc`` for the kernel (its units)."""
    return LoopConstants(ha=np.asarray(sc.harmonic_a, float), hb=np.asarray(sc.harmonic_b, float), n=float(sc.n),
                         tmax=float(sc.torque_limit), hmax=float(sc.momentum_limit),
                         drf_idx=np.array(DRF_INPUTS[sc.drf_mode] * 2, dtype=np.int64),
                         rtol=float(sc.rtol), atol=np.asarray(sc.atol, float),
                         divergence=float(sc.divergence), max_sat=float(sc.max_saturation),
                         C=_C, A=_A, B5=_B5, E=_E)


def simulate(sc: Scenario) -> SimResult:
    """Integrate a :class:`Scenario`; stops early (a result, not an error) on divergence.

    The closed loop of eqs 3.1, 3.5, 3.8, 3.9 and 5.1 with saturation (ch. 5.1,
    ``docs/ERRATA.md`` § Saturation).

    Parameters
    ----------
    sc : Scenario
        Plant, gains, disturbance and integration settings, as arrays (units in
        :class:`Scenario`).

    Returns
    -------
    SimResult
        Sampled trajectory (up to the stop) and verdict.
    """
    # samples NaN (flags 0) until written, extremes NaN until reached, the saturation times 0
    S, L = sc.sample_times.shape[0], sc.level_start.shape[0]
    out = KernelOutputs(state=np.full((S, 24), np.nan), u_cmd=np.full((S, 3), np.nan), u=np.full((S, 3), np.nan),
                        flags=np.zeros((S, 6)), level=np.zeros(S, dtype=np.int64), peak_h=np.full(L, np.nan),
                        steady=np.full((L, 3), np.nan), run=np.append(np.full(9, np.nan), np.zeros(2)))
    last, stop, t_stop, n_steps, n_rej = _integrate(
        np.ascontiguousarray(sc.sample_times, float), np.asarray(sc.x0, float), _schedule(sc),
        _loop_constants(sc), out)
    k = last + 1
    t = sc.sample_times[:k].copy()
    if stop != STOP_NONE:
        t[-1] = t_stop
    w = np.asarray(sc.bias)[out.level[:k]] + dyn.disturbance_torque(t, 0.0, sc.harmonic_a, sc.harmonic_b, sc.n)
    run = out.run
    return SimResult(t=t, state=out.state[:k], u_cmd=out.u_cmd[:k], u=out.u[:k], w=w,
                     level=out.level[:k], torque_saturated=out.flags[:k, :3] > 0,
                     momentum_saturated=out.flags[:k, 3:] > 0, stop_code=int(stop),
                     stop_time=float(t_stop), n_steps=int(n_steps), n_rejected=int(n_rej),
                     level_peak_momentum=out.peak_h, level_steady_error=out.steady,
                     run_extremes=RunExtremes(run[0:3], run[3:6], run[6:9], run[9], run[10]))


def kernel_rhs(sc: Scenario, t: float, X: np.ndarray, level: int = 0):
    """The compiled right-hand side at one state: returns (Ẋ, u delivered, u commanded).

    Parameters
    ----------
    sc : Scenario
        The closed loop (units in :class:`Scenario`).
    t : float
        Time, s.
    X : (24,) array
        Plain state, in the units listed in the module docstring.
    level : int
        Index of the inertia level in force.

    Returns
    -------
    X_dot : (24,) array
        Ẋ, in the units of X per second.
    u : (3,) array
        Torque delivered after saturation, ft·lbf.
    u_cmd : (3,) array
        Commanded torque −K x (eq 5.1), ft·lbf.
    """
    # one level's rows only (the whole schedule costs ~0.1 ms a call, and solve_ivp calls often);
    # closed_loop_rhs reads neither theta_ref nor mid
    inertia = np.ascontiguousarray(sc.inertia[level], float)
    theta_est = np.ascontiguousarray(sc.theta_est[level], float)
    lv = Level(inertia=inertia, inertia_inv=np.linalg.inv(inertia), bias=np.ascontiguousarray(sc.bias[level], float),
               theta_est=theta_est, omega_est=np.ascontiguousarray(kin.lvlh_rate_in_body(theta_est, sc.n), float),
               gain=np.ascontiguousarray(sc.gain[level], float), theta_ref=theta_est, mid=0.0)
    w = _workspace()
    out = np.empty(24)
    closed_loop_rhs(t, np.asarray(X, float), lv, _loop_constants(sc), out, w)
    return out, w.u.copy(), w.u_cmd.copy()
