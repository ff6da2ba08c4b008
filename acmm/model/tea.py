"""Torque-equilibrium attitude (TEA), CR-185644 eqs 4.1–4.3: one continuation, compiled.

The TEA θ* solves τ_gyro(ω*(θ*)) + τ_gg(θ*) + bias = 0 with ω*(θ) = C_BL·(0, −n, 0)
(eq 4.3).  Several roots exist; the physical branch is reached reproducibly by continuation
(``docs/ERRATA.md`` § TEA): start from the diagonal body at LVLH (θ = 0 is exact there with zero bias), grow the
products of inertia to their values, then grow the bias.  A fold in the bias continuation
means no equilibrium exists for the full bias.

The algorithm is written once, as numba kernels on plain arrays (compiled once and cached on disk,
:mod:`acmm.model.compiled_cache`): the residual of eq 4.1 and its Jacobian in closed form, damped
Newton (steps ≤ 0.5 rad, |θ| < 89.5°, 3×3 Gaussian elimination with partial pivoting), the
continuation (first step 0.05 of the path, ×1.5 up to 0.1 on success, halved on failure, a fold
below 1e-7; a step is accepted when Newton converges to :data:`_RESIDUAL_TOL`, θ jumps
≤ 5° and the sign of det ∂r/∂θ is kept) and the bisection of a fold.  The functions below are the
Python layer: the :class:`TEA` record, the fallbacks, the messages and the errors.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from acmm.model import kinematics as kin
from acmm.model.compiled_cache import njit_cached
from acmm_qpp.errors import EXIT_INPUT, AcmmError, ConvergenceError
from acmm.model.unit_systems import FT_LBF_IN_NM

#: The hint of a bias with no equilibrium: which settings to change (acmm's config).
_BIAS_HINT = "reduce disturbance.bias (or use disturbance.bias_from_tea with the attitude you want)"


class NoEquilibriumError(AcmmError):
    """No torque-equilibrium attitude exists for the given inertia and bias (eqs 4.1–4.3).

    A property of the configured plant, so it is an input error (exit 2); see
    ``docs/ERRATA.md`` § TEA."""

    exit_code = EXIT_INPUT


#: Largest residual (ft·lbf) accepted for an equilibrium; for a station whose gravity-gradient
#: torque scale 3n²·max|I| is below 10 ft·lbf, 1e-13 of that scale instead (an absolute 1e-12
#: would accept a 3 % residual on a model-sized station), and never below 1e-15 of it (round-off):
#: max(min(tol, 1e-13·scale), 1e-15·scale), the threshold of Newton and of the family search.
_RESIDUAL_TOL = 1e-12


# ------------------------------------------------------------------------------------------------
# The kernels (numba): residual and Jacobian, Newton, continuation, fold bisection
# ------------------------------------------------------------------------------------------------

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
def _max_diff(a, b):
    """max_i |a_i − b_i| of two attitudes (rad): the jump of a continuation step."""
    return np.abs(a - b).max()


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

    An iterate beyond 89.5° fails: in any angle, or with ``yaw_only`` in yaw θ3 alone, the one
    singular angle of the 2-3-1 sequence."""
    th = theta0.copy()
    scale = max(3.0 * n * n * np.abs(inertia).max(), 1e-300)
    thr = max(min(tol, 1e-13 * scale), 1e-15 * scale)          # threshold of _RESIDUAL_TOL
    r = np.empty(3)
    jac = np.empty((3, 3))
    step = np.empty(3)
    for it in range(max_iter + 1):          # the last pass only tests the final iterate
        _residual_jac(th, inertia, n, bias, r, jac, it < max_iter)
        if max(abs(r[0]), abs(r[1]), abs(r[2])) <= thr:
            out[:] = th
            return True
        if it == max_iter or not _solve3(jac, -r, step):
            return False
        norm = 0.0
        for i in range(3):
            if not np.isfinite(step[i]):
                return False
            norm = max(norm, abs(step[i]))
        if norm > max_step:
            step *= max_step / norm
        th += step
        if abs(th[2]) > _THETA_LIMIT or (not yaw_only and max(abs(th[0]), abs(th[1])) > _THETA_LIMIT):
            return False
    return False


