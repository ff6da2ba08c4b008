"""The small-gain form of the circle criterion for a coupled φ (φ_i depending on outputs other
than y_i, outside lemma 1 of ch. 9.2; Desoer & Vidyasagar, *Feedback Systems*, ch. VI).

φ = C_0 y + Δ(y, t) with C_0 = diag(c_i), c_i the centre of a diagonal channel's sector and 0 for
a coupled one, ‖Δ‖₂ ≤ ρ‖y‖₂, ρ² = max_{diagonal i} r_i² + Σ_{coupled i} r_i²; the loop is
exponentially stable with rate a when A + B C_0 C + aI is Hurwitz and ρ·sup_ω σ̄(H_c(−a + jω)) < 1,
H_c = (I − H C_0)⁻¹ H.  Split from :mod:`qpp.circle`, which calls :func:`small_gain_result`.
"""
from __future__ import annotations

import numpy as np

from qpp.circle import CircleResult, _passing_scales


def _small_gain_terms(alpha, beta, coupled) -> tuple[np.ndarray, float]:
    """(C_0 diagonal, ρ) of the small-gain form (module docstring) for the sector [α, β]."""
    centre = np.where(coupled, 0.0, 0.5 * (alpha + beta))
    half = np.where(coupled, np.maximum(np.abs(alpha), np.abs(beta)), 0.5 * (beta - alpha))
    diag_part = float(np.max(half[~coupled] ** 2)) if (~coupled).any() else 0.0
    return centre, float(np.sqrt(diag_part + np.sum(half[coupled] ** 2)))


def spectral_norms(H: np.ndarray) -> np.ndarray:
    """σ̄(H_k), the largest singular value of each matrix of a stack (N, m, m).

    For m ≤ 2 in closed form (the larger eigenvalue of the 2×2 Hermitian Hᴴ H), which is
    ~10× faster than numpy's batched SVD on a frequency grid; otherwise ``numpy.linalg.norm``.

    Parameters
    ----------
    H : (N, m, m) complex array
        The matrices, in any unit.

    Returns
    -------
    (N,) float array
        Their spectral norms, in the unit of H.
    """
    m = H.shape[-1]
    if H.shape[-2] != m or m > 2:
        return np.linalg.norm(H, ord=2, axis=(-2, -1))
    if m == 1:
        return np.abs(H[..., 0, 0])
    big = np.max(np.abs(H), axis=(-2, -1))             # scaled to 1: no over- or underflow
    d = np.where(big > 0, big, 1.0)[..., None, None]
    G = H.real / d + 1j * (H.imag / d) if np.iscomplexobj(H) else H / d   # no 1/big (denormal big)
    col = np.sum(np.abs(G) ** 2, axis=-2)              # diagonal of Gᴴ G
    off = np.sum(np.conj(G[..., :, 0]) * G[..., :, 1], axis=-1)
    mean, half = 0.5 * (col[..., 0] + col[..., 1]), 0.5 * (col[..., 0] - col[..., 1])
    return big * np.sqrt(mean + np.hypot(half, np.abs(off)))


def _small_gain_at(Hw, A, B, C, a, alpha, beta, coupled, s) -> tuple[bool, float, int, float]:
    """(passed, margin 1 − ρ·peak, P_0 of the centred loop, peak σ̄ of H_c) at sector scale s."""
    centre, rho = _small_gain_terms(s * alpha, s * beta, coupled)
    n = A.shape[0]
    P0 = int(np.sum(np.linalg.eigvals(A + B @ (centre[:, None] * C) + a * np.eye(n)).real >= 0))
    Hc = Hw
    if np.any(centre):
        try:
            Hc = np.linalg.solve(np.eye(Hw.shape[1])[None] - Hw * centre[None, None, :], Hw)
        except np.linalg.LinAlgError:           # I − H C_0 singular on the grid: not certified
            return False, -np.inf, P0, np.inf
    peak = float(np.max(spectral_norms(Hc)))
    margin = 1.0 - rho * peak
    return bool(P0 == 0 and margin > 0), margin, P0, peak


def small_gain_result(Hw, A, B, C, a, omega, centres, radii, alpha, beta, coupled, P0_open) -> CircleResult:
    """:func:`qpp.circle.circle_criterion` for a coupled φ: the small-gain form (module docstring).

    Parameters
    ----------
    Hw : (N, m, m) complex array
        H(−a + jω) on the grid, in the units of y per unit of φ.
    A, B, C : arrays
        Realization of H, in the units of the closed loop's state, φ and y.
    a : float
        Exponential weighting, 1/s.
    omega : (N,) array
        The grid, rad/s.
    centres, radii : (m, N) arrays
        Gershgorin bands of ``Hw`` (stored for the figure), in the units of H.
    alpha, beta : (m,) arrays
        The sector, dimensionless gains.
    coupled : (m,) bool array
        Channels whose φ_i depends on other outputs (dimensionless flags).
    P0_open : int
        Poles of H(s − a) in the closed right half plane.

    Returns
    -------
    CircleResult
        ``method = "small_gain"``, the margin 1 − ρ·sup σ̄(H_c) on every channel.
    """
    passed, margin, P0, peak = _small_gain_at(Hw, A, B, C, a, alpha, beta, coupled, 1.0)
    centre, rho = _small_gain_terms(alpha, beta, coupled)
    if not np.any(centre):          # H_c = H at every scale: s·ρ·peak < 1 in closed form
        smin, smax = (0.0, (np.inf if rho * peak == 0 else 1.0 / (rho * peak))) if P0 == 0 else (np.nan, 0.0)
    else:
        smin, smax = _passing_scales(lambda s: _small_gain_at(Hw, A, B, C, a, alpha, beta, coupled, s)[0],
                                     fine=P0_open > 0)
        smax = 0.0 if np.isnan(smax) else smax
    m = alpha.size
    return CircleResult(passed, np.full(m, margin), np.zeros(m, dtype=int), P0, omega, centres, radii,
                        alpha, beta, smax, smin, "small_gain", rho, peak)
