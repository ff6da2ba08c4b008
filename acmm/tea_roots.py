"""Every torque-equilibrium attitude near LVLH (eqs 4.1–4.3), by Newton from a grid of attitudes.

The other roots of the TEA equations (``docs/ERRATA.md`` § TEA), and the fallback of
:func:`acmm.tea.solve_tea` for stations its continuation cannot follow.  Split from
:mod:`acmm.tea`, which re-exports :func:`all_equilibria`.
"""
from __future__ import annotations

import itertools

import numpy as np

from acmm.tea import TEA, _newton, make_tea


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