@njit_cached()
def _continue(theta, i0, i1, b0, b1, n, tol, min_step, connected=False):
    """Follow θ(λ) along I = i0 + λ(i1 − i0), bias = b0 + λ(b1 − b0) from λ = 0 to 1.

    Returns (θ, λ reached, folded) with the step control of the module's docstring.  With
    ``connected`` (:func:`solve_tea_connected`) Newton is boxed in yaw only, and
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
        ok = _newton(th, inertia, n, bias, tol, 50, 0.5, new, connected) and _max_diff(new, th) <= _MAX_JUMP
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
    for i in range(3):
        err = max(err, abs(new[i] - th[i] - 0.5 * h * (ta[i] + tb[i])))
    return err <= 0.05 * _max_diff(new, th) + 1e-12


@njit_cached()
def _fold_location(theta, lam, inertia, n, bias, tol):
    """The largest λ in [``lam``, 1] whose equilibrium exists on the branch through ``theta`` (bisection)."""
    lo, hi = lam, 1.0
    th = theta.copy()
    new = np.empty(3)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if _newton(th, inertia, n, mid * bias, tol, 50, 0.05, new) and _max_diff(new, th) < _MAX_JUMP:
            lo = mid
            th[:] = new
        else:
            hi = mid
    return lo


@njit_cached()
def _from_lvlh(inertia, n, bias, tol):
    """(θ, status, λ): status 0 solved, 1 fold in the products of inertia (λ reached), 2 fold
    in the bias (λ: the largest bias fraction with an equilibrium)."""
    zero = np.zeros(3)
    th, lam, fold = _continue(np.zeros(3), np.diag(np.diag(inertia)), inertia, zero, zero, n, tol, 1e-7)
    if fold:
        return th, 1, lam
    th, lam, fold = _continue(th, inertia, inertia, zero, bias, n, tol, 1e-7)
    if fold:
        return th, 2, _fold_location(th, lam, inertia, n, bias, tol)
    return th, 0, 1.0


@njit_cached()
def _from_root(theta0, i0, b0, i1, b1, n, tol):
    """(θ, ok): the root of (i1, b1) on the branch through the root of (i0, b0) that damped
    Newton reaches from θ0 (within 5°), by the connected continuation."""
    start = np.empty(3)
    if not (_newton(theta0, i0, n, b0, tol, 50, 0.05, start, False) and _max_diff(start, theta0) <= _MAX_JUMP):
        return theta0.copy(), False         # the caller reads θ only when ok
    th, _, fold = _continue(start, i0, i1, b0, b1, n, tol, 1e-7, True)
    return th, not fold


# ------------------------------------------------------------------------------------------------
# The Python layer
# ------------------------------------------------------------------------------------------------
def _vec(x) -> np.ndarray:
    """``x`` as the C-contiguous float64 array the kernels are compiled for."""
    return np.ascontiguousarray(x, dtype=float)


def _root(theta0, inertia, n, bias, max_iter=50, max_step=0.5) -> np.ndarray | None:
    """Damped Newton on eq 4.1 from ``theta0`` (rad); the root, or None when it fails to converge."""
    out = np.empty(3)
    ok = _newton(_vec(theta0), _vec(inertia), float(n), _vec(bias), _RESIDUAL_TOL, max_iter, max_step, out, False)
    return out if ok else None


@dataclass(frozen=True)
class TEA:
    """A torque-equilibrium attitude.

    Attributes
    ----------
    theta : (3,) array
        θ* = (roll, pitch, yaw), rad.
    omega : (3,) array
        ω* of eq 4.3, rad/s.
    bias : (3,) array
        Bias torque the equilibrium balances, ft·lbf.
    residual : float
        max |τ_gyro + τ_gg + bias| at θ*, ft·lbf.
    """

    theta: np.ndarray
    omega: np.ndarray
    bias: np.ndarray
    residual: float

    @property
    def theta_deg(self) -> np.ndarray:
        """θ* in degrees, (3,) array (as printed in Table 1)."""
        return np.degrees(self.theta)


def equilibrium_residual(theta, inertia, n, bias) -> np.ndarray:
    """τ_gyro(ω*(θ)) + τ_gg(θ) + bias, eq 4.1 with eq 4.3 substituted (ft·lbf).

    Parameters
    ----------
    theta : (3,) array
        Roll, pitch, yaw, rad.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.

    Returns
    -------
    (3,) array
        Residual torque, ft·lbf (zero at an equilibrium).
    """
    r = np.empty(3)
    _residual_jac(_vec(theta), _vec(inertia), float(n), _vec(bias), r, np.empty((3, 3)), False)
    return r


def equilibrium_jacobian(theta, inertia, n) -> np.ndarray:
    """∂/∂θ of :func:`equilibrium_residual` (ft·lbf/rad), analytic.

    Built from the partials of eqs 4.3, 4.8–4.10 and the corrected 4.12–4.14
    (``docs/ERRATA.md`` § Linearization).

    Parameters
    ----------
    theta : (3,) array
        Roll, pitch, yaw, rad.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (3, 3) array
        Jacobian of the residual, ft·lbf/rad.
    """
    jac = np.empty((3, 3))
    _residual_jac(_vec(theta), _vec(inertia), float(n), np.zeros(3), np.empty(3), jac, True)
    return jac


def bias_for_attitude(theta, inertia, n) -> np.ndarray:
    """The bias torque (ft·lbf) that makes ``theta`` (rad) an equilibrium (eq 4.1 solved for bias).

    How Table 1 is reproduced exactly (``docs/ERRATA.md`` § TEA).

    Parameters
    ----------
    theta : (3,) array
        Attitude to be made an equilibrium, rad.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (3,) array
        Bias torque, ft·lbf.
    """
    return -equilibrium_residual(theta, inertia, n, np.zeros(3))


def solve_tea(inertia: np.ndarray, n: float, bias: np.ndarray, expected=None) -> TEA:
    """The physical-branch TEA by continuation (eqs 4.1–4.3).

    Fallbacks: with ``expected`` (an attitude known to be an equilibrium, e.g. the config's
    ``bias_from_tea``), when the continuation fails or ends more than 1e-6 rad from it, the
    equilibrium at ``expected`` (Newton from it): the TEA a config asks for is the TEA it gets.
    When the continuation in the products of inertia fails (I11 = I33: every pitch balances
    the diagonal body, no unique start; a branch turning beyond ±89.5°), the smallest-|θ| root
    of :func:`all_equilibria`.  A fold of the bias continuation is an error (no equilibrium on
    the branch continued from LVLH; distant branches: :func:`all_equilibria`).

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.
    expected : (3,) array, optional
        An attitude (rad) known to be an equilibrium for this inertia and bias (see above).

    Returns
    -------
    TEA
        θ* (rad), ω* (rad/s), the bias (ft·lbf) and the residual (ft·lbf).

    Raises
    ------
    NoEquilibriumError
        When the bias continuation folds: the message gives the largest bias (same direction)
        that still has an equilibrium on this branch (``docs/ERRATA.md`` § TEA).
    ConvergenceError
        The products continuation fails and no equilibrium lies within ±85°.
    """
    inertia, bias = _vec(inertia), _vec(bias)
    at = None if expected is None else _at_expected(inertia, n, bias, expected)
    try:
        t = _solve_by_continuation(inertia, n, bias)
    except (NoEquilibriumError, ConvergenceError) as exc:
        return at if at is not None else _without_continuation(exc, inertia, n, bias)
    return at if at is not None and np.max(np.abs(t.theta - at.theta)) > 1e-6 else t


def _at_expected(inertia, n, bias, expected) -> TEA | None:
    """The equilibrium within 1e-6 rad of ``expected`` (rad) by Newton from it, or None."""
    theta = _root(expected, inertia, n, bias, max_step=0.05)
    ok = theta is not None and np.max(np.abs(theta - expected)) <= 1e-6
    return _make_tea(theta, inertia, n, bias) if ok else None


def _solve_by_continuation(inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """:func:`solve_tea`'s continuation (diagonal body at LVLH → products → bias) and its errors."""
    theta, status, lam = _from_lvlh(inertia, float(n), bias, _RESIDUAL_TOL)
    if status == 1:
        raise ConvergenceError(
            "TEA continuation in the products of inertia failed at "
            f"{100 * lam:.3g}% of their values (the inertia may have no LVLH-near equilibrium)",
            hint="check the products of inertia (inertia.I12, I13, I23) or give the bias as "
                 "disturbance.bias_from_tea")
    if status == 2:
        raise NoEquilibriumError(_fold_message(bias, lam), hint=_BIAS_HINT)
    return _make_tea(theta, inertia, n, bias)


