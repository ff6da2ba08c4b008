"""Compiled TEA continuations for sweeps (issue 16): :func:`acmm.model.tea.solve_tea`'s algorithm in numba.

A Monte Carlo case of a sweep re-solves the perturbed plant's TEA (eqs 4.1–4.3).  The
continuation of :func:`acmm.model.tea.solve_tea` (diagonal body at LVLH → products of inertia →
bias) takes ~80 damped Newton iterations on 3-vectors, i.e. ~30 ms of numpy call overhead, several
times the 10-orbit closed-loop integration itself.  This module runs the *same* continuation
— same path, same step control (first step 0.05, ×1.5 up to 0.1 on success, halved on failure,
fold below 1e-7), same acceptance tests (Newton converged to the residual tolerance, jump
≤ 5°, unchanged sign of det ∂r/∂θ), same Newton (damped to 0.5 rad, |θ| < 89.5°), same fold bisection — compiled, in
~0.1–0.5 ms.

A sweep case's plant, though, is a perturbation of the plant the controller was designed for, so its
TEA is the equilibrium *connected to the design TEA*
(:func:`acmm.model.tea_compiled.solve_tea_connected`: the same continuation, from the design TEA along
the straight line from the nominal plant to the perturbed one; a few steps, median 0.14 ms on MB3; a
branch that folds ~1 ms before the fallback), with two differences: only yaw is boxed at ±89.5° (the
singular angle of the 2-3-1 sequence), and on a path exactly symmetric about the orbit plane (no
I12, I23, roll or yaw bias; roll = yaw = 0) a step across which det ∂r/∂θ changes sign is accepted
when ∂r2/∂θ2 keeps its sign and the trapezoidal rule of the branch's tangents reproduces it
(:func:`_smooth_step`): a pitchfork, through which the branch goes on, rather than a jump between
the two roots of a fold (a nearly symmetric station has such a fold there, and it is one).  The root
the continuation from LVLH reaches is not that one for a nearly planar body: for MB3 (I11 ≈ I33) a
0.5 % smaller I33 flips it from −44.7° to +41.8° pitch, while the design TEA's equilibrium moves to
−48.2°; in the packaged ±30 % Monte Carlo 95 of MB3's 200 cases had the LVLH root on the other
principal alignment.  A plain Newton step from the nominal TEA is not used either: on such plants it
may land on a root of another branch.  Where the design TEA's branch folds before the perturbed
plant (AC: 102 of 200 cases, as I33 − I11 shrinks; 21 of them have no root continued from LVLH
either), the sweep falls back to :func:`solve_tea_fast`, the continuation from LVLH
(:mod:`acmm.model.tea`'s physical branch).

The arithmetic is written out in scalars (closed-form residual and Jacobian, 3×3 Gaussian
elimination with partial pivoting), so results agree with :func:`acmm.model.tea.solve_tea` to
round-off (≤ 1e-13 rad), not bit for bit; they are deterministic (the same inputs give the same
bits in every process, executor and chunking).  A fold raises the error :func:`acmm.model.tea.solve_tea`
raises, with the same message; every root is re-checked with the numpy residual of
:mod:`acmm.model.tea` and :func:`acmm.model.tea.solve_tea` is the fallback if the check fails.
"""
from __future__ import annotations

import math

import numpy as np

from acmm.model.compiled_cache import njit_cached
from acmm.model.tea import (RESIDUAL_TOL, TEA, equilibrium_residual, fold_message, make_tea, residual_threshold,
                             solve_tea)
from acmm_qpp.errors import NoEquilibriumError

_MAX_JUMP = math.radians(5.0)
_THETA_LIMIT = math.radians(89.5)


@njit_cached()
def _mv(a, v):
    out = np.empty(3)
    for i in range(3):
        out[i] = a[i, 0] * v[0] + a[i, 1] * v[1] + a[i, 2] * v[2]
    return out


