"""Chapter 11: H∞ state-feedback and observer gains (Riccati 11.1, steps 1–8; CR-185644 ch. 11, eqs 11.1–11.3).

The published gains are reproduced (``docs/ERRATA.md`` § QPP chapter 11) by the γ = 1 (ν = 1 after the
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

from acmm_qpp.errors import ConvergenceError, DesignError
from qpp.model.lure import LurePlant, augmented, closed_loop
from qpp.design.spheres import hinf_norm

#: The hint of a failed H∞ Riccati equation: which settings of the qpp config to change.
RICCATI_HINT = "change hinf.rho or hinf.nu (larger values relax the H∞ problem), or set hinf.search: true"


@dataclass
class HinfGains:
    """Result of one pass of theorem 3 (eqs 11.1–11.3).

    Attributes
    ----------
    K1 : (m, n) ndarray
        Observer-state gain, in the units of the plant's u and x.
    Kc : (m, q) ndarray
        Servo-state gain, in the units of the plant's u and x_c.
    H : (n, p) ndarray
        Observer gain, printed sign (L = −H), in the units of the plant's x and y.
    k : (n+q, n+q) ndarray
        Solution of 11.1, in the units of the augmented plant.
    h : (n, n) ndarray
        Filter-Riccati solution, in the units of the plant's x.
    rho : float
        Control weight ρ, dimensionless.
    nu : float
        H∞ level ν, dimensionless.
    a : float
        Exponential weighting a, 1/s.
    residual_k : float
        Relative residual of 11.1, dimensionless.
    residual_h : float
        Relative residual of the filter Riccati equation, dimensionless.
    lambda_kh : float
        λ_max(k11 h), existence condition (iii), dimensionless.
    history : list
        One dict per pass of :func:`hinf_search` (empty for a single pass).
    """

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
               weight: str = "servo", observer: str = "filter", strict: bool = True) -> HinfGains:
    """Gains K1, Kc, H of theorem 3 for control weight ``rho`` and shift ``a``.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    rho : float
        Control weight ρ > 0 in z = [ρ u; W_s e] (13.5), dimensionless; the report uses 1e-4
        (ch. 13), 1e-3 (ch. 14).
    a : float
        Exponential weighting a ≥ 0, 1/s (10.27).
    nu : float
        H∞ level ν of the scaling 11.3 (γ = ν), dimensionless; the published gains use ν = 1.
    weight : {"servo", "output"}
        State weight ``[0 Cc]`` (reproduces the report) or the printed ``[C 0]``.
    observer : {"filter", "dgkf"}
        Observer gain: filter Riccati, or with the (I − h k11)⁻¹ correction.
    strict : bool
        Raise when k is not positive semi-definite (step 4); ``False`` returns the gains and leaves
        the tests to the caller (:func:`existence_tests`).

    Returns
    -------
    HinfGains
        The gains K1, Kc, H with the Riccati solutions and their residuals.

    Raises
    ------
    DesignError
        No stabilizing non-negative solution of 11.1 exists at this (ρ, ν).
    ConvergenceError
        The residual of 11.1 is too large.
    ValueError
        ``weight`` or ``observer`` is not one of the readings listed above.
    """
    if rho <= 0 or nu <= 0 or a < 0:
        raise DesignError(f"need rho > 0, nu > 0, a >= 0 (got rho={rho}, nu={nu}, a={a})")
    P = plant
    Aa, Ba, Ga, _ = augmented(P)
    Ab = Aa + a * np.eye(Aa.shape[0])
    if weight == "servo":                        # the state weight Q = C_wᵀ C_w
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
        raise DesignError(f"Riccati 11.1 has no stabilizing solution at rho={rho:g}, nu={nu:g}: {exc}",
                          hint=RICCATI_HINT) from None
    k = 0.5 * (k + k.T)
    res_k = _rel_res(Ab.T @ k + k @ Ab + k @ (Ga @ Ga.T / nu ** 2 - Ba @ Ba.T / rho ** 2) @ k + Q, k)
    if not np.all(np.isfinite(k)) or res_k > 1e-6:
        raise ConvergenceError(f"Riccati 11.1 residual {res_k:.1e} too large at rho={rho:g}, nu={nu:g}",
                               hint=RICCATI_HINT)
    if strict and np.linalg.eigvalsh(k).min() < -1e-9 * max(1.0, np.abs(k).max()):
        raise DesignError(f"Riccati 11.1 solution is not k ≥ 0 at rho={rho:g}, nu={nu:g} (step 4)", hint=RICCATI_HINT)
    K = -Ba.T @ k / rho ** 2
    n = P.n
    h, res_h = _filter_riccati(P, a)
    k11 = k[:n, :n]
    lam = float(np.max(np.real(np.linalg.eigvals(k11 @ h))))
    if observer == "filter":
        H = -h @ P.C.T
    elif observer == "dgkf":
        H = -np.linalg.solve(np.eye(n) - h @ k11 / nu ** 2, h @ P.C.T)
    else:
        raise ValueError(f"observer must be 'filter' or 'dgkf', got {observer!r}")
    return HinfGains(K[:, :n], K[:, n:], H, k, h, rho, nu, a, res_k, res_h, lam)


def _filter_riccati(P: LurePlant, a: float):
    """The filter Riccati solution h∞ of theorem 3 (a-shifted) and its relative residual."""
    Af = P.A + a * np.eye(P.n)
    GG = P.G @ P.G.T
    try:
        h = sla.solve_continuous_are(Af.T, P.C.T, GG, np.eye(P.p))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DesignError(f"filter Riccati equation has no stabilizing solution: {exc}",
                          hint="change hinf.rho or hinf.nu, or set hinf.search: true") from None
    h = 0.5 * (h + h.T)
    return h, _rel_res(Af @ h + h @ Af.T - h @ P.C.T @ P.C @ h + GG, h)


def closed_loop_norm(plant: LurePlant, g: HinfGains, *, bz: str = "eq10.7") -> float:
    """δ = ‖T_wy‖∞ of the a-shifted closed loop (11.4) = β1 of these gains.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    g : HinfGains
        The gains (and shift ``a``) of one pass of theorem 3.
    bz : {"eq10.7", "printed"}
        Reading of B_z (:func:`qpp.model.lure.closed_loop`).

    Returns
    -------
    float
        δ, the H∞ norm from w = [r; d] to y, in the units of y per unit of w.
    """
    Az, Bz, Cz = closed_loop(plant, g.K1, g.Kc, g.H, bz=bz)
    return hinf_norm(Az + g.a * np.eye(Az.shape[0]), Bz, Cz)[0]


def existence_tests(g: HinfGains) -> dict:
    """Existence conditions of theorem 3 / steps 4–5 of ch. 11 for one solution.

    ``k_psd``: k1 ⪰ 0 (plant block of k); ``h_psd``: h∞ ⪰ 0; ``spectral``: λmax(k1 h∞) < ν², i.e.
    λmax < 1 for the scaled system of 11.3 (the scaling multiplies k1 h∞ by ν⁻²).

    Parameters
    ----------
    g : HinfGains
        The gains and Riccati solutions of one pass of theorem 3.

    Returns
    -------
    dict
        ``k_psd``, ``h_psd``, ``spectral`` (bool) and ``lambda_kh_scaled`` (float, dimensionless).
    """
    k_psd = bool(np.linalg.eigvalsh(g.k).min() >= -1e-9 * max(1.0, np.abs(g.k).max()))
    h_psd = bool(np.linalg.eigvalsh(g.h).min() >= -1e-9 * max(1.0, np.abs(g.h).max()))
    scaled = g.lambda_kh / g.nu ** 2          # λmax(k1 h∞), computed by hinf_gains
    return {"k_psd": k_psd, "h_psd": h_psd, "lambda_kh_scaled": scaled, "spectral": bool(scaled < 1.0)}


def hinf_search(plant: LurePlant, *, rho: float, a: float, nu: float | None = None,
                rho_factor: float = 0.5, rho_min: float = 1e-8, max_iter: int = 60,
                weight: str = "servo", observer: str = "filter", bz: str = "eq10.7",
                target: float | None = None) -> HinfGains:
    """Steps 1–8 of ch. 11 with all of their tests.

    Step 1: ν starts at δ = ‖T_wy‖∞ of the ν = 1 design (or the given ``nu``).  Steps 2–3: solve
    Riccati 11.1 and the observer equation at (ρ, ν) and evaluate δ (11.4) — here δ is the a-shifted
    norm from w = [r; d] to y, i.e. β1 of the gains.  Step 4: k1 ⪰ 0 and h∞ ⪰ 0, else (δ ≥ ν:
    ρ ← ρ·rho_factor; δ < ν: ν ← δ).  Step 5: λmax(k1 h∞)/ν² < 1, same branching.  Step 6: δ < ν →
    ν ← δ (step 7: repeat while ν keeps falling); otherwise ρ ≤ ε (``rho_min``) ends the search
    (step 8), else ρ is decreased.  With ``target`` the search stops at the first admissible
    solution with δ ≤ target (procedure 12.1 step 2: "until β1 ≤ m").

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    rho : float
        Initial control weight ρ > 0, dimensionless.
    a : float
        Exponential weighting a ≥ 0, 1/s (10.27).
    nu : float or None
        Initial H∞ level ν, dimensionless; None starts from δ of the ν = 1 design (step 1).
    rho_factor : float
        Factor by which ρ is decreased, dimensionless.
    rho_min : float
        Smallest ρ (ε of step 6), dimensionless.
    max_iter : int
        Largest number of passes.
    weight : {"servo", "output"}
        State weight, as in :func:`hinf_gains`.
    observer : {"filter", "dgkf"}
        Observer gain, as in :func:`hinf_gains`.
    bz : {"eq10.7", "printed"}
        Reading of B_z (:func:`qpp.model.lure.closed_loop`).
    target : float or None
        Stop at the first admissible solution with δ ≤ target (units of y per unit of w); None
        searches on.

    Returns
    -------
    HinfGains
        The admissible gains of smallest δ; ``history`` holds one dict per pass: ρ, ν, δ, k_psd,
        h_psd, lambda_kh_scaled, spectral, admissible, action.

    Raises
    ------
    DesignError
        No admissible gains were found.
    """
    history = []
    best: HinfGains | None = None
    best_delta = np.inf
    if nu is None:                      # step 1: δ of the ν = 1 design (1 when that design fails)
        nu = _search_pass(plant, rho, a, 1.0, weight, observer, bz)[1]
        nu = nu if np.isfinite(nu) and nu > 0 else 1.0
    nu_min = np.inf
    for _ in range(max_iter):
        g, delta, rec = _search_pass(plant, rho, a, nu, weight, observer, bz)
        ok = rec["admissible"]
        history.append(rec)
        if ok and delta < best_delta:
            best, best_delta = g, delta
        rec["action"], nu, nu_min, rho, stop = _next_step(ok, delta, nu, nu_min, rho, rho_min, rho_factor,
                                                          target)
        if stop:
            break
    if best is None:
        raise DesignError("H∞ search (ch. 11 steps 1-8) found no admissible gains "
                          "(k1 ⪰ 0, h∞ ⪰ 0, λmax(k1 h∞) < ν² failed for every ρ, ν tried)")
    best.history = history
    return best


def _search_pass(plant: LurePlant, rho: float, a: float, nu: float, weight: str, observer: str, bz: str):
    """Steps 2–5 of ch. 11 at (ρ, ν): the gains (None when no solution), δ and the history record
    (existence tests, ``admissible``)."""
    rec = {"rho": rho, "nu": nu, "delta": np.inf, "k_psd": False, "h_psd": False,
           "lambda_kh_scaled": np.nan, "spectral": False, "admissible": False}
    try:
        g = hinf_gains(plant, rho=rho, a=a, nu=nu, weight=weight, observer=observer, strict=False)
        rec.update(existence_tests(g))
        rec["delta"] = delta = closed_loop_norm(plant, g, bz=bz)
    except (DesignError, ConvergenceError):
        g, delta = None, np.inf
    rec["admissible"] = bool(rec["k_psd"] and rec["h_psd"] and rec["spectral"] and np.isfinite(delta))
    return g, delta, rec


def _next_step(ok: bool, delta: float, nu: float, nu_min: float, rho: float, rho_min: float,
               rho_factor: float, target):
    """Steps 4–8 of ch. 11 after one pass: (action, ν, smallest ν, ρ, stop)."""
    if ok and target is not None and delta <= target:
        return "target met", nu, nu_min, rho, True
    if not ok:                                    # steps 4-5
        if np.isfinite(delta) and delta < nu:
            return "nu <- delta", delta, nu_min, rho, False
    elif delta < nu * (1 - 1e-6):                 # steps 6-7
        nu = delta
        if nu < nu_min:
            return "nu <- delta (smaller)", nu, nu, rho, False
    if rho <= rho_min:                            # step 6: rho <= eps -> step 8
        return "rho <= eps: stop", nu, nu_min, rho, True
    return "rho decreased", nu, nu_min, max(rho * rho_factor, rho_min), False
