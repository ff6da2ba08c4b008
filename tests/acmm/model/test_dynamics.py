"""acmm.model.dynamics (CR-185644 eqs 3.1-3.9) against independent computations.

Every reference value is built from first principles, here or in this folder's ``conftest``: the
direction-cosine matrix from elementary rotations, the gravity-gradient torque from a cloud of
point masses in an inverse-square field, and each analytic Jacobian from fourth-order central
differences.
"""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model import dynamics as dyn
from acmm.model import kinematics as kin

from tests.acmm.model.conftest import (CASES, N, RNG_SEED, cross_matrix, dcm, num_jac, random_inertia,
                                       random_theta)


def gg_torque_ref(theta, inertia, n):
    """3n² c × (I c) with c the third column of the independently built DCM."""
    c = dcm(theta)[:, 2]
    return 3 * n**2 * np.cross(c, inertia @ c)


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
        one = dyn.plant_rhs(th[i], om[i], h[i], inertia, N, w[i], u[i])
        for stacked, single in zip(rhs, one):
            np.testing.assert_allclose(stacked[i], single, rtol=1e-13, atol=1e-20)


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
    """I ω̇ − τ_gg − w + u of plant_rhs is the printed −[ω×] I ω."""
    rng = np.random.default_rng(RNG_SEED + case)
    inertia, om, th = random_inertia(rng), rng.normal(size=3) * 1e-3, random_theta(rng)
    w1, w2, w3 = om
    printed = -np.array([[0, -w3, w2], [w3, 0, -w1], [-w2, w1, 0]]) @ inertia @ om
    omdot = dyn.plant_rhs(th, om, np.zeros(3), inertia, N, np.zeros(3), np.zeros(3))[1]
    scale = 3 * N**2 * np.abs(inertia).max()
    np.testing.assert_allclose(inertia @ omdot - gg_torque_ref(th, inertia, N), printed,
                               rtol=1e-12, atol=1e-15 * scale)


def test_cmg_momentum_rate_eq_3_8():
    rng = np.random.default_rng(3)
    om, h, u = rng.normal(size=3) * 1e-3, rng.normal(size=3) * 1e4, rng.normal(size=3) * 50
    w1, w2, w3 = om
    printed = u - np.array([[0, -w3, w2], [w3, 0, -w1], [-w2, w1, 0]]) @ h
    hdot = dyn.plant_rhs(np.zeros(3), om, h, np.diag([1e7, 2e7, 3e7]), N, np.zeros(3), u)[2]
    np.testing.assert_allclose(hdot, printed, rtol=1e-13, atol=1e-12)


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
    h, z = np.zeros(3), np.zeros(3)
    base = dyn.plant_rhs(th, om, h, inertia, N, z, z)[1]
    e = np.array([0.0, 5.0, 0.0])
    np.testing.assert_allclose(dyn.plant_rhs(th, om, h, inertia, N, e, z)[1] - base,
                               np.linalg.solve(inertia, e), rtol=1e-9)
    np.testing.assert_allclose(dyn.plant_rhs(th, om, h, inertia, N, z, e)[1] - base,
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