@njit_cached()
def _residual_jac(th, inertia, n, bias, r, jac, want_jac):
    """r = τ_gyro(ω*(θ)) + τ_gg(θ) + bias (ft·lbf) and, with ``want_jac``, ∂r/∂θ (eq 4.1, 4.3)."""
    s1, s2, s3 = math.sin(th[0]), math.sin(th[1]), math.sin(th[2])
    c1, c2, c3 = math.cos(th[0]), math.cos(th[1]), math.cos(th[2])
    # ω* = C_BL (0, −n, 0), eq 4.3
    w = np.empty(3)
    w[0] = -n * s3
    w[1] = -n * c1 * c3
    w[2] = n * s1 * c3
    # nadir vector c, eq 3.4
    c = np.empty(3)
    c[0] = -s2 * c3
    c[1] = c1 * s2 * s3 + s1 * c2
    c[2] = -s1 * s2 * s3 + c1 * c2
    iw = _mv(inertia, w)
    ic = _mv(inertia, c)
    k = 3.0 * n * n
    r[0] = -(w[1] * iw[2] - w[2] * iw[1]) + k * (c[1] * ic[2] - c[2] * ic[1]) + bias[0]
    r[1] = -(w[2] * iw[0] - w[0] * iw[2]) + k * (c[2] * ic[0] - c[0] * ic[2]) + bias[1]
    r[2] = -(w[0] * iw[1] - w[1] * iw[0]) + k * (c[0] * ic[1] - c[1] * ic[0]) + bias[2]
    if not want_jac:
        return
    # ∂ω*/∂θ
    dw = np.zeros((3, 3))
    dw[0, 2] = -n * c3
    dw[1, 0] = n * s1 * c3
    dw[1, 2] = n * c1 * s3
    dw[2, 0] = n * c1 * c3
    dw[2, 2] = -n * s1 * s3
    # ∂τ_gyro/∂ω = [(Iω)×] − [ω×] I
    gj = np.empty((3, 3))
    for j in range(3):
        gj[0, j] = -(w[1] * inertia[2, j] - w[2] * inertia[1, j])
        gj[1, j] = -(w[2] * inertia[0, j] - w[0] * inertia[2, j])
        gj[2, j] = -(w[0] * inertia[1, j] - w[1] * inertia[0, j])
    gj[0, 1] += -iw[2]
    gj[0, 2] += iw[1]
    gj[1, 0] += iw[2]
    gj[1, 2] += -iw[0]
    gj[2, 0] += -iw[1]
    gj[2, 1] += iw[0]
    # ∂c/∂θ: columns d_k
    d = np.empty((3, 3))
    d[0, 0], d[1, 0], d[2, 0] = 0.0, -s1 * s2 * s3 + c1 * c2, -c1 * s2 * s3 - s1 * c2
    d[0, 1], d[1, 1], d[2, 1] = -c2 * c3, c1 * c2 * s3 - s1 * s2, -s1 * c2 * s3 - c1 * s2
    d[0, 2], d[1, 2], d[2, 2] = s2 * s3, c1 * s2 * c3, -s1 * s2 * c3
    for kk in range(3):
        idk = _mv(inertia, d[:, kk])
        # d_k × Ic + c × I d_k
        g0 = d[1, kk] * ic[2] - d[2, kk] * ic[1] + c[1] * idk[2] - c[2] * idk[1]
        g1 = d[2, kk] * ic[0] - d[0, kk] * ic[2] + c[2] * idk[0] - c[0] * idk[2]
        g2 = d[0, kk] * ic[1] - d[1, kk] * ic[0] + c[0] * idk[1] - c[1] * idk[0]
        jac[0, kk] = k * g0
        jac[1, kk] = k * g1
        jac[2, kk] = k * g2
    for i in range(3):
        for j in range(3):
            jac[i, j] += gj[i, 0] * dw[0, j] + gj[i, 1] * dw[1, j] + gj[i, 2] * dw[2, j]


@njit_cached()
def _det3(a):
    return (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
            - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
            + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))


@njit_cached()
def _solve3(a, b, x):
    """x = a⁻¹ b by Gaussian elimination with partial pivoting; False when singular."""
    m = a.copy()
    v = b.copy()
    for col in range(3):
        p = col
        for i in range(col + 1, 3):
            if abs(m[i, col]) > abs(m[p, col]):
                p = i
        if m[p, col] == 0.0:
            return False
        if p != col:
            for j in range(3):
                m[col, j], m[p, j] = m[p, j], m[col, j]
            v[col], v[p] = v[p], v[col]
        for i in range(col + 1, 3):
            f = m[i, col] / m[col, col]
            for j in range(col, 3):
                m[i, j] -= f * m[col, j]
            v[i] -= f * v[col]
    for i in range(2, -1, -1):
        acc = v[i]
        for j in range(i + 1, 3):
            acc -= m[i, j] * x[j]
        x[i] = acc / m[i, i]
    return True


