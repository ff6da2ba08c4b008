"""Nonlinear closed-loop simulation of the ACMM law (CR-185644 ch. 6).

Plant: eqs 3.1, 3.5, 3.8 with the disturbance of eq 3.9 (per-level bias).  Controller: the
integral ∫h and the twelve DRF states (eqs 4.35–4.40, fed by deviations) are integrated with
the plant; u = −K(θ̂*)·x (eq 5.1) with x of eq 4.47 built from the nonlinear state around the
current TEA estimate θ̂* (θ̇2 from the nonlinear kinematics).  Saturation (ch. 5.1,
``docs/ERRATA.md`` § Saturation):
the commanded torque is clipped to ±torque_limit per axis; a CMG axis at |h_i| ≥ momentum_limit
delivers only the torque that stops |h_i| growing, and the body receives exactly the torque the
CMG absorbs, so I ω̇ + ḣ + ω×(Iω + h) = τ_gg + w holds along every trajectory.

The integrator is an adaptive Dormand–Prince 5(4) pair compiled with numba (``cache=True``: the
one-time compilation is reused across runs).  :func:`rhs_numpy` (in :mod:`acmm.simulate.reference`) is a plain-numpy right-hand side of the same model built from
:mod:`acmm.model.dynamics`, used as the independent reference and as the ``solve_ivp`` baseline of
``make bench``.

Integrated state X (24): ω (rad/s), θ (rad), h (ft·lbf·s), ∫h (ft·lbf·s²), DRF states
(α̇1, α1, α̇2, α2, α̇3, α3, β̇1, β1, β̇2, β2, β̇3, β3).
"""
from __future__ import annotations

import numpy as np

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin
from acmm.simulate.compiled_cache import njit_cached
from acmm.model.linearize import DRF_INPUTS
from acmm.simulate.scenario import STOP_NONE, RunExtremes, Scenario, SimResult


# ----------------------------------------------------------------------------------------------
# compiled kernel
# ----------------------------------------------------------------------------------------------
@njit_cached(fastmath=False)
def _torque(X, th2d, theta_est, omega_est, gain, tmax, hmax, ucmd_out, u_out, flags, x, u):
    """Controller state x (eq 4.47) into ``x``, commanded and delivered torque (eq 5.1, saturation)
    into ``ucmd_out``, ``u_out`` and ``u``; returns ω × h."""
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
        ucmd_out[i] = acc
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
        u_out[i] = u[i]
    return wxh0, wxh1, wxh2


@njit_cached(fastmath=False)
def _rhs(t, X, inertia, inertia_inv, bias, theta_est, omega_est, gain, ha, hb, n,
         tmax, hmax, drf_idx, out, u_out, ucmd_out, flags, x, u):
    """Closed-loop Ẋ into ``out``; ``x`` (24) and ``u`` (3) are scratch buffers."""
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
    wxh0, wxh1, wxh2 = _torque(X, th2d, theta_est, omega_est, gain, tmax, hmax, ucmd_out, u_out,
                               flags, x, u)
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
    out[9] = h1
    out[10] = h2
    out[11] = h3
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
def _dp_attempt(X, t, h, Il, Iil, bl, tl, ol, gl, ha, hb, n, tmax, hmax, drf_idx, rtol, atol,
                C, A, B5, E, K, tmp, u, ucmd, flags, xs, us):
    """One Dormand–Prince 5(4) step of length h from (t, X): stages into ``K``, the 5th-order
    solution into ``tmp``; returns (RMS of the scaled error estimate, all finite)."""
    nx = 24
    # stages
    for st in range(7):
        for i in range(nx):
            acc = X[i]
            for j in range(st):
                acc += h * A[st, j] * K[j, i]
            tmp[i] = acc
        _rhs(t + C[st] * h, tmp, Il, Iil, bl, tl, ol, gl, ha, hb, n, tmax, hmax, drf_idx,
             K[st], u, ucmd, flags, xs, us)
    # error estimate (RMS of scaled error)
    err = 0.0
    finite = True
    for i in range(nx):
        y5 = X[i]
        e = 0.0
        for j in range(7):
            y5 += h * B5[j] * K[j, i]
            e += h * E[j] * K[j, i]
        tmp[i] = y5
        sc = atol[i] + rtol * max(abs(X[i]), abs(y5))
        err += (e / sc) ** 2
        if not np.isfinite(y5):
            finite = False
    err = np.sqrt(err / nx)
    return err, finite


