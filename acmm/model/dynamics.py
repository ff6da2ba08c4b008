"""Nonlinear rigid-body dynamics of the Space Station (CR-185644 eqs 3.1–3.9).

Units slug·ft², ft·lbf, ft·lbf·s, rad, s (``docs/ERRATA.md`` § Units); attitude θ, frames and the
kinematics of eqs 3.4–3.6 as in :mod:`acmm.model.kinematics`.  The control torque u enters ω̇ as −u
and ḣ as +u; the disturbance w enters ω̇ as +w (``docs/ERRATA.md`` § Momentum balance).  All
functions are pure and accept stacked inputs along leading axes where noted; they keep the input
dtype, so complex-step differentiation works through them.
"""
from __future__ import annotations

import numpy as np

from acmm.model.kinematics import attitude_rate, cross, nadir_vector, nadir_vector_jacobian, skew


def gyroscopic_torque_jacobian(omega: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """∂τ_gyro/∂ω = [(Iω)×] − [ω×] I (ft·lbf per rad/s); eqs 4.8–4.10 in matrix form.

    Parameters
    ----------
    omega : (3,) array
        Angular velocity at which to differentiate (ω* of eq 4.3), rad/s.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².

    Returns
    -------
    (3, 3) array
        ∂τ_gyro/∂ω, ft·lbf per rad/s.
    """
    return skew(inertia @ omega) - skew(omega) @ inertia


def gravity_gradient_torque(theta: np.ndarray, inertia: np.ndarray, n: float) -> np.ndarray:
    """τ_gg = 3n² c × (I c), eq 3.3 (ft·lbf), c the nadir vector of eq 3.4.

    Parameters
    ----------
    theta : (..., 3) array
        Roll, pitch, yaw (rad).
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (..., 3) array
        Gravity-gradient torque, ft·lbf.
    """
    c = nadir_vector(theta)
    return 3.0 * n * n * cross(c, c @ inertia.T)


def gravity_gradient_jacobian(theta: np.ndarray, inertia: np.ndarray, n: float) -> np.ndarray:
    """∂τ_gg/∂θ (3×3, ft·lbf/rad); column k = 3n²(d_k × I c + c × I d_k), d_k = ∂c/∂θ_k.

    This replaces the printed eqs 4.12–4.14 (4.12 has the wrong prefactor sign and a missing
    −I23·B1·C1 term in row 2; 4.13–4.14 are garbled beyond repair); see ``docs/ERRATA.md``
    § Linearization.

    Parameters
    ----------
    theta : (3,) array
        Roll, pitch, yaw at which to differentiate (θ*), rad.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    (3, 3) array
        ∂τ_gg/∂θ, ft·lbf/rad.
    """
    c = nadir_vector(theta)
    d = nadir_vector_jacobian(theta)
    # d_k × Ic + c × I d_k for all k at once: (−[Ic×] + [c×] I) D
    return 3.0 * n * n * ((skew(c) @ inertia - skew(inertia @ c)) @ d)


def disturbance_torque(t, bias: np.ndarray, a: np.ndarray, b: np.ndarray, n: float) -> np.ndarray:
    """w(t) = bias + A sin(nt) + B sin(2nt), eq 3.9 (ft·lbf); ``t`` scalar or (N,) s.

    Parameters
    ----------
    t : float or (N,) array
        Time, s.
    bias : (3,) array
        Constant (bias) torque, ft·lbf.
    a : (3,) array
        Amplitude A of sin(nt) per axis, ft·lbf.
    b : (3,) array
        Amplitude B of sin(2nt) per axis, ft·lbf.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    w : (3,) or (N, 3) array
        Disturbance torque, ft·lbf (one row per time when ``t`` is an array).
    """
    t = np.asarray(t, float)[..., None]
    return np.asarray(bias) + np.asarray(a) * np.sin(n * t) + np.asarray(b) * np.sin(2 * n * t)


def plant_rhs(theta, omega, h, inertia, n, w, u):
    """Right-hand side of eqs 3.1, 3.5, 3.8: returns (θ̇, ω̇, ḣ).

    I ω̇ = τ_gyro + τ_gg + (w − u) with τ_gyro = −ω × (I ω) (eq 3.2); ḣ = u − ω × h (eq 3.8).
    Signs of u and w: ``docs/ERRATA.md`` § Momentum balance.

    Parameters
    ----------
    theta : (..., 3) array
        Roll, pitch, yaw (rad).
    omega : (..., 3) array
        Absolute angular velocity in body axes, rad/s.
    h : (..., 3) array
        CMG momentum in body axes, ft·lbf·s.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    n : float
        Orbital rate, rad/s.
    w : (..., 3) array
        Disturbance torque (eq 3.9), ft·lbf.
    u : (..., 3) array
        CMG control torque, ft·lbf.

    Returns
    -------
    theta_dot : (..., 3) array
        θ̇ (eq 3.5), rad/s.
    omega_dot : (..., 3) array
        ω̇ (eq 3.1), rad/s².
    h_dot : (..., 3) array
        ḣ (eq 3.8), ft·lbf.
    """
    omega = np.asarray(omega)
    torque = -cross(omega, omega @ inertia.T) + gravity_gradient_torque(theta, inertia, n) + w - u
    return attitude_rate(theta, omega, n), torque @ np.linalg.inv(inertia).T, u - cross(omega, h)
