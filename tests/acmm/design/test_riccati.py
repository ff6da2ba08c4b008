"""Riccati solvers (eq 5.4), acmm.design.riccati.

References are independent of the code under test: SLICOT SB02PD's published example, the residual
of eq 5.4 written out in the test, and scipy's solver called directly.
"""
import numpy as np
import pytest
import scipy.linalg as sla

from acmm_qpp.errors import ConvergenceError
from acmm.design.riccati import METHODS, care_residual, other_method_hint, residual_hint, solve_care

from tests.acmm.design.conftest import SB02PD_A, SB02PD_B, SB02PD_Q, SB02PD_X, _hamiltonian, _random_problem


def _residual_by_hand(A, B, Q, R, P):
    res = A.T @ P + P @ A - P @ B @ np.linalg.inv(R) @ B.T @ P + Q
    return np.linalg.norm(res) / np.linalg.norm(P @ B @ np.linalg.inv(R) @ B.T @ P)


@pytest.mark.parametrize("method", METHODS)
def test_sb02pd_published_example(method):
    r = solve_care(SB02PD_A, SB02PD_B, SB02PD_Q, 1.0, method=method)
    np.testing.assert_allclose(r.P, SB02PD_X, atol=1e-12)
    np.testing.assert_allclose(r.K, [[1.0, 2.0]], atol=1e-12)  # K = R⁻¹B'X = second row of X
    assert r.residual < 1e-14 and r.method == method


@pytest.mark.parametrize("seed", range(5))
def test_three_methods_agree_on_random_problems(seed):
    rng = np.random.default_rng(seed)
    A, B, Q, R = _random_problem(rng, nx=6 + seed)
    ref = sla.solve_continuous_are(A, B, Q, R)
    for method in METHODS:
        r = solve_care(A, B, Q, R, method=method)
        np.testing.assert_allclose(r.P, ref, rtol=1e-8, atol=1e-8 * np.linalg.norm(ref))
        # stabilizing, and the residual written out here
        assert np.max(np.linalg.eigvals(A - B @ r.K).real) < 0
        assert _residual_by_hand(A, B, Q, R, r.P) < 1e-10


def test_residual_is_independent_of_solver_and_can_fail():
    A, B, Q, R = _random_problem(np.random.default_rng(7))
    X = sla.solve_continuous_are(A, B, Q, R)
    assert care_residual(A, B, Q, R, X) < 1e-12
    # definition: ‖res‖_F / (‖Q‖ + 2‖A'P‖ + ‖PGP‖), checked on a perturbed solution
    Xp = X + 1e-3 * np.eye(len(X))
    G = B @ np.linalg.solve(R, B.T)
    res = A.T @ Xp + Xp @ A - Xp @ G @ Xp + Q
    den = np.linalg.norm(Q) + 2 * np.linalg.norm(A.T @ Xp) + np.linalg.norm(Xp @ G @ Xp)
    assert care_residual(A, B, Q, R, Xp) == pytest.approx(np.linalg.norm(res) / den, rel=1e-12)
    assert care_residual(A, B, Q, R, Xp) > 1e-6


@pytest.mark.parametrize("method", METHODS)
def test_residual_above_tolerance_refuses(method):
    A, B, Q, R = _random_problem(np.random.default_rng(3))
    with pytest.raises(ConvergenceError, match=rf"method='{method}'.*backward error .* exceeds tolerance 1\.0e-30"):
        solve_care(A, B, Q, R, method=method, tol=1e-30)


def test_scaling_maps_back_to_physical_units():
    """A badly scaled problem (states of magnitude 1e-5 … 1e6) solved with scale=d equals the
    well-scaled problem mapped by x = D x̃."""
    rng = np.random.default_rng(11)
    At, Bt, Qt, R = _random_problem(rng, nx=6)
    d = 10.0 ** np.array([-5, -2, 0, 2, 4, 6])
    A = At * d[:, None] / d[None, :]        # x = D x̃  ⇒  A = D Ã D⁻¹
    B = Bt * d[:, None]
    Q = Qt / d[:, None] / d[None, :]
    Xt = sla.solve_continuous_are(At, Bt, Qt, R)
    for method in METHODS:
        r = solve_care(A, B, Q, R, method=method, scale=d)
        np.testing.assert_allclose(r.P * d[:, None] * d[None, :], Xt, rtol=1e-8,
                                   atol=1e-9 * np.linalg.norm(Xt))
        np.testing.assert_allclose(r.K * d[None, :], np.linalg.solve(R, Bt.T @ Xt), rtol=1e-8,
                                   atol=1e-9 * np.linalg.norm(Xt))
        assert r.residual == pytest.approx(care_residual(At, Bt, Qt, R, r.P * np.outer(d, d)),
                                           rel=1e-6, abs=1e-15)