@njit_cached()
def _bounds_stop(X, tl, divergence, hmax, max_sat, step_len, sat_time):
    """Divergence checks after an accepted step: 1 (attitude bound), 2 (saturated too long) or 0;
    updates the saturation clocks ``sat_time``."""
    stop = 0
    for i in range(3):
        if abs(X[3 + i] - tl[i]) > divergence:
            stop = 1
        if abs(X[6 + i]) >= hmax * (1.0 - 1e-9):
            sat_time[i] += step_len
            if sat_time[i] > max_sat:
                stop = 2
        else:
            sat_time[i] = 0.0
    return stop


@njit_cached()
def _track(X, t, level, tl, rl, level_mid, run_mid, peak_h, steady, run, flags, step_len):
    """Extremes at every accepted step (not only at the output samples).  Per level: peak
    max_i |h_i|, and max |θ_i − θ̂*_i| from the middle of its dwell on.  Over the run (``run``):
    peak |h_i|, peak |θ_i − θ_ref,i| and the same from ``run_mid`` on, per axis; then the time
    with any axis torque-saturated and any axis momentum-saturated (the step's end state)."""
    hm = max(abs(X[6]), abs(X[7]), abs(X[8]))
    if not (peak_h[level] >= hm):          # NaN (not reached yet) or smaller
        peak_h[level] = hm
    for i in range(3):
        e = abs(X[3 + i] - tl[i])
        if t >= level_mid[level] - 1e-9 and not (steady[level, i] >= e):
            steady[level, i] = e
        a = abs(X[6 + i])
        if not (run[i] >= a):
            run[i] = a
        e = abs(X[3 + i] - rl[i])
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
def _integrate(sample_times, level_start, inertia, inertia_inv, bias, theta_est, omega_est, gain,
               ha, hb, n, tmax, hmax, drf_idx, x0, rtol, atol, divergence, max_sat,
               C, A, B5, E, out_state, out_ucmd, out_u, out_flags, out_level,
               level_mid, out_peak_h, out_steady, theta_ref, run_mid, out_run):
    nx = 24
    L = level_start.shape[0]
    X = x0.copy()
    K = np.empty((7, nx))
    tmp = np.empty(nx)
    u, ucmd, us = np.empty(3), np.empty(3), np.empty(3)
    flags = np.zeros(6)
    xs = np.empty(24)
    sat_time = np.zeros(3)
    t = sample_times[0]
    dt = 10.0
    n_steps, n_rej, stop, level = 0, 0, 0, 0
    # record the first sample
    _rhs(t, X, inertia[0], inertia_inv[0], bias[0], theta_est[0], omega_est[0], gain[0], ha, hb,
         n, tmax, hmax, drf_idx, tmp, u, ucmd, flags, xs, us)
    out_state[0] = X
    out_u[0] = u
    out_ucmd[0] = ucmd
    out_flags[0] = flags
    out_level[0] = 0
    _track(X, t, 0, theta_est[0], theta_ref[0], level_mid, run_mid, out_peak_h, out_steady, out_run, flags, 0.0)
    n_samples = sample_times.shape[0]
    last = 0
    for s in range(1, n_samples):
        t_target = sample_times[s]
        while level + 1 < L and level_start[level + 1] <= t + 1e-9:
            level += 1
        Il, Iil, bl = inertia[level], inertia_inv[level], bias[level]
        tl, ol, gl, rl = theta_est[level], omega_est[level], gain[level], theta_ref[level]
        while t < t_target - 1e-9:
            h = min(dt, t_target - t)
            err, finite = _dp_attempt(X, t, h, Il, Iil, bl, tl, ol, gl, ha, hb, n, tmax, hmax, drf_idx,
                                      rtol, atol, C, A, B5, E, K, tmp, u, ucmd, flags, xs, us)
            if not finite:
                stop = 3
                break
            if err <= 1.0:
                # accept
                step_len = h
                _window_entry(X, K, tmp, t, h, level_mid[level], tl, out_steady[level])
                _window_entry(X, K, tmp, t, h, run_mid, rl, out_run[6:9])
                t += h
                for i in range(nx):
                    X[i] = tmp[i]
                n_steps += 1
                _track(X, t, level, tl, rl, level_mid, run_mid, out_peak_h, out_steady, out_run, flags, step_len)
                fac = 0.9 * err ** (-0.2) if err > 0 else 5.0
                dt = h * min(5.0, max(0.2, fac))
                stop = _bounds_stop(X, tl, divergence, hmax, max_sat, step_len, sat_time)
                if stop != 0:
                    break
            else:
                n_rej += 1
                dt = h * max(0.1, 0.9 * err ** (-0.25))
                if dt < 1e-6:
                    stop = 4
                    break
        # record the sample (the last state reached, also when stopping) with the level in force
        # from t on: a sample at a level start belongs to the new level
        while level + 1 < L and level_start[level + 1] <= t + 1e-9:
            level += 1
        Il, Iil, bl = inertia[level], inertia_inv[level], bias[level]
        tl, ol, gl = theta_est[level], omega_est[level], gain[level]
        _rhs(t, X, Il, Iil, bl, tl, ol, gl, ha, hb, n, tmax, hmax, drf_idx, tmp, u, ucmd, flags, xs, us)
        out_state[s] = X
        out_u[s] = u
        out_ucmd[s] = ucmd
        out_flags[s] = flags
        out_level[s] = level
        last = s
        if stop != 0:
            break
    return last, stop, t, n_steps, n_rej