def bias_fold(inertia: np.ndarray, n: float, bias: np.ndarray) -> float | None:
    """Where :func:`solve_tea`'s continuation folds in the bias.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Body-frame bias torque, ft·lbf.

    Returns
    -------
    float or None
        The largest fraction λ of ``bias`` with an equilibrium on the branch the continuation
        follows from LVLH (dimensionless, the fraction :class:`NoEquilibriumError` names), or None
        when the continuation reaches the whole bias or fails before it (in the products of
        inertia).
    """
    _, status, lam = _from_lvlh(_vec(inertia), float(n), _vec(bias), _RESIDUAL_TOL)
    return float(lam) if status == 2 else None


def solve_tea_near(inertia: np.ndarray, n: float, bias: np.ndarray, theta_guess: np.ndarray,
                   expected=None) -> TEA:
    """The equilibrium nearest a guess (rad) by damped Newton, e.g. along a continuation path.

    Falls back to :func:`solve_tea` when Newton does not converge within 5° of the guess; with
    ``expected`` (see :func:`solve_tea`) a root more than 1e-6 rad from it is replaced by the
    equilibrium at ``expected``.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.
    theta_guess : (3,) array
        Starting attitude, rad.
    expected : (3,) array, optional
        An attitude (rad) known to be an equilibrium (the config's ``bias_from_tea``).

    Returns
    -------
    TEA
        The equilibrium of eqs 4.1–4.3 near the guess (or the physical branch).

    Raises
    ------
    NoEquilibriumError, ConvergenceError
        From the fallback :func:`solve_tea`.
    """
    inertia, bias = _vec(inertia), _vec(bias)
    theta = _root(theta_guess, inertia, n, bias, max_step=0.05)
    if theta is None or np.max(np.abs(theta - theta_guess)) > np.radians(5.0):
        return solve_tea(inertia, n, bias, expected=expected)
    far = expected is not None and np.max(np.abs(theta - expected)) > 1e-6
    at = _at_expected(inertia, n, bias, expected) if far else None
    return at if at is not None else _make_tea(theta, inertia, n, bias)


