"""Independent references of the model tests (``test_kinematics``, ``test_dynamics``): the
direction-cosine matrix from elementary rotations, the cross-product matrix, random physically
possible inertias and attitudes, and a fourth-order central-difference Jacobian; the TEA
continuation in plain numpy (``test_tea``'s oracle of the compiled one)."""
from __future__ import annotations

import numpy as np

from acmm.model import dynamics as dyn, kinematics as kin

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


# ----------------------------------------------------------------- the TEA continuation in plain numpy
# The oracle of acmm.model.tea's compiled continuation (test_tea): the same algorithm (path, step
# control, acceptance tests, fold bisection) on the numpy residual of acmm.model.dynamics and
# acmm.model.kinematics, numpy's LAPACK solve and determinant.
def lvlh_rate_jacobian(theta, n):
    """∂ω*/∂θ (3×3) of eq 4.3, rad/s per rad (checked against differences in test_kinematics)."""
    s1, _, s3 = np.sin(theta)
    c1, _, c3 = np.cos(theta)
    return np.array([[0.0, 0.0, -n * c3],
                     [n * s1 * c3, 0.0, n * c1 * s3],
                     [n * c1 * c3, 0.0, -n * s1 * s3]])


def tea_residual_np(theta, inertia, n, bias):
    """Eq 4.1 with eq 4.3 substituted, from the model's numpy torques (ft·lbf)."""
    omega = kin.lvlh_rate_in_body(theta, n)
    return -kin.cross(omega, omega @ inertia.T) + dyn.gravity_gradient_torque(theta, inertia, n) + bias


def tea_jacobian_np(theta, inertia, n):
    """∂/∂θ of :func:`tea_residual_np` from the model's numpy partials (ft·lbf/rad)."""
    omega = kin.lvlh_rate_in_body(theta, n)
    return (dyn.gyroscopic_torque_jacobian(omega, inertia) @ lvlh_rate_jacobian(theta, n)
            + dyn.gravity_gradient_jacobian(theta, inertia, n))


def _newton_np(theta0, inertia, n, bias, max_iter=50, max_step=0.5):
    theta = np.array(theta0, float)
    scale = max(3 * n * n * np.abs(inertia).max(), 1e-300)
    thr = max(min(1e-12, 1e-13 * scale), 1e-15 * scale)
    for _ in range(max_iter):
        r = tea_residual_np(theta, inertia, n, bias)
        if np.max(np.abs(r)) <= thr:
            return theta
        try:
            step = np.linalg.solve(tea_jacobian_np(theta, inertia, n), -r)
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
    return theta if np.max(np.abs(tea_residual_np(theta, inertia, n, bias))) <= thr else None


def _continue_np(theta, path, n, max_jump=np.radians(5.0), min_step=1e-7):
    lam, step = 0.0, 0.05
    det0 = np.sign(np.linalg.det(tea_jacobian_np(theta, path(0.0)[0], n)))
    while lam < 1.0:
        trial = min(1.0, lam + step)
        inertia, bias = path(trial)
        new = _newton_np(theta, inertia, n, bias)
        ok = new is not None and np.max(np.abs(new - theta)) <= max_jump
        if ok and np.sign(np.linalg.det(tea_jacobian_np(new, inertia, n))) == det0:
            theta, lam = new, trial
            step = min(step * 1.5, 0.1)
        else:
            step *= 0.5
            if step < min_step:
                return theta, lam
    return theta, None


def tea_continuation_np(inertia, n, bias):
    """(θ, status, λ) of the continuation from the diagonal body at LVLH: status 0 solved, 1 fold
    in the products of inertia at λ, 2 fold in the bias (λ: the largest bias fraction with an
    equilibrium, by bisection)."""
    diag = np.diag(np.diag(inertia))
    theta, fold = _continue_np(np.zeros(3), lambda lam: (diag + lam * (inertia - diag), np.zeros(3)), n)
    if fold is not None:
        return theta, 1, fold
    theta, fold = _continue_np(theta, lambda lam: (inertia, lam * bias), n)
    if fold is None:
        return theta, 0, 1.0
    lo, hi = fold, 1.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        new = _newton_np(theta, inertia, n, mid * bias, max_step=0.05)
        if new is not None and np.max(np.abs(new - theta)) < np.radians(5):
            lo, theta = mid, new
        else:
            hi = mid
    return theta, 2, lo