def _drf_index(drf_mode: str) -> np.ndarray:
    """Index in x (eq 4.47) of the input of each of the six DRFs (n filters, then 2n)."""
    return np.array([DRF_INPUTS[drf_mode][j % 3] for j in range(6)], dtype=np.int64)


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
    L = sc.level_start.shape[0]
    inertia = np.ascontiguousarray(sc.inertia, float)
    inertia_inv = np.linalg.inv(inertia)
    omega_est = np.array([kin.lvlh_rate_in_body(th, sc.n) for th in sc.theta_est]).reshape(L, 3)
    drf_idx = _drf_index(sc.drf_mode)
    S = sc.sample_times.shape[0]
    out_state = np.full((S, 24), np.nan)
    out_ucmd = np.full((S, 3), np.nan)
    out_u = np.full((S, 3), np.nan)
    out_flags = np.zeros((S, 6))
    out_level = np.zeros(S, dtype=np.int64)
    ends = np.append(np.asarray(sc.level_start, float)[1:], sc.t_end)
    level_mid = 0.5 * (np.asarray(sc.level_start, float) + ends)
    out_peak_h = np.full(L, np.nan)
    out_steady = np.full((L, 3), np.nan)
    out_run = np.append(np.full(9, np.nan), np.zeros(2))
    theta_ref = np.ascontiguousarray(sc.theta_est if sc.theta_ref is None else sc.theta_ref, float)
    last, stop, t_stop, n_steps, n_rej = _integrate(
        np.ascontiguousarray(sc.sample_times, float), np.ascontiguousarray(sc.level_start, float),
        inertia, inertia_inv, np.ascontiguousarray(sc.bias, float),
        np.ascontiguousarray(sc.theta_est, float), omega_est, np.ascontiguousarray(sc.gain, float),
        np.asarray(sc.harmonic_a, float), np.asarray(sc.harmonic_b, float), float(sc.n),
        float(sc.torque_limit), float(sc.momentum_limit), drf_idx, np.asarray(sc.x0, float),
        float(sc.rtol), np.asarray(sc.atol, float), float(sc.divergence), float(sc.max_saturation),
        _C, _A, _B5, _E, out_state, out_ucmd, out_u, out_flags, out_level,
        level_mid, out_peak_h, out_steady, theta_ref.reshape(L, 3), 0.5 * float(sc.t_end), out_run)
    k = last + 1
    t = sc.sample_times[:k].copy()
    if stop != STOP_NONE:
        t[-1] = t_stop
    w = np.asarray(sc.bias)[out_level[:k]] + dyn.disturbance_torque(t, 0.0, sc.harmonic_a, sc.harmonic_b, sc.n)
    return SimResult(t=t, state=out_state[:k], u_cmd=out_ucmd[:k], u=out_u[:k], w=w,
                     level=out_level[:k], torque_saturated=out_flags[:k, :3] > 0,
                     momentum_saturated=out_flags[:k, 3:] > 0, stop_code=int(stop),
                     stop_time=float(t_stop), n_steps=int(n_steps), n_rejected=int(n_rej),
                     level_peak_momentum=out_peak_h, level_steady_error=out_steady,
                     run_extremes=RunExtremes(out_run[0:3], out_run[3:6], out_run[6:9], out_run[9], out_run[10]))
