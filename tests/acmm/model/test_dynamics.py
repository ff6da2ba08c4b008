"""acmm.model.dynamics (CR-185644 eqs 3.1-3.9) against independent computations.

Every reference value here is built from first principles inside this file: the
direction-cosine matrix from elementary rotations, the gravity-gradient torque from a
cloud of point masses in an inverse-square field, the kinematics from a differentiated
rotation, and each analytic Jacobian from fourth-order central differences.
"""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin

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


def gg_torque_ref(theta, inertia, n):
    """3n² c × (I c) with c the third column of the independently built DCM."""
    c = dcm(theta)[:, 2]
    return 3 * n**2 * np.cross(c, inertia @ c)


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


# ----------------------------------------------------------------- frames (docs/ERRATA.md § Frames)
@pytest.mark.parametrize("case", CASES)
def test_dcm_is_pitch_yaw_roll_sequence(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    c = kin.dcm_body_from_lvlh(th)
    np.testing.assert_allclose(c, dcm(th), atol=1e-15)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("case", CASES)
def test_nadir_vector_is_third_column_of_dcm(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    np.testing.assert_allclose(kin.nadir_vector(th), dcm(th)[:, 2], atol=1e-15)
    assert np.linalg.norm(kin.nadir_vector(th)) == pytest.approx(1.0, abs=1e-15)


def test_nadir_vector_at_lvlh_and_pure_pitch():
    # At LVLH the body z axis points to nadir; a pitch θ2 tilts nadir to (−sin θ2, 0, cos θ2).
    np.testing.assert_allclose(kin.nadir_vector(np.zeros(3)), [0, 0, 1], atol=0)
    t = np.radians(30.0)
    np.testing.assert_allclose(kin.nadir_vector([0, t, 0]), [-np.sin(t), 0, np.cos(t)], atol=1e-16)


@pytest.mark.parametrize("case", CASES)
def test_lvlh_rate_is_dcm_times_minus_n_y(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    np.testing.assert_allclose(kin.lvlh_rate_in_body(th, N), dcm(th) @ [0, -N, 0], atol=1e-18)


def test_vectorized_functions_match_loops():
    rng = np.random.default_rng(RNG_SEED)
    inertia = random_inertia(rng)
    th = np.array([random_theta(rng) for _ in range(5)])
    om = rng.normal(size=(5, 3)) * 1e-3
    h = rng.normal(size=(5, 3)) * 1e3
    w = rng.normal(size=(5, 3))
    u = rng.normal(size=(5, 3)) * 10
    rhs = dyn.plant_rhs(th, om, h, inertia, N, w, u)
    for i in range(5):
        np.testing.assert_allclose(kin.nadir_vector(th)[i], dcm(th[i])[:, 2], atol=1e-15)
        np.testing.assert_allclose(kin.lvlh_rate_in_body(th, N)[i], dcm(th[i]) @ [0, -N, 0], atol=1e-18)
        np.testing.assert_allclose(dyn.gravity_gradient_torque(th, inertia, N)[i],
                                   gg_torque_ref(th[i], inertia, N), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(dyn.gyroscopic_torque(om, inertia)[i],
                                   -cross_matrix(om[i]) @ inertia @ om[i], rtol=1e-12, atol=1e-15)
        one = dyn.plant_rhs(th[i], om[i], h[i], inertia, N, w[i], u[i])
        for stacked, single in zip(rhs, one):
            np.testing.assert_allclose(stacked[i], single, rtol=1e-13, atol=1e-20)


def test_skew_is_cross_product():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(kin.skew(a) @ b, np.cross(a, b), atol=1e-15)
    np.testing.assert_allclose(kin.skew(a), cross_matrix(a), atol=0)


# ----------------------------------------------------------------- torques (eqs 3.2, 3.3)
@pytest.mark.parametrize("case", CASES)
def test_gravity_gradient_torque_from_dcm(case):
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, th = random_inertia(rng), random_theta(rng)
    ref = gg_torque_ref(th, inertia, N)
    # eq 3.3 written with the printed skew matrix of c
    c = dcm(th)[:, 2]
    np.testing.assert_allclose(ref, 3 * N**2 * cross_matrix(c) @ inertia @ c, rtol=1e-12)
    np.testing.assert_allclose(dyn.gravity_gradient_torque(th, inertia, N), ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("case", [0, 1, 2])
def test_gravity_gradient_torque_from_point_masses(case):
    """τ_gg from Newtonian gravity on six point masses that realize I (first principles).

    The masses sit on the principal axes (second moments S = tr(I)/2 − I); the Earth's centre
    lies at distance R along the nadir vector c = C_BL e3; μ = n² R³.  The exact torque
    Σ ρ_i × F_i equals 3n² c × I c up to O(ρ/R).
    """
    rng = np.random.default_rng(100 + case)
    inertia, th = random_inertia(rng), random_theta(rng, 80.0)
    j, v = np.linalg.eigh(inertia)
    s = j.sum() / 2 - j  # principal second moments
    m = 1000.0  # slug per point
    a = np.sqrt(s / (2 * m))
    rho = [sign * a[k] * v[:, k] for k in range(3) for sign in (1, -1)]
    # the masses reproduce I exactly
    i_pts = sum(m * (r @ r * np.eye(3) - np.outer(r, r)) for r in rho)
    np.testing.assert_allclose(i_pts, inertia, rtol=1e-12, atol=1e-6 * np.abs(inertia).max())
    R = 1e8  # ft
    mu = N**2 * R**3
    nadir = dcm(th) @ [0, 0, 1]  # LVLH z = nadir, expressed in body axes
    torque = np.zeros(3)
    for r in rho:
        pos = -R * nadir + r  # position of the point relative to the Earth's centre
        force = -mu * m * pos / np.linalg.norm(pos) ** 3
        torque += np.cross(r, force)
    scale = 3 * N**2 * np.abs(inertia).max()
    got = dyn.gravity_gradient_torque(th, inertia, N)
    np.testing.assert_allclose(got, torque, atol=1e-5 * scale)
    assert np.max(np.abs(got)) > 1e-2 * scale  # not a trivial zero


@pytest.mark.parametrize("case", CASES)
def test_gyroscopic_torque_eq_3_2(case):
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, om = random_inertia(rng), rng.normal(size=3) * 1e-3
    w1, w2, w3 = om
    printed = -np.array([[0, -w3, w2], [w3, 0, -w1], [-w2, w1, 0]]) @ inertia @ om
    np.testing.assert_allclose(dyn.gyroscopic_torque(om, inertia), printed, rtol=1e-12, atol=1e-14)


def test_cmg_momentum_rate_eq_3_8():
    rng = np.random.default_rng(3)
    om, h, u = rng.normal(size=3) * 1e-3, rng.normal(size=3) * 1e4, rng.normal(size=3) * 50
    w1, w2, w3 = om
    printed = u - np.array([[0, -w3, w2], [w3, 0, -w1], [-w2, w1, 0]]) @ h
    np.testing.assert_allclose(dyn.cmg_momentum_rate(om, h, u), printed, rtol=1e-13, atol=1e-12)


def test_disturbance_eq_3_9():
    bias, a, b = np.array([0.1, -0.2, 0.3]), np.array([1.0, 2.0, 1.0]), np.array([0.5, 0.5, 0.5])
    ts = np.array([0.0, 100.0, 1234.5, 5712.0])
    got = dyn.disturbance_torque(ts, bias, a, b, N)
    assert got.shape == (4, 3)
    for t, row in zip(ts, got):
        ref = [bias[i] + a[i] * np.sin(N * t) + b[i] * np.sin(2 * N * t) for i in range(3)]
        np.testing.assert_allclose(row, ref, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(dyn.disturbance_torque(t, bias, a, b, N), ref, rtol=1e-14, atol=1e-15)
    # quarter orbit: sin(nt) = 1, sin(2nt) = 0
    np.testing.assert_allclose(dyn.disturbance_torque(np.pi / 2 / N, bias, a, b, N), bias + a, atol=1e-14)


# ----------------------------------------------------------------- kinematics (eqs 3.5-3.7)
def printed_f(theta):
    """Eq 3.6 exactly as printed: (1,1) bracket entry 1 instead of cos θ3."""
    s1, s3, k1, k3 = np.sin(theta[0]), np.sin(theta[2]), np.cos(theta[0]), np.cos(theta[2])
    return np.array([[1, -k1 * s3, s1 * s3], [0, k1, -s1], [0, s1 * k3, k1 * k3]]) / k3


def kinematics_defect(theta, omega, n, f=None):
    """‖dC_BL/dt + [ω_rel×] C_BL‖ with θ̇ from eq 3.5 and a central difference in time."""
    if f is None:
        thdot = kin.attitude_rate(theta, omega, n)
    else:
        thdot = f(theta) @ omega + np.array([0, n, 0])
    dt = 1e-4 / max(np.abs(thdot).max(), 1e-300)
    dcdt = (dcm(theta + dt * thdot) - dcm(theta - dt * thdot)) / (2 * dt)
    c = dcm(theta)
    omega_rel = omega - c @ [0, -n, 0]
    return np.abs(dcdt + cross_matrix(omega_rel) @ c).max(), np.abs(dcdt).max()


@pytest.mark.parametrize("case", CASES)
def test_kinematics_from_differentiated_rotation(case):
    rng = np.random.default_rng(RNG_SEED + case)
    th = random_theta(rng)
    for n, om in ((N, rng.normal(size=3) * 1e-3), (0.4, rng.normal(size=3))):
        defect, size = kinematics_defect(th, om, n)
        assert defect < 1e-7 * size, (defect, size)
        np.testing.assert_allclose(kin.attitude_rate(th, om, n),
                                   kin.kinematics_matrix(th) @ om + [0, n, 0], rtol=1e-12, atol=1e-18)


def test_printed_eq_3_6_fails_differentiated_rotation():
    th, om = np.radians([10.0, -30.0, 25.0]), np.array([0.3, -0.5, 0.2])
    defect, size = kinematics_defect(th, om, 0.4, printed_f)
    assert defect > 1e-2 * size


def test_kinematics_f11_is_one():
    rng = np.random.default_rng(7)
    for _ in range(5):
        assert kin.kinematics_matrix(random_theta(rng))[0, 0] == pytest.approx(1.0, abs=1e-15)


@pytest.mark.parametrize("case", CASES)
def test_eq_4_2_holds_with_corrected_f(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    om_star = dcm(th) @ [0, -N, 0]
    np.testing.assert_allclose(kin.kinematics_matrix(th) @ om_star + [0, N, 0], 0, atol=1e-17)
    np.testing.assert_allclose(kin.attitude_rate(th, om_star, N), 0, atol=1e-17)


def test_eq_4_2_fails_with_printed_f():
    th = np.radians([5.0, -40.0, 20.0])
    om_star = dcm(th) @ [0, -N, 0]
    r = printed_f(th) @ om_star + [0, N, 0]
    # residual of the printed (1,1) entry: n sin θ3 (1 − 1/cos θ3) in row 1
    assert abs(r[0]) > 1e-2 * N
    assert r[0] == pytest.approx(N * np.sin(th[2]) * (1 - 1 / np.cos(th[2])), rel=1e-12)


# ----------------------------------------------------------------- analytic Jacobians
@pytest.mark.parametrize("case", CASES)
def test_nadir_vector_jacobian(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    ref = num_jac(lambda x: dcm(x)[:, 2], th, 1e-3)
    np.testing.assert_allclose(kin.nadir_vector_jacobian(th), ref, atol=1e-11)


@pytest.mark.parametrize("case", CASES)
def test_lvlh_rate_jacobian(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    ref = num_jac(lambda x: dcm(x) @ [0, -N, 0], th, 1e-3)
    np.testing.assert_allclose(kin.lvlh_rate_jacobian(th, N), ref, atol=1e-11 * N)


@pytest.mark.parametrize("case", CASES)
def test_gyroscopic_torque_jacobian(case):
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, om = random_inertia(rng), rng.normal(size=3) * 1e-3
    ref = num_jac(lambda w: -np.cross(w, inertia @ w), om, 1e-5)
    scale = np.abs(inertia).max() * 1e-3
    np.testing.assert_allclose(dyn.gyroscopic_torque_jacobian(om, inertia), ref, atol=1e-9 * scale)


@pytest.mark.parametrize("case", CASES)
def test_gravity_gradient_jacobian(case):
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, th = random_inertia(rng), random_theta(rng)
    ref = num_jac(lambda x: gg_torque_ref(x, inertia, N), th, 1e-3)
    scale = 3 * N**2 * np.abs(inertia).max()
    np.testing.assert_allclose(dyn.gravity_gradient_jacobian(th, inertia, N), ref, atol=1e-10 * scale)
    assert np.abs(ref).max() > 1e-2 * scale


def test_angular_acceleration_signs():
    """u enters ω̇ as −u, w as +w (eq 3.1)."""
    rng = np.random.default_rng(11)
    inertia, th, om = random_inertia(rng), random_theta(rng), rng.normal(size=3) * 1e-3
    base = dyn.angular_acceleration(th, om, inertia, N, np.zeros(3), np.zeros(3))
    e = np.array([0.0, 5.0, 0.0])
    np.testing.assert_allclose(dyn.angular_acceleration(th, om, inertia, N, e, np.zeros(3)) - base,
                               np.linalg.solve(inertia, e), rtol=1e-9)
    np.testing.assert_allclose(dyn.angular_acceleration(th, om, inertia, N, np.zeros(3), e) - base,
                               -np.linalg.solve(inertia, e), rtol=1e-9)


# ----------------------------------------------------------------- momentum balance
@pytest.mark.parametrize("case", CASES)
def test_total_angular_momentum_balance(case):
    """I ω̇ + ḣ + ω × (I ω + h) = τ_gg + w for arbitrary states and controls (eqs 3.1 + 3.8)."""
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, th = random_inertia(rng), random_theta(rng)
    om = rng.normal(size=3) * 1e-2
    h = rng.normal(size=3) * 2e4
    w = rng.normal(size=3) * 3
    u = rng.normal(size=3) * 150
    _, omdot, hdot = dyn.plant_rhs(th, om, h, inertia, N, w, u)
    lhs = inertia @ omdot + hdot + np.cross(om, inertia @ om + h)
    rhs = gg_torque_ref(th, inertia, N) + w
    scale = max(np.abs(inertia @ omdot).max(), np.abs(np.cross(om, h)).max(), np.abs(u).max())
    np.testing.assert_allclose(lhs, rhs, atol=1e-12 * scale)
    # and the control torque really cancels between body and CMG (non-trivial check)
    assert np.abs(hdot - u).max() > 1.0
