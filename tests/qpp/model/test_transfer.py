"""qpp.model.transfer: the modal frequency response agrees with the direct solves (an independent
computation per point), the direct one is what the report's small examples keep, and an
ill-conditioned or defective A falls back to the direct solves."""
import numpy as np
import pytest

from qpp.model.transfer import MODAL_MIN_ORDER, transfer_on_grid


def _stable(n, m, p, seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(n)
    return A, rng.standard_normal((n, m)), rng.standard_normal((p, n))


def _by_point(A, B, C, s):
    return np.array([C @ np.linalg.solve(z * np.eye(A.shape[0]) - A, B) for z in s])


@pytest.mark.parametrize("n", [6, 40, 60])
def test_modal_and_direct_agree_with_a_solve_per_point(n):
    A, B, C = _stable(n, 3, 4, n)
    s = -0.01 + 1j * np.concatenate([[0.0], np.logspace(-3, 3, 301)])
    ref = _by_point(A, B, C, s)
    scale = np.abs(ref).max()
    for method in ("direct", "modal", "auto"):
        got = transfer_on_grid(A, B, C, s, method=method)
        assert got.shape == (s.size, 4, 3)
        assert np.abs(got - ref).max() <= 1e-9 * scale, method


def test_auto_below_the_modal_order_is_the_direct_solve_bit_for_bit():
    A, B, C = _stable(MODAL_MIN_ORDER - 1, 2, 2, 1)
    s = 1j * np.logspace(-2, 2, 50)
    assert np.array_equal(transfer_on_grid(A, B, C, s), transfer_on_grid(A, B, C, s, method="direct"))


def test_defective_matrix_falls_back_to_the_direct_solve():
    n = 40
    A = -np.eye(n) + np.diag(np.ones(n - 1), 1)          # one Jordan block: V singular
    B, C = np.ones((n, 1)), np.eye(1, n)
    s = 1j * np.logspace(-2, 2, 40)
    ref = _by_point(A, B, C, s)
    got = transfer_on_grid(A, B, C, s, method="modal")
    assert np.array_equal(got, transfer_on_grid(A, B, C, s, method="direct"))
    assert np.abs(got - ref).max() <= 1e-9 * np.abs(ref).max()


def test_unknown_method_refused():
    with pytest.raises(ValueError, match="method"):
        transfer_on_grid(np.eye(2), np.ones((2, 1)), np.ones((1, 2)), [1j], method="fast")
