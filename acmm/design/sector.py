"""The sector of Fig 5.2 and the verification of a sector design (report ch. 5.2, eqs 5.2–5.4).

Margins of poles in the sector, the :class:`SectorLQR` result, eigenvalue conditioning and the
sector robustness radius, and the checks every design of :mod:`acmm.design.lqr` ends with (``_finish``:
Q ⪰ 0, Riccati residual, every pole in the sector).  Used by :mod:`acmm.design.lqr`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm_qpp.errors import ConvergenceError, DesignError
from acmm.design.riccati import ILL_CONDITIONED, care_backward_error, care_condition, care_residual



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

    Returns
    -------
    ndarray of float
        Margin m(λ) of each pole, in units of n (dimensionless); negative = outside.
    """
    lam = np.asarray(poles, dtype=complex)
    phi = np.deg2rad(half_angle_deg)
    x, y = lam.real, np.abs(lam.imag)
    d1 = -sigma * n - x
    d2 = -(y * np.cos(phi) + x * np.sin(phi))
    return np.minimum(d1, d2) / n


def in_sector(poles, n: float, sigma: float = 0.5, half_angle_deg: float = 45.0, *,
              min_margin: float = 0.0) -> np.ndarray:
    """Boolean mask: pole lies in the sector with :func:`sector_margin` ≥ ``min_margin`` (units of n).

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
    min_margin : float
        Required margin, in units of n.

    Returns
    -------
    bool array
        True where the pole lies in the sector with the required margin.
    """
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
        Relative Riccati residual (:func:`acmm.design.riccati.care_residual`) of (A + shift·I, B, Q, R, P)
        in the scaled coordinates, dimensionless (reported; acceptance is by ``backward_error``).
    shift : float
        α (rad/s): K is the LQR gain of (A + αI, B, Q, R).
    mirror_shifts : tuple of float
        The h (rad/s) of each pole-shifting step (``method="shift"``).
    method, riccati_method : str
        Design method and Riccati solver.
    scale : (N,) array or None
        State scaling used, x = diag(scale) x̃, in the units of each state.
    eig_condition : (N,) array
        Condition number κ_i = ‖w_i‖‖v_i‖/|w_i^H v_i| of each pole (same order as ``poles``) of
        A − BK in the scaled coordinates (:func:`eigen_conditioning`), dimensionless.
    robustness_radius, robustness_radius_elementwise : float
        Sector robustness radius (:func:`sector_robustness`): the estimated smallest relative
        gain error that moves a pole out of the sector, normwise (‖δK̃‖₂/‖K̃‖₂, scaled) and
        elementwise (max |δK_ij/K_ij|), dimensionless.
    riccati_condition : float
        κ_CARE of the Riccati equation solved for the shifted LQR (:mod:`acmm.design.riccati`),
        dimensionless.
    riccati_ill_conditioned : bool
        κ_CARE above :data:`acmm.design.riccati.ILL_CONDITIONED`.
    backward_error : float
        Backward error ω (:func:`acmm.design.riccati.care_backward_error`) of (A + shift·I, B, Q, R, P),
        the accepted quantity (≤ ``residual_tol``), dimensionless.
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
    backward_error: float = float("nan")

    @property
    def max_eig_condition(self) -> float:
        """Largest eigenvalue condition number of A − BK in the scaled coordinates."""
        return float(np.max(self.eig_condition)) if self.eig_condition.size else float("nan")


