"""Plain-numpy right-hand side of the closed loop simulated by :mod:`acmm.simulate.kernel` (eqs 3.1–3.9,
ch. 4–5), built from :mod:`acmm.model.dynamics` independently of the compiled kernel.
"""
from __future__ import annotations

import numpy as np

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin
from acmm.model.linearize import DRF_INPUTS
from acmm.simulate.scenario import Scenario


def rhs_numpy(t: float, X: np.ndarray, sc: Scenario, level: int = 0) -> np.ndarray:
    """Plain-numpy right-hand side of the same closed loop, from :mod:`acmm.model.dynamics`.

    The independent reference for the compiled kernel and the ``solve_ivp`` baseline
    (eqs 3.1, 3.5, 3.8, 3.9, 4.35–4.40 and 5.1; ``docs/ERRATA.md`` § Saturation).

    Parameters
    ----------
    t : float
        Time, s.
    X : (24,) array
        Plain state X, in the units of :mod:`acmm.simulate.scenario`.
    sc : Scenario
        The closed loop (units in :class:`Scenario`).
    level : int
        Index of the inertia level in force.

    Returns
    -------
    (24,) array
        Ẋ, in the units of X per second.
    """
    n = sc.n
    omega, theta, h = X[0:3], X[3:6], X[6:9]
    th_est = sc.theta_est[level]
    om_est = kin.lvlh_rate_in_body(th_est, n)
    theta_dot = kin.attitude_rate(theta, omega, n)
    x = np.concatenate([[omega[0] - om_est[0], theta_dot[1], omega[2] - om_est[2]],
                        theta - th_est, X[6:24]])
    u = np.clip(-sc.gain[level] @ x, -sc.torque_limit, sc.torque_limit)
    absorbed = np.cross(omega, h)
    at_limit = (np.abs(h) >= sc.momentum_limit) & ((u - absorbed) * h > 0)
    u = np.where(at_limit, absorbed, u)
    w = dyn.disturbance_torque(t, sc.bias[level], sc.harmonic_a, sc.harmonic_b, n)
    _, omega_dot, h_dot = dyn.plant_rhs(theta, omega, h, sc.inertia[level], n, w, u)
    # DRFs at n, then 2n: (α̇, α)' = (−ω_f² α + input, α̇)
    wf = np.repeat([n, 2 * n], 3)
    d_drf = np.stack([-wf * wf * X[13:24:2] + x[list(DRF_INPUTS[sc.drf_mode] * 2)], X[12:24:2]], -1).ravel()
    return np.concatenate([omega_dot, theta_dot, h_dot, h, d_drf])
