"""acmm.model.kinematics (CR-185644 eqs 3.4-3.7, 4.2) against independent computations.

The direction-cosine matrix is built from elementary rotations (``conftest``), the kinematics from a
differentiated rotation, and each analytic Jacobian from fourth-order central differences.
"""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model import kinematics as kin

from tests.acmm.model.conftest import (CASES, N, RNG_SEED, cross_matrix, dcm, lvlh_rate_jacobian, num_jac,
                                       random_theta)


# ----------------------------------------------------------------- frames (docs/ERRATA.md § Frames)
@pytest.mark.parametrize("case", CASES)
def test_nadir_vector_is_third_column_of_dcm(case):
    th = random_theta(np.random.default_rng(RNG_SEED + case))
    c = dcm(th)
    np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(c) == pytest.approx(1.0, abs=1e-14)
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


def test_skew_is_cross_product():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(kin.skew(a) @ b, np.cross(a, b), atol=1e-15)
    np.testing.assert_allclose(kin.skew(a), cross_matrix(a), atol=0)


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
    np.testing.assert_allclose(lvlh_rate_jacobian(th, N), ref, atol=1e-11 * N)
