"""The TEA of a perturbed plant on the branch connected to a known equilibrium (issue 16, sweeps).

A sweep case perturbs the plant a controller was designed for; the station sits at the
equilibrium (eqs 4.1–4.3) it reaches as the plant moves from the nominal one to the perturbed one.
:func:`solve_tea_connected` follows it with the compiled continuation of :mod:`acmm.model.tea_compiled`
(``connected=True``: yaw-only box, pitchfork passage; see that module's docstring for why this
and not the continuation from LVLH or one Newton step).
"""
from __future__ import annotations

import numpy as np

from acmm.model.tea import RESIDUAL_TOL, TEA, make_tea
from acmm.model.tea_compiled import _MAX_JUMP, _continue, _newton, _verified


def _continue_from(theta0, i0, b0, i1, b1, n, tol):
    """(θ, ok): the root of (i1, b1) on the branch through the root of (i0, b0) that damped
    Newton reaches from θ0 (within 5°).  Plain Python over the compiled kernels of
    :mod:`acmm.model.tea_compiled`: a cached numba function calling another module's kernels would keep
    their old machine code when only that module changes (numba's cache tracks one file)."""
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
    inertia, bias : (3, 3) array, (3,) array
        The perturbed plant, same units.
    n : float
        Orbital rate, rad/s.

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
    """Compile (or load from numba's cache) the kernel of this module."""
    from acmm.model.tea_compiled import solve_tea_fast

    inertia, bias = np.diag([2.0e7, 1.0e6, 2.5e7]), np.array([0.0, 0.1, 0.0])
    root = solve_tea_fast(inertia, 0.0011, bias)
    solve_tea_connected(root.theta, inertia, bias, 1.01 * inertia, 0.0011, bias)