@njit_cached()
def _newton(theta0, inertia, n, bias, tol, max_iter, max_step, out, yaw_only=False):
    """Damped Newton on eq 4.1 from ``theta0``; the root in ``out``, True when converged.

    An iterate beyond 89.5° fails: in any angle (as :mod:`acmm.model.tea`), or with ``yaw_only`` in yaw
    θ3 alone, the one singular angle of the 2-3-1 sequence."""
    th = theta0.copy()
    amax = 0.0
    for i in range(3):
        for j in range(3):
            amax = max(amax, abs(inertia[i, j]))
    scale = max(3.0 * n * n * amax, 1e-300)
    thr = max(min(tol, 1e-13 * scale), 1e-15 * scale)          # acmm.model.tea.residual_threshold
    r = np.empty(3)
    jac = np.empty((3, 3))
    step = np.empty(3)
    for _ in range(max_iter):
        _residual_jac(th, inertia, n, bias, r, jac, True)
        if max(abs(r[0]), abs(r[1]), abs(r[2])) <= thr:
            out[:] = th
            return True
        if not _solve3(jac, -r, step):
            return False
        norm = 0.0
        for i in range(3):
            if not np.isfinite(step[i]):
                return False
            norm = max(norm, abs(step[i]))
        if norm > max_step:
            for i in range(3):
                step[i] *= max_step / norm
        for i in range(3):
            th[i] += step[i]
        if abs(th[2]) > _THETA_LIMIT or (not yaw_only and max(abs(th[0]), abs(th[1])) > _THETA_LIMIT):
            return False
    _residual_jac(th, inertia, n, bias, r, jac, False)
    if max(abs(r[0]), abs(r[1]), abs(r[2])) <= thr:
        out[:] = th
        return True
    return False


@njit_cached()
def _continue(theta, i0, i1, b0, b1, n, tol, min_step, connected=False):
    """Follow θ(λ) along I = i0 + λ(i1 − i0), bias = b0 + λ(b1 − b0) from λ = 0 to 1.

    Returns (θ, λ reached, folded) with the step control of :func:`acmm.model.tea._continue`.  With
    ``connected`` (:func:`acmm.model.tea_compiled.solve_tea_connected`) Newton is boxed in yaw only, and
    on a path exactly symmetric about the orbit plane (:func:`_symmetric_path`) a step across
    which det ∂r/∂θ changes sign is accepted when ∂r2/∂θ2 keeps its sign and the step is smooth
    (:func:`_smooth_step`): the branch passes a pitchfork (the roll/yaw stiffness changes sign),
    not a fold.  A nearly symmetric station has a fold there instead, and it is treated as one.
    """
    lam, step = 0.0, 0.05
    jac = np.empty((3, 3))
    r = np.empty(3)
    _residual_jac(theta, i0, n, b0, r, jac, True)
    det0 = np.sign(_det3(jac))
    pitch0 = np.sign(jac[1, 1])
    symmetric = connected and _symmetric_path(theta, i0, i1, b0, b1)
    new = np.empty(3)
    th = theta.copy()
    while lam < 1.0:
        trial = min(1.0, lam + step)
        inertia = i0 + trial * (i1 - i0)
        bias = b0 + trial * (b1 - b0)
        ok = _newton(th, inertia, n, bias, tol, 50, 0.5, new, connected)
        if ok:
            jump = 0.0
            for i in range(3):
                jump = max(jump, abs(new[i] - th[i]))
            ok = jump <= _MAX_JUMP
        if ok:
            _residual_jac(new, inertia, n, bias, r, jac, True)
            det = np.sign(_det3(jac))
            if (det != det0 and symmetric and np.sign(jac[1, 1]) == pitch0 and new[0] == 0.0
                    and new[2] == 0.0 and _smooth_step(th, new, lam, trial, i0, i1, b0, b1, n)):
                det0 = det
            ok = det == det0
        if ok:
            th[:] = new
            lam = trial
            step = min(step * 1.5, 0.1)
        else:
            step *= 0.5
            if step < min_step:
                return th, lam, True
    return th, lam, False


