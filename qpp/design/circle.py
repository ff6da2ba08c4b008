"""Multivariable circle criterion (Cook 1972; lemma 1, ch. 9.2) on H_a(jω) = H(−a + jω).

H(s) = C_z (sI − A_z)⁻¹ B_φ is the square transfer matrix from the sector nonlinearity φ (the
disturbance columns of B_z, eq 10.7) to y.  The loop is ż = A_z z + B_φ φ(y): φ enters with +,
as in eqs 13.1 and 14.2 (see ``docs/ERRATA.md`` § QPP signs and § QPP circle sign).  Lemma 1 as
printed is for φ entering with − (eq 10.1), whose critical disc D(α, β) has the diameter
[−1/α, −1/β]; for the loop as built, −H takes the place of H, i.e. h_ii is compared with the
mirror image of that disc, the disc with the diameter [1/α, 1/β] (:func:`critical_disc`).  A
constant gain k_i ∈ [α_i, β_i] on each channel is one member of the sector, so a passing sector
never holds a destabilizing constant diagonal gain (tested).

**Diagonal φ** (φ_i depends on y_i only): the i-th Gershgorin mean band is swept by discs
centred at h_ii with radius (d_i + d'_i)/2 (row and column off-diagonal sums, definition 3).
Conditions checked, per channel i:

* 0 < α_i < β_i (or α_i < β_i < 0): the band avoids the disc and Σ N_ci = −P_0, with N_ci the
  clockwise encirclements of the disc by h_ii (counted as the winding number of h_ii about the
  disc centre along ω = −∞…∞) and P_0 the poles of H(s − a) in the closed right half plane;
* α_i < 0 < β_i: the band lies inside the disc (so it does not encircle it: N_ci = 0);
* α_i = 0 < β_i: the band lies in the half plane Re s < 1/β_i (α_i < β_i = 0: Re s > 1/α_i;
  N_ci = 0);

and, over all channels, Σ N_ci = −P_0 (eq 9.3).  With every channel of the second or third
kind that is P_0 = 0; channels of different kinds may be mixed (e.g. a decoupled H(s) is m
independent SISO circle criteria).

**Coupled φ** (some φ_i depends on other outputs, ``coupled``): the criterion above assumes a
diagonal φ and does not apply.  The small-gain form of the circle criterion is checked instead
(Desoer & Vidyasagar, *Feedback Systems*, ch. VI): φ = C_0 y + Δ(y, t) with C_0 = diag(c_i),
c_i the centre (α_i + β_i)/2 of a diagonal channel and 0 for a coupled one, and
‖Δ(y, t)‖₂ ≤ ρ ‖y‖₂ with ρ² = max_{diagonal i} r_i² + Σ_{coupled i} r_i² (r_i the half-width
of the sector; for a coupled channel the sector is ±sup Σ_j |∂φ_i/∂y_j| ≥ |φ_i| / ‖y‖∞).  The
loop is exponentially stable with rate a when A_z + B_φ C_0 C_z + aI is Hurwitz (P_0 = 0, P_0
counted on that centred loop) and ρ · sup_ω σ̄(H_c(−a + jω)) < 1, H_c = (I − H C_0)⁻¹ H.

The check is made on a dense frequency grid (default 0 and 6000 log-spaced points spanning the
pole magnitudes, extended until the Nyquist tail lies within 1 % of the critical sets; a sector
the grid does not resolve is not certified): exact for the encirclement count, accurate to the
grid for the distance margins.

**Decided by the KYP lemma, not on a frequency grid** (:func:`circle_kyp`, issue 43; the premise
``circle`` of the certificate).  With φ = C_0 y + Δ(y, t) as above and |Δ_i| ≤ r_i |y_i|, r_i the
half-width (the loop transformation of the circle criterion), the loop ż = A z + B φ(C z) is
exponentially stable with rate a when

* A_c = A + B C_0 C + aI is Hurwitz (eigenvalues), and
* the small-gain inequality ‖D R C (sI − A_c)⁻¹ B D⁻¹‖∞ < 1 holds, R = diag(r_i), D a positive
  diagonal scaling (it commutes with a diagonal Δ; for a coupled φ, D = I and R = ρI with ρ of
  the small-gain form above).

The frequency-domain inequality is a KYP statement; it is decided by the Hamiltonian matrix
[[A_c, B̃B̃ᵀ], [−C̃ᵀC̃, −A_cᵀ]] (B̃ = B D⁻¹, C̃ = D R C): with A_c Hurwitz the H∞ norm is < 1 exactly
when it has no eigenvalue on the imaginary axis (Boyd, Balakrishnan & Kabamba 1989), the test by
which β1 is computed.  For one channel this is the circle criterion itself (the disc, half-plane or
encirclement condition is the image of the small-gain condition under the loop transformation);
for several diagonal channels it is the scaled small-gain form, a sufficient condition beside
the Gershgorin bands of lemma 1.  The frequency grid remains for the figures and as a cross-check
in the tests.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from qpp.design.spheres import hinf_norm
from qpp.model.transfer import transfer_on_grid


def default_grid(A, n: int = 6000) -> np.ndarray:
    """Non-negative frequencies (rad/s) spanning the pole magnitudes of A by three decades.

    Parameters
    ----------
    A : (k, k) array
        State matrix, 1/s.
    n : int
        Number of log-spaced points (the grid also holds ω = 0).

    Returns
    -------
    (n+1,) ndarray
        Frequencies, rad/s.
    """
    mags = np.abs(np.linalg.eigvals(A))
    mags = mags[mags > 0]
    lo = (mags.min() if mags.size else 1.0) / 1e3
    hi = (mags.max() if mags.size else 1.0) * 1e3
    return np.concatenate([[0.0], np.logspace(np.log10(lo), np.log10(hi), n)])


def frequency_response(A, B, C, a: float, omega) -> np.ndarray:
    """H(−a + jω) for each ω; shape (len(omega), p, k).

    Parameters
    ----------
    A : (n, n) array
        State matrix, 1/s.
    B : (n, k) array
        Input matrix, in the units of the state per unit of input and second.
    C : (p, n) array
        Output matrix, in the units of the output per unit of state.
    a : float
        Exponential weighting, 1/s.
    omega : (N,) array
        Frequencies, rad/s.

    Returns
    -------
    (N, p, k) complex ndarray
        H(−a + jω), in the units of the output per unit of input.
    """
    return transfer_on_grid(A, B, C, -a + 1j * np.asarray(omega, float))


def gershgorin_bands(Hw: np.ndarray):
    """Centres h_ii and mean radii (d_i + d'_i)/2 (definition 3) of a response array (N, m, m).

    Parameters
    ----------
    Hw : (N, m, m) complex ndarray
        Frequency response, in the units of the output per unit of input.

    Returns
    -------
    centres : (m, N) complex ndarray
        h_ii, same units as ``Hw``.
    radii : (m, N) ndarray
        Mean Gershgorin radii, same units as ``Hw``.

    Raises
    ------
    ValueError
        ``Hw`` is not square.
    """
    Hw = np.asarray(Hw)
    if Hw.shape[1] != Hw.shape[2]:
        raise ValueError(f"circle criterion needs a square H(s), got {Hw.shape[1]}×{Hw.shape[2]}")
    absH = np.abs(Hw)
    diag = np.einsum("kii->ki", Hw)
    absd = np.abs(diag)
    d_row = absH.sum(axis=2) - absd
    d_col = absH.sum(axis=1) - absd
    return diag.T, (0.5 * (d_row + d_col)).T   # (m, N) each


def critical_disc(alpha: float, beta: float) -> tuple[float, float]:
    """Centre and radius of the critical disc of h_ii for the loop ż = A z + B φ(y) (φ entering
    with +): the disc with diameter [1/α, 1/β] (α, β ≠ 0), the mirror image of the report's
    D(α, β) (diameter [−1/α, −1/β], for φ entering with −, eq 10.1).

    Parameters
    ----------
    alpha : float
        Lower sector gain α, dimensionless.
    beta : float
        Upper sector gain β, dimensionless.

    Returns
    -------
    centre : float
        Centre of the disc on the real axis, dimensionless.
    radius : float
        Radius of the disc, dimensionless.
    """
    p1, p2 = 1.0 / alpha, 1.0 / beta
    return 0.5 * (p1 + p2), 0.5 * abs(p1 - p2)


@dataclass
class CircleResult:
    """Outcome of lemma 1 on H(−a + jω).

    Attributes
    ----------
    passed : bool
        All conditions of lemma 1 hold.
    margins : (m,) ndarray
        Per channel: smallest distance band ↔ disc boundary (> 0 is good), dimensionless.
    encirclements : (m,) int array
        N_ci, clockwise encirclements of each critical disc.
    P0 : int
        Open-loop poles of H(s − a) in the closed right half plane.
    omega : (N,) ndarray
        Frequency grid, rad/s.
    centres : (m, N) complex ndarray
        h_ii(−a + jω) for ω ≥ 0, dimensionless.
    radii : (m, N) ndarray
        Mean Gershgorin radii, dimensionless.
    alpha : (m,) ndarray
        Lower sector gains, dimensionless.
    beta : (m,) ndarray
        Upper sector gains, dimensionless.
    max_scale : float
        Largest s with [s α, s β] passing (grid), inf if unbounded, 0 if none passes;
        dimensionless.
    min_scale : float
        Smallest s with [s α, s β] passing: 0 when every small sector passes (a stable H), > 0
        when the sector must be wide enough to stabilize an unstable H, nan if none passes;
        dimensionless.
    method : str
        ``"gershgorin"`` (diagonal φ: the bands and discs) or ``"small_gain"`` (some φ_i coupled:
        the margins are 1 − ρ·sup σ̄(H_c), the same for every channel).
    gain_bound : float
        ρ of the small-gain form, ‖Δ‖₂ ≤ ρ‖y‖₂ (nan for ``"gershgorin"``); dimensionless.
    peak_gain : float
        sup_ω σ̄(H_c(−a + jω)) at the sector itself (nan for ``"gershgorin"``); dimensionless.
    """

    passed: bool
    margins: np.ndarray        #: per channel: smallest distance band ↔ disc boundary (> 0 is good)
    encirclements: np.ndarray  #: N_ci, clockwise encirclements of each critical disc
    P0: int                    #: open-loop poles of H(s − a) in the closed right half plane
    omega: np.ndarray
    centres: np.ndarray        #: (m, N) h_ii(−a + jω) for ω ≥ 0
    radii: np.ndarray          #: (m, N) mean Gershgorin radii
    alpha: np.ndarray
    beta: np.ndarray
    max_scale: float           #: largest s with [s α, s β] passing (grid), inf if unbounded
    min_scale: float = 0.0     #: smallest s with [s α, s β] passing (0: all small ones pass)
    method: str = "gershgorin"  #: "gershgorin" (diagonal φ) or "small_gain" (coupled φ)
    gain_bound: float = float("nan")   #: ρ of the small-gain form (nan for "gershgorin")
    peak_gain: float = float("nan")    #: sup_ω σ̄(H_c(−a + jω)) at s = 1 (nan for "gershgorin")


def _check(centres, radii, full_centres, alpha, beta, P0):
    m = centres.shape[0]
    margins = np.empty(m)
    N = np.zeros(m, dtype=int)
    for i in range(m):
        al, be = alpha[i], beta[i]
        if al < 0 < be:
            c, R = critical_disc(al, be)
            margins[i] = np.min(R - (np.abs(centres[i] - c) + radii[i]))
        elif al == 0:          # φ_i ∈ [0, β_i] entering with +: the band left of 1/β_i
            margins[i] = np.min(1.0 / be - centres[i].real - radii[i])
        elif be == 0:          # φ_i ∈ [α_i, 0]: the band right of 1/α_i
            margins[i] = np.min(centres[i].real - radii[i] - 1.0 / al)
        else:
            c, R = critical_disc(al, be)
            margins[i] = np.min(np.abs(centres[i] - c) - radii[i] - R)
            ang = np.unwrap(np.angle(full_centres[i] - c))           # winding number about the disc centre,
            N[i] = -int(np.round((ang[-1] - ang[0]) / (2 * np.pi)))   # counted clockwise
    # eq 9.3 over all channels; a band inside its disc or half plane counts N_ci = 0
    return bool(np.all(margins > 0) and int(N.sum()) == -P0), margins, N


#: sector scales tried by :func:`_passing_scales` before refining (4 per decade, and s = 1) ...
_SCALES = np.unique(np.concatenate([np.logspace(-12, 12, 97), [1.0]]))
#: ... and for an unstable H, whose passing scales may be a window away from 0 (48 per decade)
_FINE_SCALES = np.unique(np.concatenate([np.logspace(-12, 12, 1153), [1.0]]))


def _passing_scales(ok, fine: bool = False) -> tuple[float, float]:
    """(smallest, largest) s > 0 with ``ok(s)`` (the sector s·[α, β] passing): each end refined by
    bisection between a passing and a failing scale of :data:`_SCALES` (``fine``:
    :data:`_FINE_SCALES`, a window narrower than a factor 1.05 is missed); 0.0 for the smallest
    when the smallest scale tried passes, inf for the largest when the largest passes; (nan, nan)
    when none passes.  For a stable H the passing scales run from 0 up; for an unstable one
    (P_0 > 0, a sector that must stabilize) they start above 0."""
    scales = _FINE_SCALES if fine else _SCALES
    good = np.array([ok(s) for s in scales])
    if not good.any():
        return float("nan"), float("nan")
    i, j = int(np.argmax(good)), int(len(good) - 1 - np.argmax(good[::-1]))

    def refine(lo, hi, want_lo):        # ok(lo) != ok(hi); returns the passing side
        for _ in range(200):
            mid = np.sqrt(lo * hi)
            if ok(mid) == want_lo:
                lo = mid
            else:
                hi = mid
            if hi / lo < 1 + 1e-9:
                break
        return lo if want_lo else hi

    smin = 0.0 if i == 0 else refine(scales[i - 1], scales[i], False)
    if j == len(good) - 1:
        smax = np.inf
    elif i == 0 and good[:j + 1].all():     # passing from 0 up to one end: bisect it over the
        smax = refine(scales[0], scales[-1], True)     # whole range (the numbers of before)
    else:
        smax = refine(scales[j], scales[j + 1], True)
    return float(smin), float(smax)


def circle_criterion(A, B, C, sector, a: float = 0.0, omega=None, coupled=None) -> CircleResult:
    """Lemma 1 on ω ↦ H(−a + jω), H(s) = C (sI − A)⁻¹ B square.

    Parameters
    ----------
    A, B, C : arrays
        Realization of H (for eq 10.7: A_z, the φ columns of B_z, C_z), in the units of the
        closed loop's state, φ and y.
    sector : sequence of (α_i, β_i)
        Sector of each φ_i (dimensionless gains), α_i < β_i.
    a : float
        Exponential weighting, 1/s (lemma 2).
    omega : array, optional
        Non-negative grid, rad/s (default :func:`default_grid`).
    coupled : sequence of bool, optional
        Per channel, whether φ_i depends on outputs other than y_i (then the small-gain form of
        the module docstring is checked; default: none, the Gershgorin form).

    Returns
    -------
    CircleResult
        The outcome, margins and the largest passing sector scale.

    Raises
    ------
    ValueError
        The sector has not one (α_i, β_i) per channel of H, or some α_i ≥ β_i.
    """
    A = np.asarray(A, float)
    sector = np.atleast_2d(np.asarray(sector, float))
    alpha, beta = sector[:, 0], sector[:, 1]
    if omega is None:
        omega, Hw = _grid_past_the_tail(A, B, C, a, default_grid(A), alpha, beta)
    else:
        omega = np.asarray(omega, float)
        Hw = frequency_response(A, B, C, a, omega)
    centres, radii = gershgorin_bands(Hw)
    if centres.shape[0] != alpha.size:
        raise ValueError(f"sector has {alpha.size} channels, H(s) has {centres.shape[0]}")
    tail = np.abs(centres[:, -1]) + radii[:, -1]
    # full contour ω = −∞ … ∞ (h(−jω) = conj h(jω)); strictly proper → closes at 0
    full = np.concatenate([np.conj(centres[:, ::-1]), centres], axis=1)
    P0 = int(np.sum(np.linalg.eigvals(A + a * np.eye(A.shape[0])).real >= 0))
    if not np.all(alpha < beta):
        bad = int(np.argmin(alpha < beta))
        raise ValueError(f"sector {bad + 1}: need alpha < beta, got [{alpha[bad]}, {beta[bad]}]")
    coupled = np.zeros(alpha.size, bool) if coupled is None else np.asarray(coupled, bool)
    if coupled.any():
        return small_gain_result(Hw, A, B, C, a, omega, centres, radii, alpha, beta, coupled, P0)
    passed, margins, N = _check(centres, radii, full, alpha, beta, P0)
    passed = passed and _resolved(tail, alpha, beta)

    def ok(s):        # a scale whose critical set the grid does not resolve is not certified
        sa, sb = s * alpha, s * beta  # (a denormal sector scaled down to [-0, 0] is not a sector)
        return bool(np.all(sa < sb)) and _resolved(tail, sa, sb) and _check(centres, radii, full, sa, sb, P0)[0]

    smin, smax = _passing_scales(ok, fine=P0 > 0)
    if np.isnan(smax):
        smax = 0.0
    return CircleResult(passed, margins, N, P0, omega, centres, radii, alpha, beta, smax, smin)


#: the band at the grid's last frequency lies within this fraction of the distance 1 / max(|α_i|,
#: |β_i|) from 0 to each critical set: the tail beyond it, down to h(±j∞) = 0, cannot reach it
TAIL_FRACTION = 0.01


def _resolved(tail, alpha, beta) -> bool:
    """Whether the grid ends where the bands (``tail``: |h_ii| + r_i at the last frequency) are
    within :data:`TAIL_FRACTION` of every critical set of the sector [α, β]."""
    return bool(np.all(tail * np.maximum(np.abs(alpha), np.abs(beta)) <= TAIL_FRACTION))


#: the default grid resolves sectors up to this many times the one checked (so that max_scale is
#: not a limit of the grid below it)
RESOLVED_SCALE = 1e3


def _grid_past_the_tail(A, B, C, a, omega, alpha, beta, max_decades: int = 12):
    """(ω, H(−a + jω)) on :func:`default_grid`, extended by decades (50 points each) until the
    critical sets of the sector scaled by :data:`RESOLVED_SCALE` are resolved (:func:`_resolved`;
    at most ``max_decades`` more).  A larger scale the grid does not resolve is not certified."""
    Hw = frequency_response(A, B, C, a, omega)
    if Hw.shape[1] != Hw.shape[2] or Hw.shape[1] != np.size(alpha):
        return omega, Hw                  # refused by the caller, with its message
    for _ in range(max_decades):
        centres, radii = gershgorin_bands(Hw[-1:])
        if _resolved(np.abs(centres[:, -1]) + radii[:, -1], RESOLVED_SCALE * alpha, RESOLVED_SCALE * beta):
            break
        more = np.logspace(np.log10(omega[-1]), np.log10(omega[-1]) + 1, 51)[1:]
        omega = np.concatenate([omega, more])
        Hw = np.concatenate([Hw, frequency_response(A, B, C, a, more)])
    return omega, Hw


# ------------------------------------------------------------------------------------------------
# The small-gain form of the circle criterion for a coupled φ (module docstring, "Coupled φ").


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
    """:func:`qpp.design.circle.circle_criterion` for a coupled φ: the small-gain form (module docstring).

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


#: the H∞ norm must be below 1 by this much (relative) for the Hamiltonian test to be taken
MARGIN = 1e-9
#: an eigenvalue of the Hamiltonian with |Re λ| below this fraction of its largest |λ| is on the axis
AXIS_TOL = 1e-9


@dataclass
class KypResult:
    """Outcome of :func:`circle_kyp`.

    Attributes
    ----------
    proved : bool
        The centred loop is Hurwitz and the scaled small-gain inequality holds (KYP, Hamiltonian).
    gain : float
        ‖D R H_c‖∞ at the scaling chosen (< 1 when proved), dimensionless.
    scaling : (m,) ndarray
        The diagonal of D, dimensionless.
    centre : (m,) ndarray
        C_0's diagonal, dimensionless gains.
    radius : (m,) ndarray
        R's diagonal, dimensionless gains.
    hurwitz : bool
        A + B C_0 C + aI Hurwitz.
    text : str
        The outcome in words.
    """

    proved: bool
    gain: float
    scaling: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    hurwitz: bool
    text: str


def _hamiltonian_clear(A, B, C) -> bool:
    """Whether the Hamiltonian [[A, BBᵀ], [−CᵀC, −Aᵀ]] of ‖C (sI − A)⁻¹ B‖∞ < 1 has no eigenvalue on the
    imaginary axis (|Re λ| ≤ AXIS_TOL·max |λ|); with A (1/s) Hurwitz this is the norm being below 1."""
    H = np.block([[A, B @ B.T], [-C.T @ C, -A.T]])
    ev = np.linalg.eigvals(H)
    scale = max(1.0, float(np.abs(ev).max()))
    return bool(np.all(np.abs(ev.real) > AXIS_TOL * scale))


def circle_kyp(A, B, C, sector, a: float = 0.0, coupled=None) -> KypResult:
    """The circle criterion of the sector on ż = A z + B φ(C z), decided by the KYP lemma.

    Parameters
    ----------
    A, B, C : arrays
        Realization of H (A_z, the φ columns of B_z, C_z of eq 10.7), in the units of the
        closed loop's state, φ and y.
    sector : (m, 2) array
        [α_i, β_i] per channel, α_i < β_i, dimensionless gains.
    a : float
        Exponential weighting, 1/s.
    coupled : (m,) bool array, optional
        Channels whose φ_i depends on other outputs (default none).

    Returns
    -------
    KypResult
        The decision, the gain and the scaling.
    """
    A, B, C = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C))
    s = np.atleast_2d(np.asarray(sector, float))
    m = s.shape[0]
    coupled = np.zeros(m, bool) if coupled is None else np.asarray(coupled, bool)
    centre, rho = _small_gain_terms(s[:, 0], s[:, 1], coupled)
    # Δ not diagonal (coupled): one radius ρ for all, no scaling; else the half-widths
    radius = np.full(m, rho) if coupled.any() else 0.5 * (s[:, 1] - s[:, 0])
    Ac = A + B @ (centre[:, None] * C) + a * np.eye(A.shape[0])
    worst = float(np.max(np.linalg.eigvals(Ac).real))
    if not worst < 0:
        return KypResult(False, np.inf, np.ones(m), centre, radius, False,
                         f"not proved: the centred loop A + B C0 C + aI is not Hurwitz (largest Re = {worst:.4g})")

    def gain(logd):
        d = np.exp(np.concatenate([[0.0], logd]))
        return hinf_norm(Ac, B / d[None, :], (d * radius)[:, None] * C)[0]

    logd = np.zeros(m - 1)
    g = gain(logd)
    if m > 1 and not coupled.any() and g >= 1.0 - MARGIN:
        res = minimize(lambda x: gain(np.clip(x, -30, 30)), logd, method="Nelder-Mead",
                       options={"maxiter": 200 * (m - 1), "xatol": 1e-4, "fatol": 1e-9})
        if res.fun < g:
            logd, g = np.clip(res.x, -30, 30), float(res.fun)
    d = np.exp(np.concatenate([[0.0], logd]))
    clear = g < 1.0 - MARGIN and _hamiltonian_clear(Ac, B / d[None, :], (d * radius)[:, None] * C)
    form = "||R H_c||" if m == 1 else ("rho ||H_c||" if coupled.any() else "||D R H_c D^-1||")
    text = (f"proved by the KYP lemma: centred loop Hurwitz and {form}_inf = {g:.6g} < 1 (Hamiltonian without "
            "imaginary-axis eigenvalues)" if clear else
            f"not proved: {form}_inf = {g:.6g} is not below 1 (KYP lemma, Hamiltonian test)")
    return KypResult(bool(clear), float(g), d, centre, radius, True, text)
