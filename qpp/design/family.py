"""Procedure 12.1's family searched for a certificate of the report's examples (issue 43; CR-185644
ch. 11, 12.1, 13, 14).

What procedure 12.1 chooses: the control weight ρ and the output weight W_s = diag(w)·S_c of the
ch. 11 Riccati design (eq 13.5), the exponential weighting a (10.27) and the truncation time T
(step 3: the settling time of the closed loop).  The consistent certificate
(:func:`qpp.design.certificate.certify`) needs β1 < m.  Two bounds hold for EVERY design of that
family, whatever ρ, w, a and T:

* **β1 ≥ 1.**  The servo-compensator carries the internal model of r_o (poles ±jω_k on the
  imaginary axis, eq 10.2), so a stable loop tracks it exactly: the reference-to-output transfer
  T_ry(s) of the loop equals I at s = jω_k.  With A_n = A_z + aI Hurwitz, H(s) = C_z (sI − A_n)⁻¹ B_z
  = T(s − a) is analytic in Re s ≥ 0 and vanishes at infinity, so by the maximum modulus
  principle (σ̄ of an analytic matrix function is subharmonic) β1 = sup_ω σ̄(H(jω)) ≥ σ̄(H(a + jω_k))
  = σ̄(T(jω_k)) ≥ 1.
* **m is at most its limit at T' → 0.**  m = inf over T' ∈ (0, T] of β_o/(β_i + β_o β3(T') + β4(T'))
  (:func:`qpp.design.thresholds.consistent`), and β4(T') = e^{aT'} ‖(k y_o)_{T'}‖₂ / E(T') tends to
  |k ∘ y_o(0)|₂ as T' → 0, with y_o(0) = C x0 fixed by the config; β3 ≥ 0.  Hence
  m ≤ β_o / (β_i + |k ∘ C x0|₂) for every design.  For the sinusoidal φ of ch. 13, β3(T') is
  (Σ k_i²)^½ sup_{[0, T']} |sin ωt| whatever the gains, so once T ≥ π/(2ω):
  m ≤ β_o / (β_i + β_o (Σ k_i²)^½).

When an upper bound of m is ≤ 1 ≤ β1, no design of the family is certified (the premise
``contraction``, β1 < m, fails).  Otherwise :func:`search` evaluates a grid of the family (T the
settling time of each design: m is non-increasing in T and γ∞·max E/m non-decreasing, so a longer
T only loses) and reports the best margin found.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm_qpp.errors import ConvergenceError, DesignError
from qpp.design.certificate import certify, default_sector
from qpp.design.hinf import hinf_gains
from qpp.design.procedure import weighted_plant
from qpp.io.config import QppConfig
from qpp.io.config_nonlin import SinusoidalNonlinearity
from scipy.optimize import minimize


@dataclass
class FamilyBounds:
    """Bounds that hold for every design of procedure 12.1's family (module docstring).

    Attributes
    ----------
    servo_frequencies : list of float
        ω_k ≥ 0 of the servo-compensator's poles on the imaginary axis, rad/s.
    beta1_lower : float
        1.0 when the compensator has such poles (β1 ≥ 1), else 0.0, dimensionless.
    m_upper : float
        β_o / (β_i + |k ∘ C x0|₂), the bound for every T, dimensionless.
    y0_term : float
        |k ∘ C x0|₂, output units.
    T_sin : float or None
        π/(2ω) of a sinusoidal φ (s), from which on ``m_upper_sin`` holds; None otherwise.
    m_upper_sin : float or None
        β_o / (β_i + β_o (Σ k_i²)^½) for T ≥ ``T_sin``, dimensionless.
    beta_i : float
        √p·β_ri + √r·‖d‖∞, output units.
    k : (r,) ndarray
        Half-widths of the certificate's sector, dimensionless.
    """

    servo_frequencies: list
    beta1_lower: float
    m_upper: float
    y0_term: float
    T_sin: float | None
    m_upper_sin: float | None
    beta_i: float
    k: np.ndarray = field(repr=False)

    @property
    def excluded(self) -> bool:
        """Whether the bounds alone exclude every design of the family (m ≤ 1 ≤ β1 for every T)."""
        return bool(self.beta1_lower >= 1.0 and self.m_upper <= self.beta1_lower)


def servo_frequencies(Ac, tol: float = 1e-9) -> list:
    """The frequencies ω_k ≥ 0 of the servo-compensator's poles on the imaginary axis, rad/s.

    Parameters
    ----------
    Ac : (q, q) array
        Servo-compensator state matrix (eq 10.2), 1/s.
    tol : float
        A pole is on the axis when |Re λ| ≤ tol·max(1, |λ|), dimensionless.

    Returns
    -------
    list of float
        Sorted distinct ω_k, rad/s.
    """
    lam = np.linalg.eigvals(np.atleast_2d(np.asarray(Ac, float)))
    on = lam[np.abs(lam.real) <= tol * np.maximum(1.0, np.abs(lam))]
    return sorted({round(float(abs(x.imag)), 12) for x in on})


def family_bounds(cfg: QppConfig) -> FamilyBounds:
    """The bounds of the module docstring for a config.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (its sector, spheres, x0 and servo-compensator).

    Returns
    -------
    FamilyBounds
        β1's lower and m's upper bounds over the family.
    """
    P = cfg.lure_plant()
    sp = cfg.spheres
    k = np.max(np.abs(default_sector(cfg)), axis=1)
    beta_i = float(np.sqrt(P.p) * sp.beta_ri + np.sqrt(P.r) * sp.d_inf)
    x0 = np.zeros(P.n) if cfg.plant.x0 is None else np.asarray(cfg.plant.x0, float)
    y0 = P.C @ x0
    y0_term = float(np.sqrt(sum((k[i] * y0[i]) ** 2 for i in range(min(k.size, y0.size)))))
    ws = servo_frequencies(P.Ac)
    m_up = sp.beta_o / (beta_i + y0_term) if beta_i + y0_term > 0 else np.inf
    T_sin = m_sin = None
    nl = cfg.nonlinearity
    if isinstance(nl, SinusoidalNonlinearity) and nl.omega > 0:
        k_struct = np.abs(P.N() @ np.asarray(nl.F_unc, float)).sum(axis=1) * nl.gamma_max
        T_sin = float(np.pi / (2 * nl.omega))
        m_sin = float(sp.beta_o / (beta_i + sp.beta_o * np.sqrt(np.sum(np.maximum(k, k_struct) ** 2))))
    return FamilyBounds(ws, 1.0 if ws else 0.0, float(m_up), y0_term, T_sin, m_sin, beta_i, k)


@dataclass
class Candidate:
    """One design of the family, certified at T = its settling time.

    Attributes
    ----------
    rho : float
        Control weight ρ, dimensionless.
    ws : tuple of float
        W_s = diag(ws)·S_c, dimensionless.
    a : float
        Exponential weighting, 1/s.
    T : float
        Truncation time (the settling time of the nominal loop), s.
    beta1 : float
        β1, dimensionless.
    m : float
        The certificate's m at T, dimensionless.
    peak : float
        γ∞·max E/m, dimensionless.
    servo_gain : float
        min over ω_k of σ̄(H(a + jω_k)), dimensionless (≥ 1: the lower bound of β1 at work).
    certified : bool
        Every premise holds.
    failed : list of str
        The premises that fail.
    """

    rho: float
    ws: tuple
    a: float
    T: float
    beta1: float
    m: float
    peak: float
    servo_gain: float
    certified: bool
    failed: list


def _servo_gain(res, freqs) -> float:
    """min over ω_k of σ̄(C_z ((a + jω_k) I − A_n)⁻¹ B_z) (= σ̄ of the loop's T(jω_k)), dimensionless."""
    Az, Bz, Cz = res.Az["eq10.7"], res.Bz["eq10.7"], res.Cz
    n = len(Az)
    return float(min(np.linalg.svd(Cz @ np.linalg.solve(1j * w * np.eye(n) - Az, Bz), compute_uv=False)[0]
                     for w in freqs)) if freqs else np.nan


def search(cfg: QppConfig, rhos, ws_list, a_list) -> list:
    """Evaluate the family on a grid: for each (ρ, w, a) the ch. 11 gains (the config's ν, weight
    and observer), the nominal loop's settling time T, and the certificate at that T.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    rhos : sequence of float
        Control weights ρ, dimensionless.
    ws_list : sequence of float or tuple
        Output weights w of W_s = diag(w)·S_c, dimensionless.
    a_list : sequence of float
        Exponential weightings a, 1/s.

    Returns
    -------
    list of Candidate
        One per grid point whose Riccati equations have a stabilizing solution.
    """
    P = cfg.lure_plant()
    freqs = servo_frequencies(P.Ac)
    hc = cfg.hinf
    horizon = max(cfg.simulation.t_final, cfg.spheres.T)
    out = []
    for rho in rhos:
        for w in ws_list:
            for a in a_list:
                try:
                    g = hinf_gains(weighted_plant(P, w), rho=float(rho), a=float(a), nu=hc.nu, weight=hc.weight,
                                   observer=hc.observer)
                    first = certify(cfg, g.K1, g.Kc, g.H, float(a), T=horizon)
                    T = float(min(max(first.T_settle, 1e-3 * horizon), horizon))
                    res = certify(cfg, g.K1, g.Kc, g.H, float(a), T=T)
                except (DesignError, ConvergenceError, np.linalg.LinAlgError):
                    continue
                c = res.consistent
                out.append(Candidate(float(rho), tuple(np.atleast_1d(w).astype(float)), float(a), T,
                                     res.beta1_ref, c.m, res.gamma_inf * c.E_over_m, _servo_gain(res, freqs),
                                     res.certified, [k for k, (ok, _) in res.premises.items() if not ok]))
    return out


#: evaluations of :func:`refine` from the best grid point
REFINE_EVALS = 30

#: the grids of the report's examples searched (docs/qpp-certificates.md): ρ over six decades, five
#: output weights w, three a; the manipulator's bounds already exclude its family, its grid is smaller
REPORT_GRIDS = {
    "qpp_siso": {"rho": tuple(np.logspace(-6, 0, 13)), "w": (0.1, 0.3, 1.0, 3.0, 10.0), "a": (1e-8, 1e-2, 0.3)},
    "qpp_manipulator": {"rho": tuple(np.logspace(-5, -1, 5)), "w": (0.3, 1.0, 3.0), "a": (1e-9, 1e-2)},
}


def refine(cfg: QppConfig, start: Candidate, max_evals: int = REFINE_EVALS) -> tuple:
    """Nelder–Mead from a grid point over (log10 ρ, log10 w, log10 a), maximizing m − β1 of the
    design certified at its settling time (:func:`search`), a fixed number of evaluations.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    start : Candidate
        The grid point to start from (its first weight w stands for every channel).
    max_evals : int
        Evaluations of the family, dimensionless.

    Returns
    -------
    tuple
        (the best Candidate met, the number of evaluations).
    """
    seen = [start]

    def cost(x):
        c = search(cfg, [10.0 ** x[0]], [10.0 ** x[1]], [10.0 ** x[2]])
        if not c:
            return 10.0
        seen.append(c[0])
        return float(c[0].beta1 - c[0].m)

    x0 = np.log10([start.rho, start.ws[0], max(start.a, 1e-12)])
    minimize(cost, x0, method="Nelder-Mead", options={"maxfev": int(max_evals), "initial_simplex":
                                                     x0 + np.vstack([np.zeros(3), 0.5 * np.eye(3)])})
    return max(seen, key=lambda c: c.m - c.beta1), len(seen) - 1