@njit_cached()
def _symmetric_path(theta, i0, i1, b0, b1):
    """Whether the path of :func:`_continue` stays exactly in the plane-symmetric subspace: no
    I12, I23, roll or yaw bias in either plant, and θ1 = θ3 = 0 (Newton keeps them exactly 0)."""
    return (theta[0] == 0.0 and theta[2] == 0.0 and i0[0, 1] == 0.0 and i0[1, 2] == 0.0
            and i1[0, 1] == 0.0 and i1[1, 2] == 0.0 and b0[0] == 0.0 and b0[2] == 0.0
            and b1[0] == 0.0 and b1[2] == 0.0)


@njit_cached()
def _tangent(th, lam, i0, i1, b0, b1, n, out):
    """dθ/dλ = −(∂r/∂θ)⁻¹ ∂r/∂λ on the path of :func:`_continue`; r is linear in the inertia and
    the bias, so ∂r/∂λ is r of the difference plant (i1 − i0, b1 − b0)."""
    r = np.empty(3)
    jac = np.empty((3, 3))
    _residual_jac(th, i0 + lam * (i1 - i0), n, b0 + lam * (b1 - b0), r, jac, True)
    _residual_jac(th, i1 - i0, n, b1 - b0, r, np.empty((3, 3)), False)
    return _solve3(jac, -r, out)


@njit_cached()
def _smooth_step(th, new, lam, trial, i0, i1, b0, b1, n):
    """Whether the step θ(λ) → θ(trial) follows one smooth branch: the trapezoidal rule of the
    tangents at both ends reproduces it to 5 % (at a fold the two roots' tangents point apart)."""
    ta = np.empty(3)
    tb = np.empty(3)
    if not (_tangent(th, lam, i0, i1, b0, b1, n, ta) and _tangent(new, trial, i0, i1, b0, b1, n, tb)):
        return False
    h = trial - lam
    err = 0.0
    size = 0.0
    for i in range(3):
        err = max(err, abs(new[i] - th[i] - 0.5 * h * (ta[i] + tb[i])))
        size = max(size, abs(new[i] - th[i]))
    return err <= 0.05 * size + 1e-12


@njit_cached()
def _fold_location(theta, lam, inertia, n, bias, tol):
    """The largest λ whose equilibrium exists (bisection as :func:`acmm.model.tea._fold_location`)."""
    lo, hi = lam, 1.0
    th = theta.copy()
    new = np.empty(3)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        ok = _newton(th, inertia, n, mid * bias, tol, 50, 0.05, new)
        if ok:
            jump = 0.0
            for i in range(3):
                jump = max(jump, abs(new[i] - th[i]))
            ok = jump < _MAX_JUMP
        if ok:
            lo = mid
            th[:] = new
        else:
            hi = mid
    return lo


@njit_cached()
def _solve_tea_compiled(inertia, n, bias, tol):
    """(θ, status, λ): status 0 solved, 1 fold in the products of inertia (λ reached), 2 fold
    in the bias (λ: the largest bias fraction with an equilibrium)."""
    diag = np.zeros((3, 3))
    for i in range(3):
        diag[i, i] = inertia[i, i]
    zero = np.zeros(3)
    th, lam, fold = _continue(np.zeros(3), diag, inertia, zero, zero, n, tol, 1e-7)
    if fold:
        return th, 1, lam
    th, lam, fold = _continue(th, inertia, inertia, zero, bias, n, tol, 1e-7)
    if fold:
        return th, 2, _fold_location(th, lam, inertia, n, bias, tol)
    return th, 0, 1.0


def _verified(theta: np.ndarray, inertia: np.ndarray, n: float, bias: np.ndarray) -> bool:
    """Whether ``theta`` (rad) passes the numpy residual check of :mod:`acmm.model.tea` for the plant."""
    scale = max(3 * n * n * np.abs(inertia).max(), 1e-300)
    res = np.max(np.abs(equilibrium_residual(theta, inertia, n, bias)))
    return bool(res <= 10 * residual_threshold(scale))