def test_not_stabilizable_refuses():
    """An uncontrollable unstable mode: no stabilizing solution exists."""
    A = np.diag([1.0, -1.0])
    B = np.array([[0.0], [1.0]])
    for method in METHODS:
        with pytest.raises(ConvergenceError):
            solve_care(A, B, np.eye(2), 1.0, method=method)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("w", [1.0, 1e-3])
def test_undamped_oscillator_with_zero_q_is_refused(method, w):
    """ẍ = −w²x + u, Q = 0: the Hamiltonian is block triangular with eig(A) = ±jw and
    eig(−A') = ±jw, all on the imaginary axis; the only solution P = 0 leaves A − BK = A
    undamped, so there is no stabilizing solution (closed form)."""
    A = np.array([[0.0, 1.0], [-w * w, 0.0]])
    B = np.array([[0.0], [1.0]])
    H = _hamiltonian(A, B @ B.T, np.zeros((2, 2)))
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(H).imag)), [w, w, w, w], rtol=1e-9)
    with pytest.raises(ConvergenceError, match="no stabilizing solution.*imaginary axis"):
        solve_care(A, B, np.zeros((2, 2)), 1.0, method=method)


@pytest.mark.parametrize("method", METHODS)
def test_double_imaginary_hamiltonian_pair_is_refused(method):
    """Closed form: A = [[0, 1], [−1, 0]], B = e2, R = 1, Q = diag(q1, q2).  With
    (sI − A)⁻¹B = [1, s]'/(s² + 1) the Hamiltonian's characteristic polynomial is
    (s² + 1)² + q1 − q2 s² = s⁴ + (2 − q2)s² + 1 + q1, which equals (s² + ω0²)² for
    q2 = 2 − 2ω0², q1 = ω0⁴ − 1: a double eigenvalue pair ±jω0 on the imaginary axis (ω0 = 2:
    Q = diag(15, −6)).  Rounding splits it by ~1e-8, and an unchecked solver returns
    closed-loop poles that look stable; solve_care must refuse."""
    w0 = 2.0
    A = np.array([[0.0, 1.0], [-1.0, 0.0]])
    B = np.array([[0.0], [1.0]])
    Q = np.diag([w0 ** 4 - 1.0, 2.0 - 2.0 * w0 ** 2])
    H = _hamiltonian(A, B @ B.T, Q)
    np.testing.assert_allclose(np.poly(H), [1, 0, 2 * w0 ** 2, 0, w0 ** 4], atol=1e-9)
    lam = np.linalg.eigvals(H)
    assert np.max(np.abs(lam.real)) < 1e-6 and np.allclose(np.sort(np.abs(lam.imag)), w0, atol=1e-6)
    with pytest.raises(ConvergenceError, match="no stabilizing solution.*imaginary axis"):
        solve_care(A, B, Q, 1.0, method=method)
    # the same problem moved off the axis (A − 0.5I) has a stabilizing solution again
    r = solve_care(A - 0.5 * np.eye(2), B, Q, 1.0, method=method)
    assert np.max(np.linalg.eigvals(A - 0.5 * np.eye(2) - B @ r.K).real) < 0


@pytest.mark.parametrize("seed", range(3))
def test_condition_estimate_matches_kronecker_definition(seed):
    """κ_CARE = ‖Ω⁻¹‖(‖Q‖ + 2‖A‖‖P‖ + ‖G‖‖P‖²)/‖P‖, with ‖Ω⁻¹‖ computed independently as
    1/σmin of the Kronecker matrix I⊗A_c' + A_c'⊗I (the Frobenius-induced norm, within a factor
    √n of the 2-norm-induced one that solve_care obtains from one Lyapunov solve)."""
    rng = np.random.default_rng(seed)
    A, B, Q, R = _random_problem(rng, nx=5)
    r = solve_care(A, B, Q, R)
    P = sla.solve_continuous_are(A, B, Q, R)
    G = B @ np.linalg.inv(R) @ B.T
    Ac = A - G @ P
    n = A.shape[0]
    L = np.kron(np.eye(n), Ac.T) + np.kron(Ac.T, np.eye(n))
    inv_f = 1.0 / np.linalg.svd(L, compute_uv=False)[-1]
    nrm = lambda M: np.linalg.norm(M, 2)  # noqa: E731
    top = nrm(Q) + 2 * nrm(A) * nrm(P) + nrm(G) * nrm(P) ** 2
    kf = inv_f * top / nrm(P)
    assert kf / np.sqrt(n) <= r.condition * (1 + 1e-8) and r.condition <= kf * np.sqrt(n) * (1 + 1e-8)
    assert not r.ill_conditioned


