"""The circle criterion (qpp.design.circle) against the loop as built and against independent
computations: φ enters ż = A z + B φ(y) with + (eqs 13.1, 14.2), so a passing sector never holds a
destabilizing constant gain; a coupled φ is checked in the small-gain form; the encirclement
count, the passing scales of an unstable plant, the SISO and MIMO report examples; the circle
criterion decided by the KYP lemma agrees with the grid where the grid resolves the response, and
refuses a resonance narrower than the grid."""
import itertools

import numpy as np
import pytest

from qpp.design.circle import circle_criterion, circle_kyp
from qpp.model.lure import LurePlant, closed_loop
from qpp.design import spheres

from tests.qpp.conftest import _pub

W = np.concatenate([[0.0], np.logspace(-3, 3, 1500)])


def _max_re(A, B, C, Phi):
    return float(np.linalg.eigvals(A + B @ Phi @ C).real.max())


def _random_stable_loop(rng, n: int, least_decay: float):
    """A random stable (n, n) A (its eigenvalues shifted to Re ≤ −U(least_decay, 1)), B (n, 2), C (2, n)."""
    A = rng.normal(size=(n, n))
    A -= (np.linalg.eigvals(A).real.max() + rng.uniform(least_decay, 1.0)) * np.eye(n)
    return A, rng.normal(size=(n, 2)), rng.normal(size=(2, n))


def _one_sided_loop():
    """The SISO loop of the review: stable for φ = k y with k ≤ 1.426 only (k < 0 all stable)."""
    P = LurePlant([[0, 1], [-1, -0.5]], [[0], [1]], [[1, 0]], [[0], [1]], [[0]], [[1]], [[1]])
    Az, Bz, Cz = closed_loop(P, np.array([[-4.0, -3.0]]), np.array([[3.0]]), np.array([[-4.0], [-4.0]]))
    return Az, Bz[:, 1:], Cz


def test_one_sided_sectors_follow_the_sign_of_the_loop():
    A, B, C = _one_sided_loop()
    ks = np.linspace(-20, 5, 2501)
    stable = np.array([_max_re(A, B, C, np.array([[k]])) < 0 for k in ks])
    k_max = ks[stable].max()
    assert 1.40 < k_max < 1.45 and stable[ks < 0].all()            # independent: eigenvalues
    assert circle_criterion(A, B, C, [[0.0, 0.9]], a=1e-4).passed
    assert not circle_criterion(A, B, C, [[0.0, 3.0]], a=1e-4).passed   # k = 3 diverges
    assert not circle_criterion(A, B, C, [[0.0, 1.5]], a=1e-4).passed
    assert circle_criterion(A, B, C, [[-3.1, 0.0]], a=1e-4).passed
    c = circle_criterion(A, B, C, [[0.0, 1.0]], a=1e-4)
    assert c.max_scale * 1.0 <= k_max * 1.001                       # sufficient, never beyond stability


def test_passing_sectors_hold_no_destabilizing_constant_gain():
    """400 random stable 2×2 loops, one-sided, two-sided and positive sectors scaled to 0.99× the
    largest admissible scale: every constant diagonal gain at a corner of the sector (and at
    random inside) leaves the loop stable."""
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(400):
        A, B, C = _random_stable_loop(rng, 3, 0.2)
        lo, hi = sorted(rng.choice([-2.0, -1.0, 0.0, 0.5, 1.0, 2.0], 2, replace=False))
        sector = np.array([[lo, hi], [min(lo, 0.0), max(hi, 0.5)]])
        c = circle_criterion(A, B, C, sector, omega=W)
        s = 0.99 * c.max_scale
        if not np.isfinite(s) or s <= 0 or c.min_scale > 0:
            continue
        checked += 1
        corners = [np.diag(d) for d in itertools.product(*(s * sector))]
        inside = [np.diag(s * (sector[:, 0] + rng.uniform(size=2) * np.ptp(sector, axis=1))) for _ in range(4)]
        assert max(_max_re(A, B, C, K) for K in corners + inside) < 1e-9
    assert checked > 200


def _cross_counterexample():
    rng = np.random.default_rng(1)
    for _ in range(300):
        A, B, C = _random_stable_loop(rng, 4, 0.1)
        diag_scale = circle_criterion(A, B, C, [[-1, 1], [-1, 1]], omega=W).max_scale
        s = 0.98 * diag_scale
        if not np.isfinite(s) or s == 0:
            continue
        Phi = s * np.array([[0.0, 1.0], [1.0, 0.0]])
        for sg in itertools.product([-1, 1], repeat=2):
            P = Phi * np.array([[1, sg[0]], [sg[1], 1]])
            if _max_re(A, B, C, P) > 0:
                return A, B, C, s
    raise AssertionError("no counterexample to the diagonal test found")


