"""The polar arm's β3 proved over a box (issue 43): the structure the bound rests on (∂φ/∂y2 = 0,
∂φ1/∂x1 = 0) and the bound itself against central differences of eq 14.2's f1, written again here."""
from __future__ import annotations

import numpy as np

from qpp.model.arm_bounds import arm_slope_bound


def _f1(x, M, mu=10.0, J=200.0, a=1.0):
    """Eq 14.2 (ch. 14): f1 = [R/(μ+M) x4²; −2 R x3 x4 / I]."""
    x1, _, x3, x4 = x
    R = mu * x1 + M * (x1 + a)
    I = J + mu * x1 ** 2 + M * (x1 + a) ** 2
    return np.array([R / (mu + M) * x4 ** 2, -2.0 * R * x3 * x4 / I])


def _jac(x, M, N, M0=50.0, h=1e-6):
    """∂φ/∂(x1, x2) of φ = N (f1(x, M) − f1(x, M0)), central differences."""
    cols = []
    for j in (0, 1):
        e = np.zeros(4)
        e[j] = h
        cols.append(N @ ((_f1(x + e, M) - _f1(x + e, M0)) - (_f1(x - e, M) - _f1(x - e, M0))) / (2 * h))
    return np.array(cols).T


def test_the_bound_contains_and_nearly_attains_the_sampled_jacobian_norm(arm):
    nl = arm.nonlinearity
    N = arm.lure_plant().N()
    x1b, x3b, x4b = (0.3, 0.7), np.array([[-0.4], [0.2]]), np.array([[0.5], [1.5]])
    bound, dq = arm_slope_bound(nl, N, x1b, x3b, x4b)
    assert dq.status == "proved" and dq.gap <= 1e-3 * dq.upper
    rng = np.random.default_rng(5)
    best = 0.0
    # |x3 x4| is largest at a corner of its box; x1 and M sampled densely
    for x1 in np.linspace(*x1b, 61):
        for M in np.linspace(nl.M_min, nl.M_max, 41):
            for x3 in x3b[:, 0]:
                for x4 in x4b[:, 0]:
                    J = _jac(np.array([x1, rng.uniform(-3, 3), x3, x4]), M, N)
                    assert abs(J[0, 0]) < 1e-6 and np.all(np.abs(J[:, 1]) < 1e-6)   # the cancellations
                    best = max(best, float(np.linalg.norm(J, 2)))
    assert best <= bound[0] <= best * (1 + 5e-3)


def test_rates_at_rest_give_no_slope(arm):
    bound, _ = arm_slope_bound(arm.nonlinearity, arm.lure_plant().N(), (0.3, 0.7),
                               np.array([[0.0], [0.0]]), np.array([[-1.0], [1.0]]))
    assert bound[0] == 0.0
