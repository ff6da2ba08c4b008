"""Spheres and thresholds (qpp.design.spheres): the printed threshold m, signal norms against
quadrature, β1 in both readings of eq 10.7, the H∞ norm of SLICOT AB13DD as python-control's."""
import numpy as np
import pytest
import scipy.integrate as si

from qpp.design import spheres
from qpp.io.config import load_config
from qpp.model.lure import closed_loop

from tests.qpp.conftest import _pub


def test_threshold_m_printed():
    assert round(spheres.threshold_m(0.2, 0.1, 0.0, 0.02727, 0.05 * 0.363), 5) == 1.61807
    assert round(spheres.threshold_m(0.14, 0.0, 0.0, 0.018, 0.056), 4) == 2.3923
    # docs/ERRATA.md § QPP thresholds: printed beta3 = 0.05 ||(sin 5t)_T||_2, T = 0.5 s (to 1e-3)
    assert spheres.beta3_sinusoidal(0.05, 5.0, 0.5) == pytest.approx(0.02727, rel=1e-3)
    # the definition with sin t gives a smaller value
    assert spheres.beta3_sinusoidal(0.05, 1.0, 0.5) < 0.02727


def test_signal_norms_against_quadrature():
    for w, T in [(5.0, 0.5), (1.0, 3.0), (0.0, 2.0)]:
        q = np.sqrt(si.quad(lambda t: np.sin(w * t) ** 2 if w else 1.0, 0, T)[0])
        assert spheres.sin_l2(w, T) == pytest.approx(q, rel=1e-10)
    a, T = 0.3, 2.0
    assert spheres.E_factor(a, T) == pytest.approx(np.sqrt(si.quad(lambda t: np.exp(2 * a * t), 0, T)[0]))
    assert spheres.E_factor(1e-12, 0.5) == pytest.approx(np.sqrt(0.5))


def _peak_gain_independent(A, B, C):
    """sup_ω σmax(C (jωI − A)⁻¹ B) by a dense log grid refined with scipy's bounded search —
    written here, independent of qpp.design.spheres."""
    from scipy.optimize import minimize_scalar

    n = len(A)

    def sig(w):
        return np.linalg.svd(C @ np.linalg.solve(1j * w * np.eye(n) - A, B), compute_uv=False)[0]

    w = np.concatenate([[0.0], np.logspace(-4, 5, 6000)])
    g = np.array([sig(x) for x in w])
    k = int(np.argmax(g))
    lo, hi = w[max(k - 1, 0)], w[min(k + 1, len(w) - 1)]
    if hi > lo:
        res = minimize_scalar(lambda x: -sig(x), bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-10 * max(hi, 1.0)})
        return max(g[k], -res.fun)
    return g[k]


@pytest.mark.parametrize("name,a,verdict", [
    ("qpp_siso", 1e-8, {"eq10.7": True, "printed": False}),
    ("qpp_manipulator", 1e-9, {"eq10.7": True, "printed": True}),
])
def test_beta1_both_readings(name, a, verdict):
    cfg = load_config(name)
    m = cfg.published.m
    for rd in ("eq10.7", "printed"):
        Az, Bz, Cz = closed_loop(cfg.lure_plant(), *_pub(cfg), bz=rd)
        b = spheres.beta1(Az, Bz, Cz, a)
        ham, _ = spheres.hinf_norm(Az + a * np.eye(len(Az)), Bz, Cz, method="hamiltonian")
        assert b["value"] == pytest.approx(ham, rel=1e-7)          # two independent exact methods
        assert b["grid_value"] <= b["value"] * (1 + 1e-9)          # grid is a lower bound ...
        assert b["grid_value"] > b["value"] * (1 - 1e-3)           # ... and close
        indep = _peak_gain_independent(Az + a * np.eye(len(Az)), Bz, Cz)
        assert b["value"] == pytest.approx(indep, rel=1e-6)
        assert (b["value"] <= m) is verdict[rd]                     # the report's verdict, per reading
        assert b["value"] != pytest.approx(cfg.published.beta1, rel=1e-4)   # printed beta1 matches neither


