"""Kinematics of the Space Station attitude (CR-185644 eqs 3.4–3.6, 4.3).

Conventions (see ``docs/ERRATA.md`` § Units, § Frames and § Kinematics):

* θ = (roll θ1, pitch θ2, yaw θ3) is a pitch–yaw–roll (2-3-1) sequence from LVLH to body:
  ``C_BL = C1(θ1) C3(θ3) C2(θ2)``; LVLH axes x = velocity, y = −orbit normal, z = nadir.
* The nadir vector c (eq 3.4) is the third column of C_BL; the LVLH angular velocity seen in
  body axes is C_BL·(0, −n, 0) (eq 4.3).
* Eq 3.6 is misprinted: its (1,1) bracket entry is cos θ3, so f11 = 1.

Cross products, the nadir vector with its Jacobian, the LVLH rate, and the attitude kinematics
θ̇ = F(θ)(ω − ω_LVLH) (eq 3.5).  All functions are pure and accept stacked inputs along leading
axes where noted; they keep the input dtype, so complex-step differentiation works through them.
"""
from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix [v×] such that ``skew(a) @ b == cross(a, b)``; v may be stacked (..., 3).

    The skew-symmetric matrices of eqs 3.2, 3.3 and 3.8.

    Parameters
    ----------
    v : (..., 3) array
        Vector(s), any unit.

    Returns
    -------
    (..., 3, 3) array
        [v×], in the unit of ``v``.
    """
    v = np.asarray(v)
    out = np.zeros(v.shape[:-1] + (3, 3), dtype=np.result_type(v.dtype, float))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b along the last axis (written out: several times faster than ``np.cross`` on 3-vectors).

    Parameters
    ----------
    a, b : (..., 3) arrays
        Vectors, any units; leading axes broadcast.

    Returns
    -------
    (..., 3) array
        a × b, in the unit of ``a`` times the unit of ``b``.
    """
    a = np.asarray(a)
    b = np.asarray(b)
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], -1)


def nadir_vector(theta: np.ndarray) -> np.ndarray:
    """Nadir unit vector in body axes, eq 3.4 (the third column of C_BL).

    Parameters
    ----------
    theta : (..., 3) array
        Roll, pitch, yaw (rad).

    Returns
    -------
    c : (..., 3) array
        Nadir unit vector (c1, c2, c3) in body axes (dimensionless).
    """
    theta = np.asarray(theta)
    s1, s2, s3 = np.sin(theta[..., 0]), np.sin(theta[..., 1]), np.sin(theta[..., 2])
    c1, c2, c3 = np.cos(theta[..., 0]), np.cos(theta[..., 1]), np.cos(theta[..., 2])
    return np.stack([-s2 * c3, c1 * s2 * s3 + s1 * c2, -s1 * s2 * s3 + c1 * c2], -1)


def nadir_vector_jacobian(theta: np.ndarray) -> np.ndarray:
    """∂c/∂θ (3×3): column k is d_k = ∂c/∂θ_k of eq 3.4.

    Used for the gravity-gradient partials that replace eqs 4.12–4.14.

    Parameters
    ----------
    theta : (3,) array
        Roll, pitch, yaw (rad).

    Returns
    -------
    (3, 3) array
        ∂c/∂θ, 1/rad.
    """
    s1, s2, s3 = np.sin(theta)
    c1, c2, c3 = np.cos(theta)
    d1 = [0.0, -s1 * s2 * s3 + c1 * c2, -c1 * s2 * s3 - s1 * c2]
    d2 = [-c2 * c3, c1 * c2 * s3 - s1 * s2, -s1 * c2 * s3 - c1 * s2]
    d3 = [s2 * s3, c1 * s2 * c3, -s1 * s2 * c3]
    return np.array([d1, d2, d3]).T


def lvlh_rate_in_body(theta: np.ndarray, n: float) -> np.ndarray:
    """Angular velocity of LVLH in body axes, C_BL·(0, −n, 0) (rad/s); ω* of eq 4.3.

    A body at rest in LVLH has absolute angular velocity ``lvlh_rate_in_body(θ, n)``
    (``docs/ERRATA.md`` § Frames).

    Parameters
    ----------
    theta : (..., 3) array
        Roll, pitch, yaw (rad).
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    omega_star : (..., 3) array
        ω* in body axes, rad/s.
    """
    theta = np.asarray(theta)
    s1, s3 = np.sin(theta[..., 0]), np.sin(theta[..., 2])
    c1, c3 = np.cos(theta[..., 0]), np.cos(theta[..., 2])
    return np.stack([-n * s3, -n * c1 * c3, n * s1 * c3], -1)


def kinematics_matrix(theta: np.ndarray) -> np.ndarray:
    """f(θ) of eq 3.6 (corrected: the (1,1) bracket entry is cos θ3, so f11 = 1).

    θ̇ = f(θ) ω + q with q = (0, n, 0) (eq 3.5, 3.7).  See ``docs/ERRATA.md`` § Kinematics.

    Parameters
    ----------
    theta : (3,) array
        Roll, pitch, yaw (rad); |θ3| < 90°.

    Returns
    -------
    f : (3, 3) array
        f(θ), dimensionless (θ̇ in rad/s per ω in rad/s).
    """
    s1, _, s3 = np.sin(theta)
    c1, _, c3 = np.cos(theta)
    return np.array([[c3, -c1 * s3, s1 * s3],
                     [0.0, c1, -s1],
                     [0.0, s1 * c3, c1 * c3]]) / c3


def attitude_rate(theta: np.ndarray, omega: np.ndarray, n: float) -> np.ndarray:
    """θ̇ = f(θ) ω + q, eq 3.5 (rad/s), for stacked inputs (..., 3).

    Written out row by row so it vectorizes; equal to ``kinematics_matrix(θ) @ ω + q``.

    Parameters
    ----------
    theta : (..., 3) array
        Roll, pitch, yaw (rad).
    omega : (..., 3) array
        Absolute angular velocity in body axes, rad/s.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    theta_dot : (..., 3) array
        θ̇, rad/s.
    """
    theta = np.asarray(theta)
    omega = np.asarray(omega)
    s1, s3 = np.sin(theta[..., 0]), np.sin(theta[..., 2])
    c1, c3 = np.cos(theta[..., 0]), np.cos(theta[..., 2])
    w1, w2, w3 = omega[..., 0], omega[..., 1], omega[..., 2]
    d2 = (c1 * w2 - s1 * w3) / c3
    d1 = w1 - s3 * d2
    d3 = s1 * w2 + c1 * w3
    return np.stack([d1, d2 + n, d3], -1)