def test_ill_conditioned_solution_is_flagged():
    """Double integrator, Q = diag(q, 0), R = 1 (closed form P12 = √q, P22 = √2 q^¼,
    P11 = √2 q^¾): for q = 1e-16 the entries of P span 12 decades and the closed-loop poles
    sit at ~q^¼ = 1e-4, so κ_CARE ≈ 1/q^¼·… ≫ 1/√ε — solved, but flagged."""
    q = 1e-16
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    B = np.array([[0.0], [1.0]])
    r = solve_care(A, B, np.diag([q, 0.0]), 1.0)
    exact = np.array([[np.sqrt(2) * q ** 0.75, np.sqrt(q)], [np.sqrt(q), np.sqrt(2) * q ** 0.25]])
    np.testing.assert_allclose(r.P, exact, rtol=1e-6)
    assert r.ill_conditioned and r.condition > 1.0 / np.sqrt(np.finfo(float).eps)
    well = solve_care(A, B, np.diag([1.0, 0.0]), 1.0)
    assert not well.ill_conditioned and well.condition < 100


# --- refinement and the backward error that decides acceptance (issue 30) --------------------

def _backward_error_by_hand(A, B, Q, R, P):
    """ω of acmm.design.riccati.care_backward_error written out: ‖ℛ(P)‖ over the size of the terms
    as floating point evaluates them, |A|ᵀ|P| + |P||A| + |P||G||P| + |Q| (Frobenius)."""
    G = B @ np.linalg.inv(R) @ B.T
    res = A.T @ P + P @ A - P @ G @ P + Q
    size = abs(A).T @ abs(P) + abs(P) @ abs(A) + abs(P) @ abs(G) @ abs(P) + abs(Q)
    return np.linalg.norm(res) / np.linalg.norm(size)


def test_refinement_recovers_a_perturbed_solution():
    """Newton–Kleinman refinement (acmm.design.riccati.refine_care) from scipy's answer perturbed by
    1e-6 relative returns to scipy's answer to 1e-12, with a residual at rounding level."""
    from acmm.design.riccati import refine_care

    rng = np.random.default_rng(11)
    A, B, Q, R = _random_problem(rng, nx=8, m=3)
    X = sla.solve_continuous_are(A, B, Q, R)
    E = rng.standard_normal(X.shape)
    P0 = X + 1e-6 * np.linalg.norm(X) * (E + E.T) / 2
    assert _residual_by_hand(A, B, Q, R, P0) > 1e-7
    P, steps = refine_care(A, B, Q, R, P0)
    assert 1 <= steps <= 6
    assert np.linalg.norm(P - X) <= 1e-12 * np.linalg.norm(X)
    assert _residual_by_hand(A, B, Q, R, P) < 1e-14


def _claim1_problem():
    """The α-shifted CARE of the cross-inertia-free MB3 model (claim 1, ch. 6) in the design's
    state scaling: nearly uncontrollable (PBH ratio ~3e-8 at s = 0)."""
    from acmm.model import linearize as lin
    from acmm.api import load_config
    from acmm.stages.runners import _compute_tea

    cfg = load_config("mb3_decoupled")
    n = cfg.orbit_rate
    inertia, tea = cfg.inertia.matrix(), _compute_tea(cfg).tea
    m = lin.design_point(inertia, tea.theta, n, model="no_cross_inertia")
    return m.A + 0.5 * n * np.eye(m.A.shape[0]), m.B, np.zeros_like(m.A), 1e-4 * np.eye(3), m.scales


@pytest.mark.parametrize("method", METHODS)
def test_nearly_uncontrollable_claim1_model_solves_with_every_method(method):
    """Claim 1's model: P spans ~10 orders of magnitude, its relative residual stays far above
    rounding for every method (the cancelling terms of PGP), while the backward error computed
    here by hand is at rounding level: accepted by every method, every closed-loop pole stable,
    and the three methods' gains agree to the accuracy the conditioning allows."""
    A, B, Q, R, d = _claim1_problem()
    r = solve_care(A, B, Q, R, method=method, scale=d)
    As, Bs = A / d[:, None] * d[None, :], B / d[:, None]
    Ps = r.P * d[:, None] * d[None, :]
    assert _backward_error_by_hand(As, Bs, Q, R, Ps) < 1e-14
    assert np.ptp(np.log10(np.abs(np.diag(Ps)))) > 8
    assert np.max(np.linalg.eigvals(A - B @ r.K).real) < 0
    # κ_CARE of this problem is astronomically large (flagged): the methods' gains differ by
    # ~1e-4 relative (measured 1.0e-4–1.2e-4 under the Haswell kernel), not by rounding
    assert r.ill_conditioned
    Rs = sla.solve_continuous_are(As, Bs, Q, R)              # scipy itself, unrefined, unchecked
    ref = np.linalg.solve(R, Bs.T @ Rs) / d[None, :]
    assert np.linalg.norm(r.K - ref) <= 1e-3 * np.linalg.norm(ref)


def test_a_riccati_hint_never_suggests_the_method_that_failed():
    for used in METHODS:
        for hint in (other_method_hint(used), residual_hint(used)):
            others = hint.split("riccati_method", 1)[1].split(";")[0]
            assert used not in others and all(m in others for m in METHODS if m != used), hint
