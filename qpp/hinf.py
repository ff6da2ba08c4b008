"""Chapter 11: H∞ state-feedback and observer gains (Riccati 11.1, steps 1–8).

The published gains are reproduced (NOTES.md, Part III) by the γ = 1 (ν = 1 after the
scaling 11.3) H∞ state-feedback Riccati equation on the a-shifted augmented plant

    Āᵀk + k Ā + k (G_a G_aᵀ/ν² − B_a B_aᵀ/ρ²) k + Qᵀ Q = 0,      Ā = aI + A_a     (11.1)

with controlled output z = [ρ u; W_s e], W_s e = C_c x_c, i.e. ``Q = [0 C_c]`` (``weight="servo"``);
the printed ``[C 0]`` (``weight="output"``) is available for comparison.  Then
``[K1 Kc] = −B_aᵀ k / ρ²`` (theorem 3).

The printed Lyapunov equation 11.2 has an indefinite solution; the observer gain is the
filter-Riccati (Kalman-type) gain ``(aI+A) h + h (aI+A)ᵀ − h Cᵀ C h + G Gᵀ = 0``,
``H = −h Cᵀ`` (``observer="filter"``), or with the DGKF-style correction of theorem 3
``H = −(I − h k11)⁻¹ h Cᵀ`` where ``k11`` is the plant block of k (``observer="dgkf"``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from acmm.errors import ConvergenceError, DesignError
from qpp.lure import LurePlant, augmented, closed_loop


@dataclass
class HinfGains:
    """Result of one pass of theorem 3 (eqs 11.1–11.3)."""

    K1: np.ndarray          #: (m, n) observer-state gain
    Kc: np.ndarray          #: (m, q) servo-state gain
    H: np.ndarray           #: (n, p) observer gain, printed sign (L = −H)
    k: np.ndarray           #: solution of 11.1
    h: np.ndarray           #: filter-Riccati solution
    rho: float
    nu: float
    a: float
    residual_k: float       #: relative residual of 11.1
    residual_h: float       #: relative residual of the filter Riccati equation
    lambda_kh: float        #: λ_max(k11 h), existence condition (iii)
    history: list = field(default_factory=list)

    @property
    def K(self) -> np.ndarray:
        """[K1 Kc]."""
        return np.hstack([self.K1, self.Kc])


def _rel_res(R, X):
    return float(np.abs(R).max() / max(np.abs(X).max(), 1e-300))


def hinf_gains(plant: LurePlant, *, rho: float, a: float, nu: float = 1.0,
               weight: str = "servo", observer: str = "filter") -> HinfGains:
    """Gains K1, Kc, H of theorem 3 for control weight ``rho`` and shift ``a``.

    Parameters
    ----------
    plant : LurePlant
    rho : float
        Control weight ρ > 0 in z = [ρ u; W_s e] (13.5); the report uses 1e-4 (ch. 13), 1e-3 (ch. 14).
    a : float
        Exponential weighting a ≥ 0, 1/s (10.27).
    nu : float
        H∞ level ν of the scaling 11.3 (γ = ν); the published gains use ν = 1.
    weight : {"servo", "output"}
        State weight ``[0 Cc]`` (reproduces the report) or the printed ``[C 0]``.
    observer : {"filter", "dgkf"}
        Observer gain: filter Riccati, or with the (I − h k11)⁻¹ correction.

    Raises
    ------
    DesignError
        No stabilizing non-negative solution of 11.1 exists at this (ρ, ν).
    """
    if rho <= 0 or nu <= 0 or a < 0:
        raise DesignError(f"need rho > 0, nu > 0, a >= 0 (got rho={rho}, nu={nu}, a={a})")
    P = plant
    Aa, Ba, Ga, _ = augmented(P)
    Ab = Aa + a * np.eye(Aa.shape[0])
    if weight == "servo":
        Cw = np.hstack([np.zeros((P.Cc.shape[0], P.n)), P.Cc])
    elif weight == "output":
        Cw = np.hstack([P.C, np.zeros((P.p, P.q))])
    else:
        raise ValueError(f"weight must be 'servo' or 'output', got {weight!r}")
    Q = Cw.T @ Cw
    Bcomb = np.hstack([Ba, Ga])
    R = np.diag([rho ** 2] * Ba.shape[1] + [-nu ** 2] * Ga.shape[1])
    try:
        k = sla.solve_continuous_are(Ab, Bcomb, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DesignError(f"Riccati 11.1 has no stabilizing solution at rho={rho:g}, nu={nu:g}: {exc}") from None
    k = 0.5 * (k + k.T)
    res_k = _rel_res(Ab.T @ k + k @ Ab + k @ (Ga @ Ga.T / nu ** 2 - Ba @ Ba.T / rho ** 2) @ k + Q, k)
    if not np.all(np.isfinite(k)) or res_k > 1e-6:
        raise ConvergenceError(f"Riccati 11.1 residual {res_k:.1e} too large at rho={rho:g}, nu={nu:g}")
    if np.linalg.eigvalsh(k).min() < -1e-9 * max(1.0, np.abs(k).max()):
        raise DesignError(f"Riccati 11.1 solution is not k ≥ 0 at rho={rho:g}, nu={nu:g} (step 4)")
    K = -Ba.T @ k / rho ** 2
    n = P.n
    Af = P.A + a * np.eye(n)
    GG = P.G @ P.G.T
    try:
        h = sla.solve_continuous_are(Af.T, P.C.T, GG, np.eye(P.p))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DesignError(f"filter Riccati equation has no stabilizing solution: {exc}") from None
    h = 0.5 * (h + h.T)
    res_h = _rel_res(Af @ h + h @ Af.T - h @ P.C.T @ P.C @ h + GG, h)
    k11 = k[:n, :n]
    lam = float(np.max(np.real(np.linalg.eigvals(k11 @ h))))
    if observer == "filter":
        H = -h @ P.C.T
    elif observer == "dgkf":
        H = -np.linalg.solve(np.eye(n) - h @ k11 / nu ** 2, h @ P.C.T)
    else:
        raise ValueError(f"observer must be 'filter' or 'dgkf', got {observer!r}")
    return HinfGains(K[:, :n], K[:, n:], H, k, h, rho, nu, a, res_k, res_h, lam)


def closed_loop_norm(plant: LurePlant, g: HinfGains, *, bz: str = "eq10.7") -> float:
    """δ = ‖T_wy‖∞ of the a-shifted closed loop (11.4) = β1 of these gains."""
    from qpp.spheres import hinf_norm

    Az, Bz, Cz = closed_loop(plant, g.K1, g.Kc, g.H, bz=bz)
    return hinf_norm(Az + g.a * np.eye(Az.shape[0]), Bz, Cz)[0]


def hinf_search(plant: LurePlant, *, rho: float, a: float, nu: float | None = None,
                rho_factor: float = 0.5, rho_min: float = 1e-8, max_iter: int = 60,
                weight: str = "servo", observer: str = "filter", bz: str = "eq10.7") -> HinfGains:
    """Steps 1–8 of ch. 11: lower ν while a solution exists, lower ρ when it stalls.

    Step 1 starts from ν = ‖T_wy‖∞ of the ν = 1 design (or the given ``nu``).  At each (ρ, ν) the
    Riccati 11.1 and filter equations are solved (step 2), δ = ‖T_wy‖∞ is evaluated (step 3), the
    existence conditions k ≥ 0, h ≥ 0 and λ_max(k h) < ν² are checked (steps 4–5); if δ < ν, ν ← δ
    (steps 6–7), otherwise ρ ← ρ·rho_factor until ρ ≤ rho_min (step 6).  The best gains (smallest δ)
    are returned (step 8); ``history`` lists (ρ, ν, δ, ok).
    """
    history = []
    best: HinfGains | None = None
    best_delta = np.inf
    if nu is None:
        g0 = hinf_gains(plant, rho=rho, a=a, nu=1.0, weight=weight, observer=observer)
        nu = closed_loop_norm(plant, g0, bz=bz)
        best, best_delta = g0, nu
        history.append((rho, 1.0, nu, True))
    for _ in range(max_iter):
        try:
            g = hinf_gains(plant, rho=rho, a=a, nu=nu, weight=weight, observer=observer)
            ok = g.lambda_kh < nu ** 2
            delta = closed_loop_norm(plant, g, bz=bz)
        except (DesignError, ConvergenceError):
            ok, delta, g = False, np.inf, None
        history.append((rho, nu, delta, ok))
        if ok and delta < best_delta:
            best, best_delta = g, delta
        if ok and delta < nu * (1 - 1e-6):
            nu = delta
            continue
        if rho * rho_factor < rho_min:
            break
        rho *= rho_factor
    if best is None:
        raise DesignError("H∞ search (ch. 11 steps 1-8) found no admissible gains")
    best.history = history
    return best
