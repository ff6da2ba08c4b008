"""LQR with every closed-loop pole in a sector (report ch. 5.2, eqs 5.2–5.4, Fig 5.2).

The sector of Fig 5.2, for orbital rate n::

    S = {λ : Re λ ≤ −σ·n  and  |Im λ| ≤ tan φ · |Re λ|}        (σ = 0.5, φ = 45° in the report)

The Sunkel–Shieh algorithm the report cites is not publicly available (`docs/ERRATA.md` § Sector LQR).
:func:`sector_lqr` instead returns an R, a Q ⪰ 0 and the gain K (u = −K x) that is the *exact*
LQR gain of the α-shifted problem ::

    minimize ∫ e^{2αt} (x'Qx + u'Ru) dt   ⇔   LQR of (A + αI, B, Q, R),   α = σ·n,

with every closed-loop pole of A − BK verified to lie in S.

``method="shift"`` (default)
    1. minimum-energy (Q = Q0, default 0) LQR on A + αI: every pole ends with Re ≤ −α;
    2. the poles still outside the φ lines (the disturbance-rejection-filter poles) are moved by
       *optimal pole shifting* (Amin 1985): for the left invariant subspace U1 of the selected
       poles (ordered real Schur form A_cl' = U T U', selected first) solve the Q = 0 Riccati
       equation of (T11' + hI, U1'B), which mirrors those poles about Re = −h while leaving all
       others unchanged; P ← P + U1 P̃ U1', K = R⁻¹B'P.  The Q making K exact for the shifted
       problem is Q ← Q + 2(h − α) U1 P̃ U1' ⪰ 0 (h ≥ α), checked through the Riccati residual.
``method="uniform"``
    The smallest uniform shift α ≥ σn (bisection) for which the LQR of (A + αI, B, Q0, R) puts
    every pole in S; Q = Q0.  Simpler, but moves every pole further than needed.

All computations are done on the state-scaled model x = D x̃ (``scale``), where the Riccati
residual is checked; K, P and Q are returned in physical units.

Conditioning (the shipped configs; README "Sector design and gain schedule").  With Q0 = 0 the
shifted LQR mirrors repeated open-loop modes — the three DRF pairs at ±jn and ±j2n, the Jordan
chains h → ∫h at 0 — onto identical points: near-defective clusters with eigenvalue condition
numbers ~1e9, "in the sector" only to rounding.  The configs therefore use a small fixed diagonal
Q0 on the scaled states (7e-6 rates, 7e-7 attitudes, 5e-6 momentum, 2e-4 momentum integral, 0 DRF;
``Q0_groups``), which splits the Jordan chains, and ``min_margin = 0.1`` (n), so every pole is
≥ 0.1n inside: largest eigenvalue condition ≤ 5.4e4 at MB3, AC and every stair-case point (the
former 1e-5/1e-6/5e-6/5e-5 reached 9.99e4).  The weights were chosen by measurement among ~60
candidates (README) for the condition number *and*
for a second-order gain schedule that can be made stable along the whole path; larger weights lower
the condition number further but make the scheduled loop unstable.  ``line_spacing`` > 0 mirrors
stray poles one real-Schur block at a time about distinct lines (distinct poles; it did not help
the stair-case).  Every result carries the eigenvalue condition numbers (:func:`eigen_conditioning`),
the sector robustness radius (:func:`sector_robustness`) and the CARE condition estimate.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from common.errors import ConvergenceError, DesignError
from acmm.riccati import ILL_CONDITIONED, care_condition, care_residual


def sector_margin(poles, n: float, sigma: float = 0.5, half_angle_deg: float = 45.0) -> np.ndarray:
    """Signed distance of each pole into the sector, in units of n (negative = outside).

    For λ = x + iy the sector is the intersection of the half-planes x ≤ −σn and
    |y| cos φ + x sin φ ≤ 0, so the margin is ::

        m(λ) = min(−σn − x,  −(|y| cos φ + x sin φ)) / n,

    the exact Euclidean distance to the boundary for a pole inside, and a negative number whose
    magnitude does not exceed the distance to the sector for a pole outside.

    Parameters
    ----------
    poles : array_like of complex
        Closed-loop eigenvalues, rad/s.
    n : float
        Orbital rate, rad/s.
    sigma : float
        Minimum decay rate in units of n.
    half_angle_deg : float
        Sector half-angle φ about the negative real axis, deg.
    """
    lam = np.asarray(poles, dtype=complex)
    phi = np.deg2rad(half_angle_deg)
    x, y = lam.real, np.abs(lam.imag)
    d1 = -sigma * n - x
    d2 = -(y * np.cos(phi) + x * np.sin(phi))
    return np.minimum(d1, d2) / n


def in_sector(poles, n: float, sigma: float = 0.5, half_angle_deg: float = 45.0, *,
              min_margin: float = 0.0) -> np.ndarray:
    """Boolean mask: pole lies in the sector with :func:`sector_margin` ≥ ``min_margin`` (units of n)."""
    return sector_margin(poles, n, sigma, half_angle_deg) >= min_margin


@dataclass(frozen=True)
class SectorLQR:
    """A verified sector-constrained LQR design.

    Attributes
    ----------
    K : (M, N) array
        Gain, u = −K x (eq 5.3), physical units (e.g. ft·lbf per state unit).
    P : (N, N) array
        Stabilizing solution of the Riccati equation of (A + shift·I, B, Q, R), physical units.
    Q : (N, N) array
        State weight (⪰ 0, symmetric) for which K is the exact LQR gain of the shifted problem,
        physical units (Q_ij in 1/(unit_i·unit_j) of the cost, R's units × ft·lbf²).
    R : (M, M) array
        Control weight, 1/(ft·lbf)².
    poles : (N,) complex array
        Eigenvalues of A − BK, rad/s, sorted by real part.
    margin : float
        Worst :func:`sector_margin` over the poles, units of n (> 0: all inside).
    residual : float
        Relative Riccati residual (:func:`acmm.riccati.care_residual`) of (A + shift·I, B, Q, R, P)
        in the scaled coordinates.
    shift : float
        α (rad/s): K is the LQR gain of (A + αI, B, Q, R).
    mirror_shifts : tuple of float
        The h (rad/s) of each pole-shifting step (``method="shift"``).
    method, riccati_method : str
        Design method and Riccati solver.
    scale : (N,) array or None
        State scaling used, x = diag(scale) x̃.
    eig_condition : (N,) array
        Condition number κ_i = ‖w_i‖‖v_i‖/|w_i^H v_i| of each pole (same order as ``poles``) of
        A − BK in the scaled coordinates (:func:`eigen_conditioning`).
    robustness_radius, robustness_radius_elementwise : float
        Sector robustness radius (:func:`sector_robustness`): the estimated smallest relative
        gain error that moves a pole out of the sector, normwise (‖δK̃‖₂/‖K̃‖₂, scaled) and
        elementwise (max |δK_ij/K_ij|).
    riccati_condition : float
        κ_CARE of the Riccati equation solved for the shifted LQR (:mod:`acmm.riccati`).
    riccati_ill_conditioned : bool
        κ_CARE above :data:`acmm.riccati.ILL_CONDITIONED`.
    """

    K: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    poles: np.ndarray
    margin: float
    residual: float
    shift: float
    mirror_shifts: tuple = ()
    method: str = "shift"
    riccati_method: str = "scipy"
    scale: np.ndarray | None = field(default=None)
    eig_condition: np.ndarray = field(default_factory=lambda: np.zeros(0))
    robustness_radius: float = float("nan")
    robustness_radius_elementwise: float = float("nan")
    riccati_condition: float = float("nan")
    riccati_ill_conditioned: bool = False

    @property
    def max_eig_condition(self) -> float:
        """Largest eigenvalue condition number of A − BK in the scaled coordinates."""
        return float(np.max(self.eig_condition)) if self.eig_condition.size else float("nan")


def eigen_conditioning(Acl):
    """Eigenvalues λ_i, right/left eigenvectors and condition numbers of ``Acl``.

    κ_i = ‖w_i‖₂‖v_i‖₂/|w_i^H v_i| (Wilkinson): a perturbation E of Acl moves λ_i by at most
    κ_i‖E‖₂ to first order.  Returns (λ, V, W, κ) with W = V⁻¹ (rows are left eigenvectors
    normalized so that W V = I), so that κ_i = ‖W[i]‖‖V[:, i]‖.
    """
    lam, V = np.linalg.eig(np.asarray(Acl, dtype=float))
    try:
        W = np.linalg.inv(V)
    except np.linalg.LinAlgError:
        return lam, V, np.full_like(V, np.nan), np.full(lam.shape, np.inf)
    kappa = np.linalg.norm(V, axis=0) * np.linalg.norm(W, axis=1)
    return lam, V, W, kappa


def sector_robustness(A, B, K, n: float, sigma: float = 0.5, half_angle_deg: float = 45.0,
                      scale=None) -> tuple[float, float]:
    """Estimated smallest relative gain error that moves a pole of A − BK out of the sector.

    First-order eigenvalue perturbation: δλ_i = −w_i^H B δK v_i (W V = I).  A pole with
    :func:`sector_margin` m_i (units of n) leaves the sector once |δλ_i| ≥ m_i n, so ::

        ε_norm = min_i m_i n / (‖K̃‖₂ ‖B̃'w̄_i‖₂ ‖v_i‖₂)           (‖δK̃‖₂ ≤ ε‖K̃‖₂, scaled),
        ε_elem = min_i m_i n / Σ_ab |(w_i^H B)_a K_ab v_ib|        (|δK_ab| ≤ ε|K_ab|),

    the first attained by the rank-one δK̃ = −ε‖K̃‖ (B̃'w̄_i)(v_i)^H/(‖·‖‖·‖) aligned with the
    pole's outward normal.  Both are first-order *estimates* (exact for small radii; clusters
    of poles make them optimistic or pessimistic).  Zero if a pole is already outside.

    Parameters
    ----------
    A, B, K : arrays
        Model and gain (physical units; ``scale`` applied for the normwise radius).
    n, sigma, half_angle_deg :
        Sector (units of n, deg).
    scale : (N,) array or None
        State scaling x = diag(scale) x̃ in which the normwise radius is measured.

    Returns
    -------
    (ε_norm, ε_elem) : tuple of float
    """
    A, B, K = (np.asarray(x, dtype=float) for x in (A, B, K))
    if scale is not None:
        d = np.asarray(scale, dtype=float)
        A, B, K = A / d[:, None] * d[None, :], B / d[:, None], K * d[None, :]
    lam, V, W, _ = eigen_conditioning(A - B @ K)
    m = sector_margin(lam, n, sigma, half_angle_deg)
    if np.min(m) <= 0:
        return 0.0, 0.0
    wb = W @ B                                              # rows w_i^H B
    kn = np.linalg.norm(K, 2)
    sens_norm = kn * np.linalg.norm(wb, axis=1) * np.linalg.norm(V, axis=0)
    sens_elem = np.einsum("ia,ab,bi->i", np.abs(wb), np.abs(K), np.abs(V))
    with np.errstate(divide="ignore"):
        e_norm = float(np.min(m * n / sens_norm))
        e_elem = float(np.min(m * n / sens_elem))
    return e_norm, e_elem


def _required_h(lam: np.ndarray, n: float, sigma: float, phi: float, target: float) -> np.ndarray:
    """Mirror line h (rad/s) that moves λ = a + ib (a < 0) to −(2h − |a|) + ib with margin `target`."""
    a = np.abs(lam.real)
    b = np.abs(lam.imag)
    h_angle = 0.5 * (a + (b * np.cos(phi) + target * n) / np.sin(phi))
    h_decay = 0.5 * (a + (sigma + target) * n)
    # h > |a| is needed for the Q = 0 Riccati equation to mirror λ at all.
    return np.maximum.reduce([h_angle, h_decay, a * (1.0 + 1e-3) + 1e-3 * target * n])


def _group(h: np.ndarray, rel_gap: float = 0.02) -> list[tuple[float, float]]:
    """Chain-link sorted h values into groups whose neighbours differ by < rel_gap."""
    hs = np.sort(h)
    groups, lo, hi = [], hs[0], hs[0]
    for v in hs[1:]:
        if v - hi <= rel_gap * hi:
            hi = v
        else:
            groups.append((lo, hi))
            lo = hi = v
    groups.append((lo, hi))
    return groups


#: PBH ratio σmin([A − λI, B]) / ‖[A, B]‖₂ below which a mode counts as uncontrollable.
UNCONTROLLABLE_RATIO = 1e-12


def _check_movable(As, Bs, n, sigma, half_angle_deg, min_margin):
    """DesignError if an open-loop pole that must move is (numerically) uncontrollable (PBH)."""
    lam = np.linalg.eigvals(As)
    outside = lam[sector_margin(lam, n, sigma, half_angle_deg) < min_margin]
    if outside.size == 0:
        return
    nx = As.shape[0]
    norm = np.linalg.norm(np.hstack([As, Bs]), 2)
    for z in outside:
        smin = np.linalg.svd(np.hstack([As - z * np.eye(nx), Bs]), compute_uv=False)[-1]
        if smin <= UNCONTROLLABLE_RATIO * norm:
            raise DesignError(
                f"sector LQR: open-loop pole λ/n = {complex(z / n):.4g} lies outside the sector "
                f"and is uncontrollable (PBH ratio {smin / norm:.2e}); no feedback can move it")


def _finish(As, Bs, Qs, R, Ps, alpha, n, sigma, half_angle_deg, d, min_margin, residual_tol,
            method, riccati_method, mirror_shifts) -> SectorLQR:
    """Verify a design in scaled coordinates and map it back to physical units."""
    Ps = 0.5 * (Ps + Ps.T)
    Qs = 0.5 * (Qs + Qs.T)
    Ks = np.linalg.solve(R, Bs.T @ Ps)
    poles = np.linalg.eigvals(As - Bs @ Ks)
    poles = poles[np.lexsort((poles.imag, poles.real))]
    margins = sector_margin(poles, n, sigma, half_angle_deg)
    margin = float(np.min(margins))
    nx = As.shape[0]
    qmin = float(np.min(np.linalg.eigvalsh(Qs))) if nx else 0.0
    if qmin < -1e-12 * max(1.0, np.linalg.norm(Qs, 2)):
        raise DesignError(f"sector LQR ({method}): Q is not positive semidefinite "
                          f"(smallest eigenvalue {qmin:.3e})")
    res = care_residual(As + alpha * np.eye(nx), Bs, Qs, R, Ps)
    if not res <= residual_tol:
        raise ConvergenceError(f"sector LQR ({method}, Riccati method {riccati_method!r}): relative "
                               f"Riccati residual {res:.3e} exceeds tolerance {residual_tol:.1e}")
    if margin < min_margin:
        bad = poles[margins < min_margin]
        raise DesignError(
            f"sector LQR ({method}): {bad.size} closed-loop pole(s) outside the sector "
            f"Re λ ≤ −{sigma}n, |Im λ| ≤ tan({half_angle_deg}°)|Re λ| with margin {min_margin}n "
            f"(worst margin {margin:.3g}n at λ/n = {complex(bad[0] / n):.4g})")
    lam_c, _, _, kappa = eigen_conditioning(As - Bs @ Ks)
    kappa = kappa[np.lexsort((lam_c.imag, lam_c.real))]
    e_norm, e_elem = sector_robustness(As, Bs, Ks, n, sigma, half_angle_deg)
    kcare = care_condition(As + alpha * np.eye(nx), Bs, Qs, R, Ps)
    if d is not None:
        K = Ks / d[None, :]
        P = Ps / d[:, None] / d[None, :]
        Q = Qs / d[:, None] / d[None, :]
    else:
        K, P, Q = Ks, Ps, Qs
    return SectorLQR(K=K, P=P, Q=Q, R=R, poles=poles, margin=margin, residual=res, shift=alpha,
                     mirror_shifts=tuple(mirror_shifts), method=method,
                     riccati_method=riccati_method, scale=d, eig_condition=kappa,
                     robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                     riccati_condition=kcare, riccati_ill_conditioned=bool(not kcare <= ILL_CONDITIONED))


def sector_lqr(A, B, R, n: float, *, sigma: float = 0.5, half_angle_deg: float = 45.0,
               Q0=None, scale=None, method: str = "shift", riccati_method: str = "scipy",
               residual_tol: float = 1e-9, min_margin: float = 0.01,
               max_uniform_shift: float = 100.0, line_spacing: float = 0.0) -> SectorLQR:
    """LQR gain with every closed-loop pole in the sector of Fig 5.2 (module docstring).

    Parameters
    ----------
    A : (N, N) array
        Open-loop state matrix (eq 4.46), 1/s.
    B : (N, M) array
        Control input matrix.
    R : float or (M, M) array
        Control weight, e.g. 1e-4 = 1/(100 ft·lbf)² per axis; a float r means r·I.
    n : float
        Orbital rate, rad/s (the sector's unit).
    sigma : float
        Minimum decay rate σ in units of n (Re λ ≤ −σn).
    half_angle_deg : float
        Sector half-angle φ, deg (|Im λ| ≤ tan φ |Re λ|).
    Q0 : None, float or (N, N) array
        Initial state weight in the coordinates the problem is solved in — the scaled states x̃
        when ``scale`` is given (dimensionless), else physical.  None or 0: minimum energy.
        A float q means q·I.
    scale : (N,) array or None
        Nominal state magnitudes d (x = diag(d) x̃); strongly recommended (`docs/ERRATA.md` § Scaling).
    method : {"shift", "uniform"}
        Optimal pole shifting of the stray poles, or the smallest uniform shift.
    riccati_method : {"scipy", "sign", "slycot"}
        Solver used for every Riccati equation (:func:`acmm.riccati.solve_care`).
    residual_tol : float
        Largest accepted relative Riccati residual (scaled coordinates).
    min_margin : float
        Required :func:`sector_margin` of every pole, units of n; moved poles are placed with
        1.5× this margin.
    max_uniform_shift : float
        Largest α/n tried by ``method="uniform"``.
    line_spacing : float
        ``method="shift"``: 0 mirrors every stray pole of a group about one line (the poles of
        a group stay clustered); δ > 0 mirrors them one real-Schur block at a time, the k-th
        about h + kδn (raised further until it lands ≥ δn from every other pole), so the
        moved poles are distinct (units of n).

    Returns
    -------
    SectorLQR

    Raises
    ------
    DesignError
        A pole cannot be brought into the sector (or Q would be indefinite).
    ConvergenceError
        A Riccati solve failed or its residual exceeds ``residual_tol``.
    """
    if method not in ("shift", "uniform"):
        raise ValueError(f"method must be 'shift' or 'uniform', got {method!r}")
    if not (n > 0 and sigma > 0 and 0 < half_angle_deg < 90 and min_margin >= 0):
        raise ValueError("need n > 0, sigma > 0, 0 < half_angle_deg < 90 and min_margin ≥ 0")
    from acmm.lqr_methods import _problem, _sector_shift, _sector_uniform   # they build on this module

    p = _problem(A, B, R, n, sigma, half_angle_deg, Q0, scale, method, riccati_method, residual_tol,
                 min_margin)
    if method == "uniform":
        return _sector_uniform(p, max_uniform_shift)
    return _sector_shift(p, line_spacing)
