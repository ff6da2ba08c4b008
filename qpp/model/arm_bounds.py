"""β3 of the polar arm of ch. 14 (eq 14.2) PROVED over a box of its state (issue 43; eq 10.40).

With φ = N (f1(x, M) − f1(x, M°)) and f1 = [R/(μ+M) x4²; −2 R x3 x4 / I],
R = μ x1 + M (x1 + a), I = J1 + J2 + μ x1² + M (x1 + a)² (:mod:`qpp.model.matched_nonlinearity`),
the outputs are y = (x1, x2):

* f1 does not depend on the angle x2, so ∂φ/∂y2 = 0;
* R/(μ+M) = x1 + M a/(μ+M), so ∂f1_1/∂x1 = x4² whatever M: its share of ∂φ/∂x1 cancels;
* ∂f1_2/∂x1 = −2 x3 x4 q(x1, M), q = ∂(R/I)/∂x1 = [(μ+M) I − R (2μ x1 + 2M (x1 + a))] / I².

The Jacobian ∂φ/∂y is therefore the single column N[:, 1] · (−2 x3 x4) (q(x1, M) − q(x1, M°)), whose
spectral norm is ‖N[:, 1]‖₂ · 2 |x3 x4| · |q(x1, M) − q(x1, M°)|.  Over a box of x1, x3, x4 and
M ∈ [M_min, M_max] this is bounded by the product of sup |x3 x4| (an interval product) and
sup |Δq|, enclosed by interval branch and bound (:func:`qpp.model.interval_bounds.maximize`;
its upper bound holds whatever the status, only its tightness depends on the budget).
"""
from __future__ import annotations

import time

import numpy as np

from qpp.model.expression_parser import sympy_module
from qpp.model.interval_bounds import compile_interval, maximize

#: boxes of the branch and bound of sup |Δq| (its upper bound holds at any count)
ARM_BOXES = 4000
#: relative width to which sup |Δq| is enclosed when the budget allows
ARM_TOL = 1e-3


def _delta_q(nl):
    """The interval enclosure of |q(x1, M) − q(x1, M°)| (module docstring) as a function
    ``f(x1 in m, M in kg) -> mpmath.iv.mpf`` of the arm ``nl``, in 1/m² (the units of ∂(R/I)/∂x1)."""
    sp = sympy_module()
    x1, M = sp.symbols("x1 M", real=True)
    mu, a, J = (sp.nsimplify(v) for v in (nl.mu, nl.a, nl.J1 + nl.J2))

    def q(m):
        R = mu * x1 + m * (x1 + a)
        inertia = J + mu * x1 ** 2 + m * (x1 + a) ** 2
        return sp.diff(R / inertia, x1)

    expr = sp.Abs(sp.factor(sp.together(q(M) - q(sp.nsimplify(nl.M_nominal)))))   # (factored: few repeats)
    return compile_interval(expr, (x1, M))


def arm_slope_bound(nl, N, x1_box, x3_box, x4_box) -> tuple:
    """Upper bounds of the spectral norm of ∂φ/∂y over x1 ∈ ``x1_box``, M ∈ [M_min, M_max] and,
    per cell, x3 and x4 in their boxes (module docstring), proved.

    Parameters
    ----------
    nl : qpp.io.config.PolarArmNonlinearity
        The arm.
    N : (r, m) array
        B = G N (assumption iii), dimensionless.
    x1_box : (float, float)
        Range of the radius x1 over every cell, in units of m (metres).
    x3_box, x4_box : (2, K) arrays
        Per cell, the range of the radial rate x3 (m/s) and of the angular rate x4 (rad/s).

    Returns
    -------
    bounds : (K,) ndarray
        The bound per cell, units of φ per unit of y (inf where the x1 box reaches a singular inertia).
    dq : qpp.model.interval_bounds.Bound
        The branch and bound of sup |Δq| (its ``gap`` is the enclosure's width), 1/m².
    """
    n1 = float(np.linalg.norm(np.asarray(N, float)[:, 1]))
    deadline = time.monotonic() + 10.0          # the proof's time budget, s
    box = [tuple(map(float, x1_box)), (float(nl.M_min), float(nl.M_max))]
    f = _delta_q(nl)
    first = maximize(f, box, tol=0.0, deadline=deadline, max_boxes=16)
    dq = maximize(f, box, tol=ARM_TOL * max(first.lower, 1e-300), deadline=deadline, max_boxes=ARM_BOXES)
    v = np.max(np.abs(np.asarray(x3_box, float)), axis=0) * np.max(np.abs(np.asarray(x4_box, float)), axis=0)
    return n1 * 2.0 * v * dq.upper * (1 + 1e-12), dq
