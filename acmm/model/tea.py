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

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin
from acmm_qpp.errors import ConvergenceError, NoEquilibriumError
import itertools
from acmm_qpp.errors import NoEquilibriumError
from acmm_qpp.units import FT_LBF_IN_NM

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
    omega = kin.lvlh_rate_in_body(theta, n)
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
    omega = kin.lvlh_rate_in_body(theta, n)
    return (dyn.gyroscopic_torque_jacobian(omega, inertia) @ kin.lvlh_rate_jacobian(theta, n)
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
    inertia = np.asarray(inertia, float)
    bias = np.asarray(bias, float)
    starts = np.radians(np.arange(-limit_deg + grid_deg / 2, limit_deg, grid_deg))
    roots: list[np.ndarray] = []
    for t0 in itertools.product(starts, repeat=3):
        th = _newton(np.array(t0), inertia, n, bias, max_iter=100, max_step=0.2)
        if th is None or np.max(np.abs(th)) > np.radians(limit_deg):
            continue
        if not any(np.max(np.abs(th - r)) < 1e-6 for r in roots):
            roots.append(th)
    roots.sort(key=lambda r: float(np.linalg.norm(r)))
    return [make_tea(r, inertia, n, bias) for r in roots]


def fold_message(bias: np.ndarray, lam_max: float) -> str:
    """The message of a bias continuation that folds at ``lam_max`` of ``bias`` (ft·lbf), the
    torques given in ft·lbf and N·m (an SI run's message printed ft·lbf only).

    Parameters
    ----------
    bias : (3,) array
        The bias asked for, ft·lbf.
    lam_max : float
        Largest fraction of it reached on the branch continued from LVLH, dimensionless.

    Returns
    -------
    str
        One sentence naming the bias and the fold.
    """
    def torque(v) -> str:      # both systems: the core does not know which one the run prints
        return (f"[{v[0]:.4g}, {v[1]:.4g}, {v[2]:.4g}] ft·lbf "
                f"(= [{v[0] * FT_LBF_IN_NM:.4g}, {v[1] * FT_LBF_IN_NM:.4g}, {v[2] * FT_LBF_IN_NM:.4g}] N·m)")

    b = lam_max * bias
    return ("no torque-equilibrium attitude on the branch continued from LVLH for bias "
            f"{torque(bias)}: the gravity-gradient torque along that branch cannot balance it; the "
            f"branch ends (folds) at bias {torque(b)} ({100 * lam_max:.1f}% of the given bias)")


def with_other_roots(exc: NoEquilibriumError, inertia, n, bias) -> NoEquilibriumError:
    """The fold of the branch continued from LVLH (``exc``), with the equilibria that exist at
    the full bias on other branches (:func:`all_equilibria`) named, or the grid search's
    confirmation that none lies within ±85°.

    Parameters
    ----------
    exc : NoEquilibriumError
        The fold (:func:`fold_message`).
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.

    Returns
    -------
    NoEquilibriumError
        The error to raise (one line).
    """
    found = all_equilibria(inertia, n, bias)
    if not found:
        return NoEquilibriumError(f"{exc}; no other equilibrium lies within ±85° either (Newton from a "
                                  "30° grid of attitudes)")
    roots = "; ".join("[" + ", ".join(f"{v:.4f}" for v in r.theta_deg) + "]" for r in found[:3])
    more = f" (and {len(found) - 3} more)" if len(found) > 3 else ""
    first = ", ".join(f"{v:.4f}" for v in found[0].theta_deg)
    return NoEquilibriumError(
        f"{exc}. Equilibria on other branches do exist for this bias, at θ = {roots} deg{more}: "
        f"name the one meant with disturbance.bias_from_tea (e.g. bias_from_tea=[{first}] "
        "gives this bias and that attitude)")


#: σmin/σmax of the eq 4.1 Jacobian below which an equilibrium is not isolated
SINGULAR_JACOBIAN = 1e-9


def non_isolated_equilibrium(inertia: np.ndarray, n: float, bias: np.ndarray,
                             max_iter: int = 100) -> TEA | None:
    """An equilibrium of a family (singular Jacobian), nearest LVLH, or None.

    An axisymmetric station (I11 = I22, say) balances a bias on a whole curve of attitudes: the
    Jacobian of eq 4.1 is singular on it, so the continuation and Newton's method fail and the
    station was reported to have no equilibrium.  Gauss–Newton with the minimum-norm step
    (least squares) from LVLH reaches the member of the family nearest LVLH; it is accepted only
    when its residual vanishes (:func:`acmm.model.tea._newton`'s test) and the Jacobian there is
    singular — an isolated root is the continuation's to find, not this function's.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.
    max_iter : int
        Gauss–Newton iterations.

    Returns
    -------
    TEA or None
        The equilibrium (its attitude in rad), or None.
    """

    theta = np.zeros(3)
    scale = max(3 * n * n * np.abs(inertia).max(), 1e-300)
    for _ in range(max_iter):
        r = equilibrium_residual(theta, inertia, n, bias)
        if np.max(np.abs(r)) <= residual_threshold(scale, RESIDUAL_TOL):
            sv = np.linalg.svd(equilibrium_jacobian(theta, inertia, n), compute_uv=False)
            return make_tea(theta, inertia, n, bias) if sv[-1] <= SINGULAR_JACOBIAN * sv[0] else None
        step = np.linalg.lstsq(equilibrium_jacobian(theta, inertia, n), -r, rcond=1e-10)[0]
        norm = np.max(np.abs(step))
        if not np.isfinite(norm):
            return None
        theta = theta + (step * (0.05 / norm) if norm > 0.05 else step)
        if np.max(np.abs(theta)) > np.radians(85.0):
            return None
    return None


def without_continuation(exc, inertia: np.ndarray, n: float, bias: np.ndarray) -> TEA:
    """The TEA when :func:`acmm.model.tea.solve_tea`'s continuation failed with ``exc``.

    A fold of the bias continuation (NoEquilibriumError): a family of equilibria
    (:func:`non_isolated_equilibrium`), else the error naming the roots of other branches.  A
    failed products-of-inertia continuation (ConvergenceError): the smallest-|θ| root of
    :func:`all_equilibria`, else a family, else the error.

    Parameters
    ----------
    exc : NoEquilibriumError or ConvergenceError
        What the continuation raised.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    bias : (3,) array
        Constant disturbance torque, ft·lbf.

    Returns
    -------
    TEA
        The equilibrium (rad).

    Raises
    ------
    NoEquilibriumError
        No equilibrium on the branch continued from LVLH, nor a family (other roots named).
    ConvergenceError
        The products continuation failed and no equilibrium was found otherwise.
    """
    if isinstance(exc, NoEquilibriumError):
        family = non_isolated_equilibrium(inertia, n, bias)     # axisymmetric: a curve of roots
        if family is not None:
            return family
        raise with_other_roots(exc, inertia, n, bias) from None
    found = all_equilibria(inertia, n, bias)
    if found:
        return found[0]
    family = non_isolated_equilibrium(inertia, n, bias)         # a symmetry axis off the body axes
    if family is not None:
        return family
    raise exc