def solve_tea_fast(inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """The physical-branch TEA (same root as :func:`acmm.model.tea.solve_tea`), compiled.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.

    Returns
    -------
    acmm.model.tea.TEA
        The torque equilibrium attitude (eqs 4.1–4.3), θ in rad.

    Raises
    ------
    NoEquilibriumError
        The bias continuation folds; same message as :func:`acmm.model.tea.solve_tea` (the largest
        bias with an equilibrium, from the same bisection).
    ConvergenceError
        The continuation in the products of inertia folds and :func:`acmm.model.tea.solve_tea`'s
        fallback finds no equilibrium either (its message).
    """
    inertia = np.ascontiguousarray(inertia, float)
    bias = np.ascontiguousarray(bias, float)
    theta, status, lam = _solve_tea_compiled(inertia, float(n), bias, RESIDUAL_TOL)
    if status == 1:     # the products continuation failed: solve_tea's grid-search fallback (or its error)
        return solve_tea(inertia, n, bias)
    if status == 2:
        raise NoEquilibriumError(fold_message(bias, lam))
    if status == 0 and _verified(theta, inertia, n, bias):
        return make_tea(theta, inertia, n, bias)
    return solve_tea(inertia, n, bias)


# ---------------------------------------------------------------------------------------------
# the TEA of a perturbed plant on the branch connected to a known equilibrium (sweeps)
# ---------------------------------------------------------------------------------------------
def _continue_from(theta0, i0, b0, i1, b1, n, tol):
    """(θ, ok): the root of (i1, b1) on the branch through the root of (i0, b0) that damped
    Newton reaches from θ0 (within 5°).  Plain Python over the compiled kernels."""
    start = np.empty(3)
    if not _newton(theta0, i0, n, b0, tol, 50, 0.05, start):
        return theta0.copy(), False
    if np.max(np.abs(start - theta0)) > _MAX_JUMP:
        return start, False
    th, _, fold = _continue(start, i0, i1, b0, b1, n, tol, 1e-7, True)
    return th, not fold


def solve_tea_connected(theta0: np.ndarray, inertia0: np.ndarray, bias0: np.ndarray,
                        inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA | None:
    """The plant's TEA on the branch continuously connected to a known equilibrium of another plant.

    A Monte Carlo case perturbs the plant a controller was designed for; the station sits at the
    equilibrium it reaches as the plant moves from the nominal one to the perturbed one, not at
    whichever root a continuation from LVLH happens to end on (for a nearly planar body such as
    MB3, I11 ≈ I33, that root can lie ~90° from the design TEA while a connected one exists).
    Damped Newton first polishes ``theta0`` as a root of the nominal plant (≤ 5° away), then the
    continuation of :func:`acmm.model.tea.solve_tea` (same step control and acceptance tests) follows
    it along I = I0 + λ(I − I0), bias = b0 + λ(b − b0), λ: 0 → 1.

    Parameters
    ----------
    theta0 : (3,) array
        An equilibrium (or a guess within 5° of one) of the nominal plant, rad.
    inertia0, bias0 : (3, 3) array, (3,) array
        The nominal plant: inertia, slug·ft²; constant disturbance torque, ft·lbf.
    inertia : (3, 3) array
        The perturbed plant's inertia, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        The perturbed plant's constant disturbance torque, ft·lbf.

    Returns
    -------
    acmm.model.tea.TEA or None
        The connected equilibrium (eqs 4.1–4.3), θ in rad; None when ``theta0`` is not within 5°
        of an equilibrium of the nominal plant, the branch folds between the two plants (it turns
        back in λ: the continuation's step falls below 1e-7), it reaches yaw ±89.5° (the 2-3-1
        sequence's singularity), or the root fails the residual check of :mod:`acmm.model.tea`.  A
        change of sign of det ∂r/∂θ on a smooth branch (a pitchfork of a symmetric station) is
        passed, and roll or pitch may go beyond ±90°.
    """
    args = [np.ascontiguousarray(a, float) for a in (theta0, inertia0, bias0, inertia, bias)]
    theta, ok = _continue_from(args[0], args[1], args[2], args[3], args[4], float(n), RESIDUAL_TOL)
    if not ok or not _verified(theta, args[3], n, args[4]):
        return None
    return make_tea(theta, args[3], n, args[4])


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels of this module."""
    inertia, bias = np.diag([2.0e7, 1.0e6, 2.5e7]), np.array([0.0, 0.1, 0.0])
    root = solve_tea_fast(inertia, 0.0011, bias)
    solve_tea_connected(root.theta, inertia, bias, 1.01 * inertia, 0.0011, bias)