def eigen_conditioning(Acl):
    """Eigenvalues λ_i, right/left eigenvectors and condition numbers of ``Acl``.

    κ_i = ‖w_i‖₂‖v_i‖₂/|w_i^H v_i| (Wilkinson): a perturbation E of Acl moves λ_i by at most
    κ_i‖E‖₂ to first order.  Returns (λ, V, W, κ) with W = V⁻¹ (rows are left eigenvectors
    normalized so that W V = I), so that κ_i = ‖W[i]‖‖V[:, i]‖.

    Parameters
    ----------
    Acl : (N, N) array
        Closed-loop state matrix, units of the state (rad/s for a rate).

    Returns
    -------
    lam : (N,) complex array
        Eigenvalues λ_i, rad/s.
    V : (N, N) complex array
        Right eigenvectors (columns), dimensionless.
    W : (N, N) complex array
        V⁻¹ (rows are left eigenvectors), dimensionless; NaN if V is singular.
    kappa : (N,) array
        Condition numbers κ_i, dimensionless; inf if V is singular.
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
    n : float
        Orbital rate, rad/s.
    sigma : float
        Minimum decay rate in units of n.
    half_angle_deg : float
        Sector half-angle, deg.
    scale : (N,) array or None
        State scaling x = diag(scale) x̃ in which the normwise radius is measured, in the units
        of each state.

    Returns
    -------
    (ε_norm, ε_elem) : tuple of float
        Normwise and elementwise robustness radii, dimensionless (relative gain errors).
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


#: PBH ratio of :func:`acmm.model.controllability.pbh_ratios` below which a mode counts as uncontrollable.
UNCONTROLLABLE_RATIO = 1e-12


def _check_movable(As, Bs, n, sigma, half_angle_deg, min_margin):
    """DesignError if an open-loop pole that must move is (numerically) uncontrollable (PBH)."""
    lam = np.linalg.eigvals(As)
    outside = lam[sector_margin(lam, n, sigma, half_angle_deg) < min_margin]
    if outside.size == 0:
        return
    from acmm.model.controllability import pbh_ratios

    for z, ratio in zip(outside, pbh_ratios(As, Bs, outside)):
        if ratio <= UNCONTROLLABLE_RATIO:
            raise DesignError(
                f"sector LQR: open-loop pole λ/n = {complex(z / n):.4g} lies outside the sector "
                f"and is uncontrollable (PBH ratio {ratio:.2e}); no feedback can move it")


def _finish(As, Bs, Qs, R, Ps, alpha, n, sigma, half_angle_deg, d, min_margin, residual_tol,
            method, riccati_method, mirror_shifts, e: float = 1.0) -> SectorLQR:
    """Verify a design in scaled coordinates (the input in units of ``e``: B·e, R·e²) and map
    it back to physical units."""
    Qs = 0.5 * (Qs + Qs.T)
    nx = As.shape[0]
    Ash = As + alpha * np.eye(nx)
    Ps = 0.5 * (Ps + Ps.T)
    Ks = np.linalg.solve(R, Bs.T @ Ps)
    poles = np.linalg.eigvals(As - Bs @ Ks)
    poles = poles[np.lexsort((poles.imag, poles.real))]
    margins = sector_margin(poles, n, sigma, half_angle_deg)
    margin = float(np.min(margins))
    qmin = float(np.min(np.linalg.eigvalsh(Qs))) if nx else 0.0
    if qmin < -1e-12 * max(1.0, np.linalg.norm(Qs, 2)):
        raise DesignError(f"sector LQR ({method}): Q is not positive semidefinite "
                          f"(smallest eigenvalue {qmin:.3e})")
    res = care_residual(Ash, Bs, Qs, R, Ps)
    omega = care_backward_error(Ash, Bs, Qs, R, Ps)
    if not omega <= residual_tol:
        raise ConvergenceError(f"sector LQR ({method}, Riccati method {riccati_method!r}): Riccati "
                               f"backward error {omega:.3e} exceeds tolerance {residual_tol:.1e} "
                               f"(relative residual {res:.3e})")
    if margin < min_margin:
        bad = poles[margins < min_margin]
        raise DesignError(
            f"sector LQR ({method}): {bad.size} closed-loop pole(s) outside the sector "
            f"Re λ ≤ −{sigma}n, |Im λ| ≤ tan({half_angle_deg}°)|Re λ| with margin {min_margin}n "
            f"(worst margin {margin:.3g}n at λ/n = {complex(bad[0] / n):.4g})")
    lam_c, _, _, kappa = eigen_conditioning(As - Bs @ Ks)
    kappa = kappa[np.lexsort((lam_c.imag, lam_c.real))]
    e_norm, e_elem = sector_robustness(As, Bs, Ks, n, sigma, half_angle_deg)
    kcare = care_condition(Ash, Bs, Qs, R, Ps)
    if d is not None:
        K = Ks / d[None, :]
        P = Ps / d[:, None] / d[None, :]
        Q = Qs / d[:, None] / d[None, :]
    else:
        K, P, Q = Ks, Ps, Qs
    if e != 1.0:                        # u = e·ũ: K = e·K̃, R = R̃ / e²
        K, R = K * e, R / e ** 2
    return SectorLQR(K=K, P=P, Q=Q, R=R, poles=poles, margin=margin, residual=res,
                     backward_error=omega, shift=alpha,
                     mirror_shifts=tuple(mirror_shifts), method=method,
                     riccati_method=riccati_method, scale=d, eig_condition=kappa,
                     robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                     riccati_condition=kcare, riccati_ill_conditioned=bool(not kcare <= ILL_CONDITIONED))
