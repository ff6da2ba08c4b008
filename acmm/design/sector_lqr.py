"""LQR with every closed-loop pole in a sector (report ch. 5.2, eqs 5.2–5.4, Fig 5.2).

The sector LQR in one place: the sector and its margins, the design result :class:`SectorLQR` and
its checks (Q ⪰ 0, Riccati backward error, every pole in the sector, eigenvalue conditioning, the
sector robustness radius), the two methods that enforce the sector, and :func:`sector_lqr`.

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

Conditioning (the shipped configs; docs/results/design.md).  With Q0 = 0 the
shifted LQR mirrors repeated open-loop modes — the three DRF pairs at ±jn and ±j2n, the Jordan
chains h → ∫h at 0 — onto identical points: near-defective clusters with eigenvalue condition
numbers ~1e9, "in the sector" only to rounding.  The configs therefore use a small fixed diagonal
Q0 on the scaled states (7e-6 rates, 7e-7 attitudes, 5e-6 momentum, 2e-4 momentum integral, 0 DRF;
``Q0_groups``), which splits the Jordan chains, and ``min_margin = 0.1`` (n), so every pole is
≥ 0.1n inside: largest eigenvalue condition ≤ 5.4e4 at MB3, AC and every stair-case point (the
former 1e-5/1e-6/5e-6/5e-5 reached 9.99e4).  The weights were chosen by measurement among ~60
candidates (CHANGELOG.md) for the condition number *and*
for a second-order gain schedule that can be made stable along the whole path; larger weights lower
the condition number further but make the scheduled loop unstable.  ``line_spacing`` > 0 mirrors
stray poles one real-Schur block at a time about distinct lines (distinct poles; it did not help
the stair-case).  Every result carries the eigenvalue condition numbers (:func:`eigen_conditioning`),
the sector robustness radius (:func:`sector_robustness`) and the CARE condition estimate.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from acmm.model.controllability import pbh_ratios
from acmm.design.riccati import (ILL_CONDITIONED, as_R, care_backward_error, care_condition, care_residual,
                                 other_method_hint, residual_hint, scale_problem, solve_care)
from acmm_qpp.errors import ConvergenceError, DesignError

#: The hint of a design whose poles stay outside the sector: which settings to change.
SECTOR_HINT = ("lower design.sector.sigma, widen design.sector.half_angle_deg, or try "
               "design.pole_method: uniform / shift")


# ---------------------------------------------------------------------------------------------
# the sector of Fig 5.2 and the verification of a design
# ---------------------------------------------------------------------------------------------
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
    runs = np.split(hs, np.flatnonzero(~(np.diff(hs) <= rel_gap * hs[:-1])) + 1)   # (a NaN starts a group)
    return [(r[0], r[-1]) for r in runs]


#: PBH ratio of :func:`acmm.model.controllability.pbh_ratios` below which a mode counts as uncontrollable.
UNCONTROLLABLE_RATIO = 1e-12


def _check_movable(As, Bs, n, sigma, half_angle_deg, min_margin):
    """DesignError if an open-loop pole that must move is (numerically) uncontrollable (PBH)."""
    lam = np.linalg.eigvals(As)
    outside = lam[sector_margin(lam, n, sigma, half_angle_deg) < min_margin]
    for z, ratio in zip(outside, pbh_ratios(As, Bs, outside)):
        if ratio <= UNCONTROLLABLE_RATIO:
            hint = ("no gain moves that pole and no sector (σ > 0) holds Re λ ≥ 0: change design.model or "
                    "design.drf_mode (an axisymmetric station's neutral mode, say)" if z.real > -1e-9 * n else
                    "no gain moves that pole: lower design.sector.sigma, or change design.model / design.drf_mode")
            raise DesignError(
                f"sector LQR: open-loop pole λ/n = {complex(z / n):.4g} lies outside the sector "
                f"and is uncontrollable (PBH ratio {ratio:.2e}); no feedback can move it", hint=hint)


# ---------------------------------------------------------------------------------------------
# the two methods: a uniform shift, or the shift σn and optimal pole shifting of the stray poles
# ---------------------------------------------------------------------------------------------
@dataclass
class _SectorProblem:
    """One sector-LQR problem in the coordinates it is solved in (scaled when ``d`` is given)."""

    As: np.ndarray
    Bs: np.ndarray
    Q0s: np.ndarray
    R: np.ndarray
    d: np.ndarray | None
    n: float
    sigma: float
    half_angle_deg: float
    min_margin: float
    residual_tol: float
    method: str
    riccati_method: str
    e: float = 1.0              # input unit of the solve: Bs and R are B·e and R·e²

    @property
    def alpha(self) -> float:
        return self.sigma * self.n

    def lqr_shifted(self, a):
        """The LQR of (As + a·I, Bs, Q0s, R)."""
        eye = np.eye(self.As.shape[0])
        try:
            return solve_care(self.As + a * eye, self.Bs, self.Q0s, self.R, method=self.riccati_method,
                              tol=self.residual_tol)
        except ConvergenceError as exc:
            raise ConvergenceError(f"sector LQR ({self.method}) at shift α = {a / self.n:.4g}n: {exc}",
                                   hint="lower design.sector.sigma (the shift α asked of the LQR may be too "
                                        f"large), or {exc.hint or other_method_hint(self.riccati_method)}") from exc

    def finish(self, Qs, Ps, alpha, mirror_shifts) -> SectorLQR:
        """Verify a design in the solve's coordinates (the input in units of ``e``: B·e, R·e²) and
        map it back to physical units."""
        As, Bs, R, n, d, method = self.As, self.Bs, self.R, self.n, self.d, self.method
        Qs = 0.5 * (Qs + Qs.T)
        nx = As.shape[0]
        Ash = As + alpha * np.eye(nx)
        Ps = 0.5 * (Ps + Ps.T)
        Ks = np.linalg.solve(R, Bs.T @ Ps)
        poles = np.linalg.eigvals(As - Bs @ Ks)
        poles = poles[np.lexsort((poles.imag, poles.real))]
        margins = sector_margin(poles, n, self.sigma, self.half_angle_deg)
        margin = float(np.min(margins))
        qmin = float(np.min(np.linalg.eigvalsh(Qs))) if nx else 0.0
        if qmin < -1e-12 * max(1.0, np.linalg.norm(Qs, 2)):
            raise DesignError(f"sector LQR ({method}): Q is not positive semidefinite "
                              f"(smallest eigenvalue {qmin:.3e})", hint="change design.Q0 or design.R")
        res = care_residual(Ash, Bs, Qs, R, Ps)
        omega = care_backward_error(Ash, Bs, Qs, R, Ps)
        if not omega <= self.residual_tol:
            raise ConvergenceError(f"sector LQR ({method}, Riccati method {self.riccati_method!r}): Riccati "
                                   f"backward error {omega:.3e} exceeds tolerance {self.residual_tol:.1e} "
                                   f"(relative residual {res:.3e})", hint=residual_hint(self.riccati_method))
        if margin < self.min_margin:
            bad = poles[margins < self.min_margin]
            raise DesignError(
                f"sector LQR ({method}): {bad.size} closed-loop pole(s) outside the sector "
                f"Re λ ≤ −{self.sigma}n, |Im λ| ≤ tan({self.half_angle_deg}°)|Re λ| "
                f"with margin {self.min_margin}n "
                f"(worst margin {margin:.3g}n at λ/n = {complex(bad[0] / n):.4g})", hint=SECTOR_HINT)
        lam_c, _, _, kappa = eigen_conditioning(As - Bs @ Ks)
        kappa = kappa[np.lexsort((lam_c.imag, lam_c.real))]
        e_norm, e_elem = sector_robustness(As, Bs, Ks, n, self.sigma, self.half_angle_deg)
        kcare = care_condition(Ash, Bs, Qs, R, Ps)
        d1 = np.ones(nx) if d is None else d                # (x/1.0 is exact)
        P, Q = Ps / d1[:, None] / d1[None, :], Qs / d1[:, None] / d1[None, :]
        K, R = Ks / d1[None, :] * self.e, R / self.e ** 2    # u = e·ũ: K = e·K̃, R = R̃ / e²
        return SectorLQR(K=K, P=P, Q=Q, R=R, poles=poles, margin=margin, residual=res,
                         backward_error=omega, shift=alpha,
                         mirror_shifts=tuple(mirror_shifts), method=method,
                         riccati_method=self.riccati_method, scale=d, eig_condition=kappa,
                         robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                         riccati_condition=kcare, riccati_ill_conditioned=bool(not kcare <= ILL_CONDITIONED))


def _sector_uniform(p: _SectorProblem, max_uniform_shift: float) -> SectorLQR:
    """``method="uniform"``: the smallest uniform shift α ≥ σn whose LQR puts every pole in the
    sector (bracketing by 1.25×, then bisection to 0.1 %)."""
    n, alpha = p.n, p.alpha

    def ok(a):
        r = p.lqr_shifted(a)
        lam = np.linalg.eigvals(p.As - p.Bs @ r.K)
        return np.min(sector_margin(lam, n, p.sigma, p.half_angle_deg)) >= p.min_margin, r

    good, r = ok(alpha)
    if good:
        return p.finish(p.Q0s, r.P, alpha, ())
    # Gentle bracketing: the minimum-energy gains grow steeply with α (every mirrored pole
    # moves by 2α), and so does the Riccati condition number.
    lo, hi = alpha, 1.25 * alpha
    while True:
        good, r_hi = ok(hi)
        if good:
            break
        lo, hi = hi, 1.25 * hi
        if hi > max_uniform_shift * n:
            raise DesignError(f"sector LQR (uniform): no shift α ≤ {max_uniform_shift}n puts "
                              f"every pole in the sector", hint=SECTOR_HINT)
    while hi - lo > 1e-3 * hi:
        mid = 0.5 * (lo + hi)
        good, r_mid = ok(mid)
        if good:
            hi, r_hi = mid, r_mid
        else:
            lo = mid
    return p.finish(p.Q0s, r_hi.P, hi, ())


def _sector_shift(p: _SectorProblem, line_spacing: float) -> SectorLQR:
    """``method="shift"``: the LQR shifted by σn, then optimal pole shifting of the stray poles
    (up to 4 sweeps; each group of stray poles needing about the same line is mirrored)."""
    As, Bs, R, n = p.As, p.Bs, p.R, p.n
    phi = np.deg2rad(p.half_angle_deg)
    Ps = p.lqr_shifted(p.alpha).P.copy()
    Qs = p.Q0s.copy()
    target = 1.5 * p.min_margin
    mirror_shifts = []
    for _sweep in range(4):
        lam = np.linalg.eigvals(As - Bs @ np.linalg.solve(R, Bs.T @ Ps))
        stray = lam[sector_margin(lam, n, p.sigma, p.half_angle_deg) < p.min_margin]
        if stray.size == 0:
            break
        for lo, hi in _group(_required_h(stray, n, p.sigma, phi, target)):
            Ps, Qs = _mirror_group(p, Ps, Qs, lo, hi, line_spacing, target, mirror_shifts)
    return p.finish(Qs, Ps, p.alpha, mirror_shifts)


def _mirror_group(p: _SectorProblem, Ps, Qs, lo, hi, line_spacing, target, mirror_shifts):
    """Mirror the stray poles whose required line h lies in [lo, hi] (all about one line, or
    with ``line_spacing`` > 0 one real-Schur block at a time); returns the updated (P, Q) and
    appends each line used to ``mirror_shifts``."""
    As, Bs, R, n, alpha = p.As, p.Bs, p.R, p.n, p.alpha
    nx = As.shape[0]
    phi = np.deg2rad(p.half_angle_deg)

    def select(re, im, lo=lo, hi=hi):
        z = np.array([complex(re, im)])
        if sector_margin(z, n, p.sigma, p.half_angle_deg)[0] >= p.min_margin:
            return False
        h = _required_h(z, n, p.sigma, phi, target)[0]
        return bool(lo * (1 - 0.01) <= h <= hi * (1 + 0.01))

    for k in range(nx if line_spacing > 0 else 1):
        Acl = As - Bs @ np.linalg.solve(R, Bs.T @ Ps)
        T, Z, sdim = sla.schur(Acl.T, output="real", sort=select)
        if sdim == 0:
            break
        if line_spacing > 0:
            # one real-Schur block at a time (the leading block is invariant), each
            # about its own line: distinct poles instead of a near-defective cluster
            sdim = 2 if sdim > 1 and T[1, 0] != 0.0 else 1
        T11, U1 = T[:sdim, :sdim], Z[:, :sdim]
        lam1 = np.linalg.eigvals(T11)
        h = float(np.max(_required_h(lam1, n, p.sigma, phi, target)))
        h = max(h, alpha) + k * line_spacing * n
        if line_spacing > 0:
            h = _clear_line(h, lam1, np.linalg.eigvals(T[sdim:, sdim:]), line_spacing, n)
        try:
            sub = solve_care(T11.T + h * np.eye(sdim), U1.T @ Bs, np.zeros((sdim, sdim)), R,
                             method=p.riccati_method, tol=p.residual_tol)
        except ConvergenceError as exc:
            raise DesignError(f"sector LQR (shift): cannot shift the poles λ/n = "
                              f"{np.round(lam1 / n, 4).tolist()} (uncontrollable?): {exc}",
                              hint="widen design.sector.half_angle_deg or lower design.sector.sigma (a narrow "
                                   "sector leaves the moved poles a sliver of the plane), or try "
                                   "design.pole_method: uniform; a nearly uncontrollable model (see `acmm "
                                   "linearize`) needs another design.model or design.drf_mode") from exc
        dP = U1 @ sub.P @ U1.T
        dP = 0.5 * (dP + dP.T)
        Ps = Ps + dP
        Qs = Qs + 2.0 * (h - alpha) * dP
        mirror_shifts.append(h)
    return Ps, Qs


def _clear_line(h: float, lam1, rest, line_spacing: float, n: float) -> float:
    """Raise the mirror line h until the mirrored poles of ``lam1`` land at least
    ``line_spacing``·n from every pole in ``rest`` (nor onto or next to a pole already there)."""
    for _bump in range(400):
        moved = -(2.0 * h + lam1.real) + 1j * np.abs(lam1.imag)
        gap = np.min(np.abs(rest[None, :] - moved[:, None])) if rest.size else np.inf
        if gap >= line_spacing * n:
            break
        h += 0.25 * line_spacing * n
    return h


# ---------------------------------------------------------------------------------------------
# the design
# ---------------------------------------------------------------------------------------------
def sector_lqr(A, B, R, n: float, *, sigma: float = 0.5, half_angle_deg: float = 45.0,
               Q0=None, scale=None, method: str = "shift", riccati_method: str = "scipy",
               residual_tol: float = 1e-12, min_margin: float = 0.01,
               max_uniform_shift: float = 100.0, line_spacing: float = 0.0,
               input_scale: float = 1.0) -> SectorLQR:
    """LQR gain with every closed-loop pole in the sector of Fig 5.2 (module docstring).

    Parameters
    ----------
    A : (N, N) array
        Open-loop state matrix (eq 4.46), 1/s.
    B : (N, M) array
        Control input matrix, state units per ft·lbf (e.g. rad/s² per ft·lbf).
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
        Units of each state (rad, rad/s, ft·lbf·s, ...).
    method : {"shift", "uniform"}
        Optimal pole shifting of the stray poles, or the smallest uniform shift.
    riccati_method : {"scipy", "sign", "slycot"}
        Solver used for every Riccati equation (:func:`acmm.design.riccati.solve_care`).
    residual_tol : float
        Largest accepted Riccati backward error after refinement
        (:func:`acmm.design.riccati.care_backward_error`), dimensionless.
    min_margin : float
        Required :func:`sector_margin` of every pole, units of n; moved poles are placed with
        1.5× this margin.
    max_uniform_shift : float
        Largest α/n tried by ``method="uniform"``, dimensionless (units of n).
    line_spacing : float
        ``method="shift"``: 0 mirrors every stray pole of a group about one line (the poles of
        a group stay clustered); δ > 0 mirrors them one real-Schur block at a time, the k-th
        about h + kδn (raised further until it lands ≥ δn from every other pole), so the
        moved poles are distinct (units of n).
    input_scale : float
        Unit of the input in which the problem is solved, in units of the input (e.g. ft·lbf):
        B·e and R·e², K and R mapped back.  The stations of :func:`acmm.model.linearize.momentum_scale`
        beyond its band pass their momentum scale over the nominal one, so that a station k
        times smaller (torques k times smaller, R k² times larger) is the same scaled problem.

    Returns
    -------
    SectorLQR
        The verified design (K, P, Q in physical units).

    Raises
    ------
    ValueError
        ``method`` is unknown, or n, sigma, half_angle_deg or min_margin is out of range.
    DesignError
        A pole cannot be brought into the sector (or Q would be indefinite).
    ConvergenceError
        A Riccati solve failed or its backward error exceeds ``residual_tol``.
    """
    if method not in ("shift", "uniform"):
        raise ValueError(f"method must be 'shift' or 'uniform', got {method!r}")
    if not (n > 0 and sigma > 0 and 0 < half_angle_deg < 90 and min_margin >= 0):
        raise ValueError("need n > 0, sigma > 0, 0 < half_angle_deg < 90 and min_margin ≥ 0")
    if not (0 < input_scale < float("inf")):
        raise ValueError("need input_scale > 0")
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    nx, m = B.shape
    if Q0 is None:
        Q0s = np.zeros((nx, nx))
    else:
        Q0s = np.asarray(Q0, dtype=float)
        Q0s = float(Q0s) * np.eye(nx) if Q0s.ndim == 0 else 0.5 * (Q0s + Q0s.T)
    d = None if scale is None else np.asarray(scale, dtype=float)
    As, Bs = (A, B) if d is None else scale_problem(A, B, np.zeros((nx, nx)), d)[:2]
    Bs, R = Bs * input_scale, as_R(R, m) * input_scale ** 2
    _check_movable(As, Bs, n, sigma, half_angle_deg, min_margin)
    p = _SectorProblem(As, Bs, Q0s, R, d, n, sigma, half_angle_deg, min_margin, residual_tol, method,
                       riccati_method, float(input_scale))
    if method == "uniform":
        return _sector_uniform(p, max_uniform_shift)
    return _sector_shift(p, line_spacing)
