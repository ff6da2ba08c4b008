"""Independent references of the model tests (``test_kinematics``, ``test_dynamics``): the
direction-cosine matrix from elementary rotations, the cross-product matrix, random physically
possible inertias and attitudes, and a fourth-order central-difference Jacobian."""
from __future__ import annotations

import numpy as np

N = 0.0011  # rad/s
RNG_SEED = 20240502


# ----------------------------------------------------------------- independent helpers
def c1(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, s], [0, -s, c]], float)


def c2(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]], float)


def c3(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]], float)


def dcm(theta):
    """C_BL of the pitch-yaw-roll (2-3-1) sequence: C1(θ1) C3(θ3) C2(θ2)."""
    return c1(theta[0]) @ c3(theta[2]) @ c2(theta[1])


def cross_matrix(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]], float)


def random_inertia(rng, scale=2e7):
    """A physically possible inertia (triangle inequality) in a random body frame."""
    while True:
        j = rng.uniform(0.1, 1.0, 3) * scale
        if j[0] + j[1] > j[2] and j[0] + j[2] > j[1] and j[1] + j[2] > j[0]:
            break
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q @ np.diag(j) @ q.T


def random_theta(rng, limit_deg=70.0):
    return np.radians(rng.uniform(-limit_deg, limit_deg, 3))


def num_jac(fun, x, h):
    """Fourth-order central-difference Jacobian (columns = d fun / d x_k)."""
    x = np.asarray(x, float)
    cols = []
    for k in range(x.size):
        e = np.zeros_like(x)
        e[k] = h
        cols.append((-fun(x + 2 * e) + 8 * fun(x + e) - 8 * fun(x - e) + fun(x - 2 * e)) / (12 * h))
    return np.array(cols).T


CASES = list(range(8))
