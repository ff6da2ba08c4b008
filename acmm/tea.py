"""Torque-equilibrium attitude (TEA), CR-185644 eqs 4.1–4.3.

The TEA θ* solves τ_gyro(ω*(θ*)) + τ_gg(θ*) + bias = 0 with ω*(θ) = C_BL·(0, −n, 0)
(eq 4.3).  Several roots exist; the physical branch is reached reproducibly by continuation
(``docs/ERRATA.md`` § TEA): start from the diagonal body at LVLH (θ = 0 is exact there with zero bias), grow the
products of inertia to their values, then grow the bias.  A fold in the bias continuation
means no equilibrium exists for the full bias.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm import dynamics as dyn
from common.errors import ConvergenceError, NoEquilibriumError

#: Largest residual (ft·lbf) accepted for an equilibrium; for a station whose gravity-gradient
#: torque scale 3n²·max|I| is below 10 ft·lbf, 1e-13 of that scale instead (an absolute 1e-12
#: would accept a 3 % residual on a model-sized station), and never below 1e-15 of it (round-off).
RESIDUAL_TOL = 1e-12


def residual_threshold(scale: float, tol: float = RESIDUAL_TOL) -> float:
    """The residual accepted for an equilibrium (see :data:`RESIDUAL_TOL`).

    Parameters
    ----------
    scale : float
        Gravity-gradient torque scale 3n²·max|I|, ft·lbf.
    tol : float, optional
        Absolute tolerance, ft·lbf.

    Returns
    -------
    float
        max(min(tol, 1e-13·scale), 1e-15·scale), ft·lbf.
    """
    return max(min(tol, 1e-13 * scale), 1e-15 * scale)


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
    omega = dyn.lvlh_rate_in_body(theta, n)
    return dyn.gyroscopic_torque(omega, inertia) + dyn.gravity_gradient_torque(theta, inertia, n) + bias


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
    omega = dyn.lvlh_rate_in_body(theta, n)
    return (dyn.gyroscopic_torque_jacobian(omega, inertia) @ dyn.lvlh_rate_jacobian(theta, n)
            + dyn.gravity_gradient_jacobian(theta, inertia, n))


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
    return -(equilibrium_residual(np.asarray(theta, float), inertia, n, np.zeros(3)))


def _newton(theta0, inertia, n, bias, tol=RESIDUAL_TOL, max_iter=50, max_step=0.5):
    """Damped Newton on eq 4.1; returns θ or None when it fails to converge."""
    theta = np.array(theta0, float)
    scale = max(3 * n * n * np.abs(inertia).max(), 1e-300)
    for _ in range(max_iter):
        r = equilibrium_residual(theta, inertia, n, bias)
        if np.max(np.abs(r)) <= residual_threshold(scale, tol):
            return theta
        jac = equilibrium_jacobian(theta, inertia, n)
        try:
            step = np.linalg.solve(jac, -r)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(step)):
            return None
        norm = np.max(np.abs(step))
        if norm > max_step:
            step *= max_step / norm
        theta = theta + step
        if np.max(np.abs(theta)) > np.radians(89.5):
            return None
    r = equilibrium_residual(theta, inertia, n, bias)
    return theta if np.max(np.abs(r)) <= residual_threshold(scale, tol) else None


def _continue(theta, path, n, max_jump=np.radians(5.0), min_step=1e-7):
    """Follow θ(λ) along ``path(λ) -> (inertia, bias)`` for λ from 0 to 1.

    Returns (θ at λ=1, None) or (θ at the last λ reached, λ_last) on a fold.
    """
    lam, step = 0.0, 0.05
    inertia, _ = path(0.0)
    det0 = np.sign(np.linalg.det(equilibrium_jacobian(theta, inertia, n)))
    while lam < 1.0:
        trial = min(1.0, lam + step)
        inertia, bias = path(trial)
        new = _newton(theta, inertia, n, bias)
        ok = new is not None and np.max(np.abs(new - theta)) <= max_jump
        if ok:
            det = np.sign(np.linalg.det(equilibrium_jacobian(new, inertia, n)))
            ok = det == det0
        if ok:
            theta, lam = new, trial
            step = min(step * 1.5, 0.1)
        else:
            step *= 0.5
            if step < min_step:
                return theta, lam
    return theta, None


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
    inertia = np.asarray(inertia, float)
    bias = np.asarray(bias, float)
    at = None if expected is None else _at_expected(inertia, n, bias, expected)
    try:
        t = _solve_by_continuation(inertia, n, bias)
    except (NoEquilibriumError, ConvergenceError) as exc:
        if at is not None:
            return at
        from acmm.tea_roots import without_continuation

        return without_continuation(exc, inertia, n, bias)
    if at is not None and np.max(np.abs(t.theta - at.theta)) > 1e-6:
        return at
    return t


def _at_expected(inertia, n, bias, expected) -> TEA | None:
    """The equilibrium within 1e-6 rad of ``expected`` (rad) by Newton from it, or None."""
    theta = _newton(np.asarray(expected, float), inertia, n, bias, max_step=0.05)
    ok = theta is not None and np.max(np.abs(theta - expected)) <= 1e-6
    return make_tea(theta, inertia, n, bias) if ok else None


def _solve_by_continuation(inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """:func:`solve_tea`'s continuation (diagonal body at LVLH → products → bias) and its errors."""
    diag = np.diag(np.diag(inertia))

    def inertia_path(lam):
        return diag + lam * (inertia - diag), np.zeros(3)

    theta, fold = _continue(np.zeros(3), inertia_path, n)
    if fold is not None:
        raise ConvergenceError(
            "TEA continuation in the products of inertia failed at "
            f"{100 * fold:.3g}% of their values (the inertia may have no LVLH-near equilibrium)")

    def bias_path(lam):
        return inertia, lam * bias

    theta, fold = _continue(theta, bias_path, n)
    if fold is not None:
        lam_max = _fold_location(theta, fold, inertia, n, bias)
        b = lam_max * bias
        from acmm.tea_roots import fold_message

        raise NoEquilibriumError(fold_message(bias, lam_max))
    return make_tea(theta, inertia, n, bias)


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
    inertia = np.asarray(inertia, float)
    bias = np.asarray(bias, float)
    theta = _newton(theta_guess, inertia, n, bias, max_step=0.05)
    if theta is None or np.max(np.abs(theta - theta_guess)) > np.radians(5.0):
        return solve_tea(inertia, n, bias, expected=expected)
    if expected is not None and np.max(np.abs(theta - expected)) > 1e-6:
        at = _at_expected(inertia, n, bias, expected)
        if at is not None:
            return at
    return make_tea(theta, inertia, n, bias)