def test_coupled_channels_take_the_small_gain_form():
    """φ_1 = k y_2, φ_2 = k y_1 inside the sector ±s of each channel can destabilize a loop the
    diagonal (Gershgorin) form passes; the coupled form does not pass it."""
    A, B, C, s = _cross_counterexample()
    sector = [[-s, s], [-s, s]]
    assert circle_criterion(A, B, C, sector, omega=W).passed                # the diagonal form: unsound here
    c = circle_criterion(A, B, C, sector, omega=W, coupled=[True, True])
    assert not c.passed and c.method == "small_gain"
    assert np.isclose(c.gain_bound, np.sqrt(2) * s)


@pytest.mark.slow
def test_coupled_small_gain_is_sufficient_on_random_loops():
    """Below the small-gain form's largest admissible scale, constant gain matrices with row sums
    |Φ_i1| + |Φ_i2| ≤ s (a coupled channel's bound) never destabilize; a diagonal channel mixed in
    keeps its own centre."""
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(200):
        A, B, C = _random_stable_loop(rng, 4, 0.1)
        sector = np.array([[-1.0, 1.0], [0.0, 1.0]])
        c = circle_criterion(A, B, C, sector, omega=W, coupled=[True, False])
        s = 0.99 * c.max_scale
        if not np.isfinite(s) or s <= 0:
            continue
        checked += 1
        for _k in range(12):
            w = rng.uniform(size=2)
            row1 = s * rng.choice([-1, 1], 2) * w / w.sum()
            k2 = s * rng.uniform(0.0, 1.0)
            assert _max_re(A, B, C, np.array([row1, [0.0, k2]])) < 1e-9
    assert checked > 100


def test_symmetric_sectors_are_unchanged_by_the_sign():
    """A symmetric sector's disc is centred at 0: its verdict and margins do not depend on the sign."""
    A, B, C = _one_sided_loop()
    c1 = circle_criterion(A, B, C, [[-0.5, 0.5]], a=1e-4)
    c2 = circle_criterion(A, -B, C, [[-0.5, 0.5]], a=1e-4)
    assert c1.passed == c2.passed and np.allclose(c1.margins, c2.margins)


def test_a_sector_the_grid_does_not_resolve_is_not_certified():
    """A huge sector's critical disc lies near 0, inside the Nyquist tail beyond the default grid's
    last frequency: the grid is extended until the tail is resolved, and a scale it cannot
    resolve is not certified (a wide sector passed although every constant gain in it
    destabilized the loop, and max_scale was reported infinite for a bounded sector)."""
    B, C = np.array([[0.0], [1.0]]), np.array([[2.0, 1.0]])
    A_unstable = np.array([[0.0, 1.0], [10.0, -9.0]])            # h = (s + 2)/((s − 1)(s + 10))
    c = circle_criterion(A_unstable, B, C, [[1e7, 3e7]])
    assert min(_max_re(A_unstable, B, C, np.array([[k]])) for k in (1e7, 2e7, 3e7)) > 0
    assert not c.passed
    A_stable = np.array([[0.0, 1.0], [-10.0, -11.0]])
    for sector, k_unstable in (([[1.0, 3.0]], 5.0), ([[1e7, 3e7]], 1e7)):
        assert _max_re(A_stable, B, C, np.array([[k_unstable * 1.01]])) > 0
        c = circle_criterion(A_stable, B, C, sector)
        assert np.isfinite(c.max_scale) and c.max_scale * sector[0][1] <= k_unstable * 1.001
        assert c.passed is (sector[0][1] < k_unstable)


@pytest.mark.parametrize("m", [1, 2, 3])
def test_spectral_norms_equal_numpy_svd_including_extreme_magnitudes(m):
    """The closed-form σ̄ of the small-gain peak (m ≤ 2) against numpy's SVD, with zero, tiny,
    huge, denormal and nearly rank-one matrices in the stack."""
    from qpp.design.circle import spectral_norms

    rng = np.random.default_rng(m)
    H = rng.normal(size=(400, m, m)) + 1j * rng.normal(size=(400, m, m))
    H[0] = 0.0
    H[1] *= 1e-200
    H[2] *= 1e300
    H[3] *= 1e-310
    H[4] = 1.0 + 1e-12 * np.eye(m)
    for stack in (H, H.real.copy()):
        ref = np.linalg.norm(stack, ord=2, axis=(1, 2))
        got = spectral_norms(stack)
        assert got[0] == 0.0
        np.testing.assert_allclose(got[1:], ref[1:], rtol=1e-13, atol=0)


def test_circle_criterion_siso_and_independent_sector(siso):
    Az, Bz, Cz = closed_loop(siso.lure_plant(), *_pub(siso))
    r = circle_criterion(Az, Bz[:, 1:], Cz, [[-0.5, 0.5]], a=1e-8)
    assert r.passed and r.P0 == 0
    # SISO symmetric sector: the largest half-width is 1/||H||inf (independent exact norm)
    hinf, _ = spheres.hinf_norm(Az + 1e-8 * np.eye(6), Bz[:, 1:], Cz)
    assert 0.5 * r.max_scale == pytest.approx(1 / hinf, rel=1e-4)
    assert not circle_criterion(Az, Bz[:, 1:], Cz, [[-1.4, 1.4]], a=1e-8).passed


