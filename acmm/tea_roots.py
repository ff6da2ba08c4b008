"""Every torque-equilibrium attitude near LVLH (eqs 4.1–4.3), by Newton from a grid of attitudes.

The other roots of the TEA equations (``docs/ERRATA.md`` § TEA), and the fallback of
:func:`acmm.tea.solve_tea` for stations its continuation cannot follow.  Split from
:mod:`acmm.tea`, which re-exports :func:`all_equilibria`.
"""
from __future__ import annotations

import itertools

import numpy as np

from acmm.tea import TEA, _newton, make_tea
from common.errors import NoEquilibriumError


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
    from common.units import FT_LBF_IN_NM

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
    when its residual vanishes (:func:`acmm.tea._newton`'s test) and the Jacobian there is
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
    from acmm.tea import RESIDUAL_TOL, equilibrium_jacobian, equilibrium_residual, residual_threshold

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
    """The TEA when :func:`acmm.tea.solve_tea`'s continuation failed with ``exc``.

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