def _fold_location(theta, lam, inertia, n, bias):
    """Refine the fold of the bias continuation: the largest λ whose equilibrium exists."""
    lo, hi, th = lam, 1.0, theta
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        new = _newton(th, inertia, n, mid * bias, max_step=0.05)
        if new is not None and np.max(np.abs(new - th)) < np.radians(5):
            lo, th = mid, new
        else:
            hi = mid
    return lo


def make_tea(theta, inertia, n, bias) -> TEA:
    """Package θ* with ω*, bias and the residual (ft·lbf).

    Parameters
    ----------
    theta : (3,) array
        Equilibrium attitude θ*, rad.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Bias torque balanced at θ*, ft·lbf.

    Returns
    -------
    TEA
        θ*, ω* of eq 4.3 (rad/s), the bias and max |residual of eq 4.1| (ft·lbf).
    """
    theta = np.asarray(theta, float)
    res = float(np.max(np.abs(equilibrium_residual(theta, inertia, n, bias))))
    return TEA(theta=theta, omega=dyn.lvlh_rate_in_body(theta, n), bias=np.asarray(bias, float),
               residual=res)


def resolve_bias(disturbance, inertia: np.ndarray, n: float) -> np.ndarray:
    """The bias (ft·lbf) a :class:`acmm.config.Disturbance` asks for (``bias_from_tea`` resolved).

    The bias of eq 3.9; ``bias_from_tea`` (deg) is turned into a torque by
    :func:`bias_for_attitude`.

    Parameters
    ----------
    disturbance : acmm.config.Disturbance
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


def __getattr__(name: str):
    """``all_equilibria`` lives in :mod:`acmm.tea_roots` (re-exported here, imported on use)."""
    if name == "all_equilibria":
        from acmm.tea_roots import all_equilibria

        return all_equilibria
    raise AttributeError(f"module 'acmm.tea' has no attribute {name!r}")