def _make_tea(theta, inertia, n, bias) -> TEA:
    """θ* (rad) with ω* of eq 4.3 (rad/s), the bias and max |residual of eq 4.1| (ft·lbf)."""
    theta = np.asarray(theta, float)
    res = float(np.max(np.abs(equilibrium_residual(theta, inertia, n, bias))))
    return TEA(theta=theta, omega=kin.lvlh_rate_in_body(theta, n), bias=np.asarray(bias, float),
               residual=res)


def resolve_bias(disturbance, inertia: np.ndarray, n: float) -> np.ndarray:
    """The bias (ft·lbf) a :class:`acmm.io.config.Disturbance` asks for (``bias_from_tea`` resolved).

    The bias of eq 3.9; ``bias_from_tea`` (deg) is turned into a torque by
    :func:`bias_for_attitude`.

    Parameters
    ----------
    disturbance : acmm.io.config.Disturbance
        Config section with ``bias`` (ft·lbf) or ``bias_from_tea`` (deg), or neither.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (3,) array
        Bias torque, ft·lbf (zero when neither is given).
    """
    if disturbance.bias_from_tea is not None:
        return bias_for_attitude(np.radians(disturbance.bias_from_tea), inertia, n)
    if disturbance.bias is not None:
        return np.asarray(disturbance.bias, float)
    return np.zeros(3)


# ------------------------------------------------------------------------------------------------
# Every torque-equilibrium attitude near LVLH (eqs 4.1–4.3), by Newton from a grid of attitudes.
#
# The other roots of the TEA equations (``docs/ERRATA.md`` § TEA), and the fallback of
# :func:`solve_tea` for stations its continuation cannot follow.