def test_hinf_norm_slycot_is_control_linfnorm_bit_for_bit():
    """hinf_norm(method="slycot") calls SLICOT AB13DD itself (no python-control import, issue 16):
    the same numbers as control.linfnorm, bit for bit, and the Hamiltonian bisection agrees."""
    import control as ct

    rng = np.random.default_rng(7)
    systems = []
    for n, m, p in ((1, 1, 1), (4, 2, 3), (6, 3, 2), (9, 1, 1)):
        A = rng.standard_normal((n, n))
        A -= (np.abs(np.linalg.eigvals(A).real).max() + 0.3) * np.eye(n)     # stable
        systems.append((A, rng.standard_normal((n, m)), rng.standard_normal((p, n)), np.zeros((p, m))))
    A, B, C, _ = systems[1]
    systems.append((A, B, C, rng.standard_normal((3, 2))))                    # feed-through
    systems.append((A + np.diag([3.0, 0, 0, 0]), B, C, np.zeros((3, 2))))   # L∞ of an unstable one
    cfg = load_config("qpp_manipulator")
    Az, Bz, Cz = closed_loop(cfg.lure_plant(), *_pub(cfg))
    systems.append((Az + 1e-9 * np.eye(len(Az)), Bz, Cz, np.zeros((Cz.shape[0], Bz.shape[1]))))
    for A, B, C, D in systems:
        got = spheres.hinf_norm(A, B, C, D)
        ref = ct.linfnorm(ct.ss(A, B, C, D))
        assert got == (float(ref[0]), float(ref[1]))
        if not np.any(D) and np.linalg.eigvals(A).real.max() < 0:
            ham, _ = spheres.hinf_norm(A, B, C, D, method="hamiltonian")
            assert got[0] == pytest.approx(ham, rel=1e-7)
    assert spheres.hinf_norm(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[3.0, 4.0]]) == (5.0, 0.0)


def test_hinf_norm_slycot_pole_on_the_axis_is_unbounded_like_control():
    import control as ct

    for A in ([[0.0]], [[0.0, 1.0], [-1.0, 0.0]]):
        n = len(A)
        got = spheres.hinf_norm(A, np.ones((n, 1)), np.ones((1, n)))
        assert got[0] == np.inf
        assert got == tuple(float(v) for v in ct.linfnorm(ct.ss(A, np.ones((n, 1)), np.ones((1, n)), 0)))


def _l2_to_peak_mp(A, B, C, dps=40):
    """(λ_max(C P Cᵀ))^½ with A P + P Aᵀ + B Bᵀ = 0, by a Kronecker solve in mpmath at ``dps`` digits."""
    import mpmath as mp

    with mp.workdps(dps):
        n = A.shape[0]
        K = mp.zeros(n * n, n * n)
        for i in range(n):
            for j in range(n):
                for k in range(n):
                    K[j * n + i, j * n + k] += A[i, k]     # (I ⊗ A) vec P, vec column by column
                    K[j * n + i, k * n + i] += A[j, k]     # (A ⊗ I) vec P
        BB = mp.matrix(B.tolist()) * mp.matrix(B.tolist()).T
        x = mp.lu_solve(K, mp.matrix([-BB[i, j] for j in range(n) for i in range(n)]))
        P = mp.matrix([[x[j * n + i] for j in range(n)] for i in range(n)])
        M = mp.matrix(C.tolist()) * P * mp.matrix(C.tolist()).T
        return float(mp.sqrt(max(mp.eigsy((M + M.T) / 2)[0])))


def test_l2_to_peak_gain_of_a_badly_scaled_loop_to_full_precision():
    """The L2-to-peak gain is similarity invariant; a loop whose ‖A‖ is 1e8 times its eigenvalues
    (large gains, as ch. 13's qpp_siso_certified: there the plain Lyapunov solve lost 1e-5,
    below the true gain, which the premise peak must not underestimate) agrees with a 40-digit
    Kronecker solve to 1e-12, and with the same loop written well scaled."""
    rng = np.random.default_rng(7)
    A0 = rng.standard_normal((4, 4)) - 4.0 * np.eye(4)
    B0, C0 = rng.standard_normal((4, 2)), rng.standard_normal((1, 4))
    S = np.diag([1e-5, 1.0, 1e3, 1e5])
    A, B, C = S @ A0 @ np.linalg.inv(S), S @ B0, C0 @ np.linalg.inv(S)
    assert np.linalg.norm(A, 2) > 1e8 * np.abs(np.linalg.eigvals(A)).max()
    exact = _l2_to_peak_mp(A0, B0, C0)
    assert spheres.l2_to_peak_gain(A, B, C) == pytest.approx(exact, rel=1e-12)
    assert spheres.l2_to_peak_gain(A0, B0, C0) == pytest.approx(exact, rel=1e-12)
