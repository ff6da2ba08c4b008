"""The circle criterion decided by the KYP lemma (issue 43): it agrees with the frequency grid of
lemma 1 where the grid resolves the response, and refuses a resonance narrower than the grid."""
from __future__ import annotations

import numpy as np
import pytest

from qpp.design.circle import circle_criterion
from qpp.design.circle_kyp import circle_kyp


def _siso(zeta, w0=2.0):
    """ẋ = A x + B φ(y): a second-order mode of damping ζ, H(s) = w0² / (s² + 2ζ w0 s + w0²)."""
    A = np.array([[0.0, 1.0], [-w0 ** 2, -2 * zeta * w0]])
    return A, np.array([[0.0], [w0 ** 2]]), np.array([[1.0, 0.0]])


@pytest.mark.parametrize("sector", [(-0.5, 0.5), (-0.9, 0.2), (0.0, 0.3), (0.1, 0.8), (-1.5, 1.5), (-0.2, 2.5)])
def test_kyp_agrees_with_the_grid_for_one_channel(sector):
    A, B, C = _siso(0.4)
    grid = circle_criterion(A, B, C, [sector]).passed
    kyp = circle_kyp(A, B, C, [sector])
    assert kyp.proved == grid
    # the peak gain the Hamiltonian decides equals an independent dense frequency sweep
    c, r = 0.5 * (sector[0] + sector[1]), 0.5 * (sector[1] - sector[0])
    if kyp.hurwitz:
        w = np.linspace(0, 50, 200001)
        H = (C @ np.linalg.solve(1j * w[:, None, None] * np.eye(2) - A - c * B @ C, B))[:, 0, 0]
        assert kyp.gain == pytest.approx(r * np.abs(H).max(), rel=1e-6)


def test_a_resonance_narrower_than_the_grid_is_refused():
    zeta = 1e-7                             # a peak of height 1/(2ζ) = 5e6 and width ~4e-7 rad/s
    A, B, C = _siso(zeta, w0=2.0 * np.pi * 0.7071)
    sector = [(-1e-5, 1e-5)]                 # |H| = 1/(2ζ) at the peak: r·|H| = 50 > 1
    kyp = circle_kyp(A, B, C, sector)
    assert not kyp.proved and kyp.gain == pytest.approx(1e-5 / (2 * zeta), rel=1e-3)
    assert circle_criterion(A, B, C, sector).passed       # the grid misses the peak


def test_the_scaling_recovers_a_channel_of_zero_width():
    A = np.array([[-1.0, 0.3], [0.2, -2.0]])
    B, C = np.eye(2), np.eye(2)
    sector = [(-0.9, 0.9), (-1e-12, 1e-12)]
    kyp = circle_kyp(A, B, C, sector)
    w = np.linspace(0, 100, 20001)
    h11 = np.array([np.linalg.solve(1j * x * np.eye(2) - A, B)[0, 0] for x in w])
    assert kyp.proved == bool(0.9 * np.abs(h11).max() < 1)