def all_equilibria(inertia: np.ndarray, n: float, bias: np.ndarray, grid_deg: float = 30.0,
                   limit_deg: float = 85.0) -> list[TEA]:
    """Every equilibrium found by Newton from a grid of starts in |θ_i| < ``limit_deg``.

    Distinct roots (to 1e-6 rad) sorted by |θ|; useful to see the other branches (e.g. the
    two principal-axis alignments of MB3 at pitch −44.70° and +45.30°; ``docs/ERRATA.md``
    § TEA).

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.
    grid_deg : float
        Spacing of the grid of starting attitudes, deg.
    limit_deg : float
        Largest |θ_i| searched and accepted, deg.

    Returns
    -------
    list of TEA
        The distinct equilibria of eqs 4.1–4.3, smallest |θ| first.
    """
    inertia, bias = _vec(inertia), _vec(bias)
    starts = np.radians(np.arange(-limit_deg + grid_deg / 2, limit_deg, grid_deg))
    roots: list[np.ndarray] = []
    for t0 in itertools.product(starts, repeat=3):
        th = _root(t0, inertia, n, bias, max_iter=100, max_step=0.2)
        if th is None or np.max(np.abs(th)) > np.radians(limit_deg):
            continue
        if not any(np.max(np.abs(th - r)) < 1e-6 for r in roots):
            roots.append(th)
    roots.sort(key=lambda r: float(np.linalg.norm(r)))
    return [_make_tea(r, inertia, n, bias) for r in roots]


def _fold_message(bias: np.ndarray, lam_max: float) -> str:
    """The message of a bias continuation (ft·lbf) that folds at the fraction ``lam_max`` of it, the
    torques given in ft·lbf and N·m (an SI run's message printed ft·lbf only)."""
    def torque(v) -> str:      # both systems: the core does not know which one the run prints
        return (f"[{v[0]:.4g}, {v[1]:.4g}, {v[2]:.4g}] ft·lbf "
                f"(= [{v[0] * FT_LBF_IN_NM:.4g}, {v[1] * FT_LBF_IN_NM:.4g}, {v[2] * FT_LBF_IN_NM:.4g}] N·m)")

    b = lam_max * bias
    return ("no torque-equilibrium attitude on the branch continued from LVLH for bias "
            f"{torque(bias)}: the gravity-gradient torque along that branch cannot balance it; the "
            f"branch ends (folds) at bias {torque(b)} ({100 * lam_max:.1f}% of the given bias)")


def _with_other_roots(exc: NoEquilibriumError, inertia, n, bias) -> NoEquilibriumError:
    """The fold of the branch continued from LVLH (``exc``), with the equilibria that exist at
    the full bias on other branches (:func:`all_equilibria`) named, or the grid search's
    confirmation that none lies within ±85°: the error to raise (one line)."""
    found = all_equilibria(inertia, n, bias)
    if not found:
        return NoEquilibriumError(f"{exc}; no other equilibrium lies within ±85° either (Newton from a "
                                  "30° grid of attitudes)", hint=exc.hint)
    roots = "; ".join("[" + ", ".join(f"{v:.4f}" for v in r.theta_deg) + "]" for r in found[:3])
    more = f" (and {len(found) - 3} more)" if len(found) > 3 else ""
    first = ", ".join(f"{v:.4f}" for v in found[0].theta_deg)
    return NoEquilibriumError(
        f"{exc}. Equilibria on other branches do exist for this bias, at θ = {roots} deg{more}: "
        f"name the one meant with disturbance.bias_from_tea (e.g. bias_from_tea=[{first}] "
        "gives this bias and that attitude)", hint=exc.hint)


#: σmin/σmax of the eq 4.1 Jacobian below which an equilibrium is not isolated
_SINGULAR_JACOBIAN = 1e-9


