"""The matrix sign function of eqs 5.5-5.6 (acmm.design.matrix_sign) against its spectral
definition through an eigendecomposition, and the printed denominator of eq 5.6 that never gives it."""
import numpy as np
import pytest

from acmm_qpp.errors import ConvergenceError
from acmm.design.matrix_sign import matrix_sign

from tests.acmm.design.conftest import (SB02PD_A, SB02PD_B, SB02PD_Q, _hamiltonian, _random_problem,
                                        _sign_by_eig)


def test_sign_iteration_matches_spectral_definition():
    rng = np.random.default_rng(5)
    A, B, Q, R = _random_problem(rng, nx=8)
    H = _hamiltonian(A, B @ np.linalg.solve(R, B.T), Q)
    ref = _sign_by_eig(H)
    for scaling in ("det", "norm", None):
        for evaluation in ("partial_fraction", "polynomial"):
            s = matrix_sign(H, scaling=scaling, evaluation=evaluation)
            np.testing.assert_allclose(s.S, ref, atol=1e-9 * np.linalg.norm(ref))
            assert s.iterations < 15


def test_partial_fraction_is_the_rational_map_of_eq_5_6():
    """One unscaled step in both evaluations is the same matrix (corrected eq 5.6)."""
    rng = np.random.default_rng(2)
    S = rng.standard_normal((5, 5)) + 3 * np.eye(5)
    one_pf = matrix_sign(S, scaling=None, max_iter=1, tol=np.inf)
    one_poly = matrix_sign(S, scaling=None, max_iter=1, tol=np.inf, evaluation="polynomial")
    I = np.eye(5)
    S2 = S @ S
    expect = S @ (5 * I + 10 * S2 + S2 @ S2) @ np.linalg.inv(I + 10 * S2 + 5 * S2 @ S2)
    np.testing.assert_allclose(one_pf.S, expect, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(one_poly.S, expect, rtol=1e-12, atol=1e-12)


def test_printed_denominator_of_eq_5_6_does_not_give_the_sign():
    """docs/ERRATA.md § Riccati sign function: the printed I + 10S + 5S⁴ never converges to the sign function."""
    f = lambda x: x * (5 + 10 * x**2 + x**4) / (1 + 10 * x + 5 * x**4)   # noqa: E731
    # scalar: −1 is not a fixed point (sign(−1) = −1 but f(−1) = 4) ...
    assert f(-1.0) == pytest.approx(4.0)
    # ... and iterates from the left half-line either end at +1 (wrong) or wander near −2
    x = -0.5
    for _ in range(100):
        x = f(x)
    assert x == pytest.approx(1.0)
    xs = [-3.0]
    for _ in range(200):
        xs.append(f(xs[-1]))
    assert np.ptp(xs[-20:]) > 0.1 and max(xs[-20:]) < 0
    # matrix: SB02PD's Hamiltonian, with and without scaling
    H = _hamiltonian(SB02PD_A, SB02PD_B @ SB02PD_B.T, SB02PD_Q)
    for scaling in ("det", None):
        with pytest.raises(ConvergenceError, match="printed"):
            matrix_sign(H, form="printed", scaling=scaling, max_iter=300)
    # the corrected iteration converges, to the spectral sign
    np.testing.assert_allclose(matrix_sign(H).S, _sign_by_eig(H), atol=1e-12)
    # a random Hamiltonian
    A, B, Q, R = _random_problem(np.random.default_rng(1))
    H = _hamiltonian(A, B @ np.linalg.solve(R, B.T), Q)
    with pytest.raises(ConvergenceError):
        matrix_sign(H, form="printed", max_iter=300)


def test_sign_of_matrix_with_imaginary_eigenvalues_fails():
    with pytest.raises(ConvergenceError, match="matrix sign"):
        matrix_sign(np.array([[0.0, 1.0], [-1.0, 0.0]]), max_iter=40)