def test_circle_encirclement_count():
    # H(s) = 2/(s - 1), φ = k y fed back with + (ẋ = (1 + 2k) x): one unstable pole, stable for
    # k < -1/2; sector [-3, -1] -> disc with diameter [1/α, 1/β] = [-1/3, -1]; Nyquist circles it once ccw
    r = circle_criterion([[1.0]], [[2.0]], [[1.0]], [[-3.0, -1.0]], a=0.0)
    assert r.P0 == 1 and r.encirclements[0] == -1 and r.passed
    assert not circle_criterion([[1.0]], [[2.0]], [[1.0]], [[1.0, 3.0]], a=0.0).passed      # 1 + 2k > 0
    r2 = circle_criterion([[1.0]], [[2.0]], [[1.0]], [[-0.2, -0.1]], a=0.0)  # disc [-10, -5]: not encircled
    assert not r2.passed


def test_circle_criterion_decoupled_mimo_is_its_siso_criteria():
    # a diagonal H(s) is m independent Lure loops: lemma 1 must pass exactly when every channel's
    # SISO circle criterion passes, whatever the mix of sector kinds (α > 0, α = 0, α < 0 < β)
    rng = np.random.default_rng(185644)
    kinds = [(0.1, 1.0), (0.0, 1.0), (-0.2, 0.2), (0.5, 4.0), (-1.5, 1.5), (0.0, 6.0)]
    seen = set()
    for _ in range(40):
        poles = -rng.uniform(0.2, 3.0, 2)
        gains = rng.uniform(0.3, 3.0, 2) * rng.choice([-1.0, 1.0], 2)
        sector = [kinds[k] for k in rng.choice(len(kinds), 2, replace=False)]
        A, B, C = np.diag(poles), np.diag(gains), np.eye(2)
        siso = [circle_criterion([[poles[i]]], [[gains[i]]], [[1.0]], [sector[i]]).passed for i in range(2)]
        mimo = circle_criterion(A, B, C, sector)
        assert mimo.passed == all(siso), (poles, gains, sector)
        seen.add((all(siso), (sector[0][0] > 0) != (sector[1][0] > 0)))
    assert (True, True) in seen and (False, True) in seen      # mixed kinds, passing and failing


def test_circle_scales_of_an_unstable_plant():
    from qpp.design.circle import RESOLVED_SCALE

    # H(s) = 1/(s − 1), φ fed back with + (ẋ = (1 + k) x: stable for k < −1): its Nyquist plot
    # is the circle on [−1, 0], travelled once anticlockwise (P0 = 1).  A sector s·[−β, −α] with
    # 0 < α passes when its disc (diameter [−1/(sα), −1/(sβ)]) lies inside that circle: s > 1/α.
    # So the passing scales start above 0 (the old bisection assumed [0, s_max] and reported 0)
    # and run up to the grid's resolution near the origin (at least RESOLVED_SCALE times the sector).
    for alpha, beta in ((2.0, 3.0), (0.1, 0.2)):
        r = circle_criterion([[1.0]], [[1.0]], [[1.0]], [[-beta, -alpha]])
        assert r.P0 == 1
        assert r.min_scale == pytest.approx(1.0 / alpha, rel=1e-6)
        assert r.max_scale >= RESOLVED_SCALE          # every larger sector passes: the grid's resolved range
        assert r.passed is (1.0 > 1.0 / alpha)
    # a stable plant: every small sector passes
    r = circle_criterion([[-1.0]], [[1.0]], [[1.0]], [[-0.5, 0.5]])
    assert r.min_scale == 0.0 and r.max_scale == pytest.approx(2.0, rel=1e-3)   # 1/||H||∞ = 1 → s·0.5 ≤ 1


def test_circle_scales_window_between_coarse_grid_points():
    # an unstable H whose passing scales are a narrow window, [~1.03, ~1.68], between two points
    # of a 4-per-decade grid (1.0 and 1.78 fail): found, and each end separates pass from fail
    A, B, C = np.diag([1.157, -0.898, -3.716]), np.ones((3, 1)), np.array([[0.896, -0.134, -1.105]])
    sector = np.array([[-1.909, -1.0]])            # fed back with +: the mirror of [1, 1.909] with −
    r = circle_criterion(A, B, C, sector)
    assert r.P0 == 1 and not r.passed
    assert 1.0 < r.min_scale < 1.1 and 1.6 < r.max_scale < 1.778
    for s, want in ((r.min_scale * 0.999, False), (r.min_scale * 1.001, True),
                    (r.max_scale * 0.999, True), (r.max_scale * 1.001, False)):
        assert circle_criterion(A, B, C, s * sector).passed is want, s


def test_mimo_circle_manipulator(arm):
    Az, Bz, Cz = closed_loop(arm.lure_plant(), *_pub(arm))
    r = circle_criterion(Az, Bz[:, 2:], Cz, [[-0.5, 0.5], [-0.5, 0.5]], a=1e-9)
    assert r.passed and r.centres.shape[0] == 2



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