def _non_isolated_equilibrium(inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA | None:
    """An equilibrium of a family (singular Jacobian), nearest LVLH (rad), or None.

    An axisymmetric station (I11 = I22, say) balances a bias on a whole curve of attitudes: the
    Jacobian of eq 4.1 is singular on it, so the continuation and Newton's method fail and the
    station was reported to have no equilibrium.  Gauss–Newton with the minimum-norm step
    (least squares) from LVLH reaches the member of the family nearest LVLH; it is accepted only
    when its residual vanishes (Newton's test, :data:`_RESIDUAL_TOL`) and the Jacobian there is
    singular — an isolated root is the continuation's to find, not this function's.  At most 100
    Gauss–Newton iterations, each step at most 0.05 rad.
    """
    theta = np.zeros(3)
    scale = max(3 * n * n * np.abs(inertia).max(), 1e-300)
    for _ in range(100):
        r = equilibrium_residual(theta, inertia, n, bias)
        if np.max(np.abs(r)) <= max(min(_RESIDUAL_TOL, 1e-13 * scale), 1e-15 * scale):
            sv = np.linalg.svd(equilibrium_jacobian(theta, inertia, n), compute_uv=False)
            return _make_tea(theta, inertia, n, bias) if sv[-1] <= _SINGULAR_JACOBIAN * sv[0] else None
        step = np.linalg.lstsq(equilibrium_jacobian(theta, inertia, n), -r, rcond=1e-10)[0]
        norm = np.max(np.abs(step))
        if not np.isfinite(norm):
            return None
        theta = theta + (step * (0.05 / norm) if norm > 0.05 else step)
        if np.max(np.abs(theta)) > np.radians(85.0):
            return None
    return None


def _without_continuation(exc, inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """The TEA when :func:`acmm.model.tea.solve_tea`'s continuation failed with ``exc``.

    A fold of the bias continuation (NoEquilibriumError): a family of equilibria
    (:func:`_non_isolated_equilibrium`), else the error naming the roots of other branches.  A
    failed products-of-inertia continuation (ConvergenceError): the smallest-|θ| root of
    :func:`all_equilibria`, else a family, else ``exc`` (units as :func:`solve_tea`).
    """
    if isinstance(exc, NoEquilibriumError):
        family = _non_isolated_equilibrium(inertia, n, bias)     # axisymmetric: a curve of roots
        if family is not None:
            return family
        raise _with_other_roots(exc, inertia, n, bias) from None
    found = all_equilibria(inertia, n, bias)
    tea = found[0] if found else _non_isolated_equilibrium(inertia, n, bias)  # a family: symmetry axis off body axes
    if tea is None:
        raise exc
    return tea


def solve_tea_fast(inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """The physical-branch TEA by :func:`solve_tea`'s continuation, without the searches of a fold.

    A sweep's per-case path: a fold of the bias continuation is the error, without
    :func:`solve_tea`'s family and grid searches (its message is the start of theirs).

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
    TEA
        The torque equilibrium attitude (eqs 4.1–4.3), θ in rad.

    Raises
    ------
    NoEquilibriumError
        The bias continuation folds (the message names the largest bias with an equilibrium).
    ConvergenceError
        The continuation in the products of inertia folds and :func:`solve_tea`'s fallbacks find
        no equilibrium either.
    """
    inertia, bias = _vec(inertia), _vec(bias)
    try:
        return _solve_by_continuation(inertia, n, bias)
    except ConvergenceError as exc:
        return _without_continuation(exc, inertia, n, bias)


def solve_tea_connected(theta0: np.ndarray, inertia0: np.ndarray, bias0: np.ndarray,
                        inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA | None:
    """The plant's TEA on the branch continuously connected to a known equilibrium of another plant.

    A Monte Carlo case perturbs the plant a controller was designed for; the station sits at the
    equilibrium it reaches as the plant moves from the nominal one to the perturbed one, not at
    whichever root a continuation from LVLH happens to end on (for a nearly planar body such as
    MB3, I11 ≈ I33, that root can lie ~90° from the design TEA while a connected one exists).
    Damped Newton first polishes ``theta0`` as a root of the nominal plant (≤ 5° away), then the
    continuation of :func:`solve_tea` (same step control and acceptance tests) follows it along
    I = I0 + λ(I − I0), bias = b0 + λ(b − b0), λ: 0 → 1.

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
    TEA or None
        The connected equilibrium (eqs 4.1–4.3), θ in rad; None when ``theta0`` is not within 5°
        of an equilibrium of the nominal plant, the branch folds between the two plants (it turns
        back in λ: the continuation's step falls below 1e-7), or it reaches yaw ±89.5° (the 2-3-1
        sequence's singularity).  A change of sign of det ∂r/∂θ on a smooth branch (a pitchfork
        of a symmetric station) is passed, and roll or pitch may go beyond ±90°.
    """
    inertia, bias = _vec(inertia), _vec(bias)
    theta, ok = _from_root(_vec(theta0), _vec(inertia0), _vec(bias0), inertia, bias, float(n), _RESIDUAL_TOL)
    return _make_tea(theta, inertia, n, bias) if ok else None


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels of this module."""
    inertia, bias = np.diag([2.0e7, 1.0e6, 2.5e7]), np.array([0.0, 0.1, 0.0])
    root = solve_tea_fast(inertia, 0.0011, bias)
    solve_tea_connected(root.theta, inertia, bias, 1.01 * inertia, 0.0011, bias)
    solve_tea_near(inertia, 0.0011, bias, root.theta)
    equilibrium_jacobian(root.theta, inertia, 0.0011)
