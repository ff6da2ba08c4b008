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

A third bound, on the premise ``peak`` (γ∞·max E/m ≤ 1), holds for a loop that starts at rest and
tracks one sine r_o = A sin(ω_r t + φ) (:func:`peak_exclusion`).  γ∞ is the L2-to-peak gain of the
loop, and the nominal loop is that loop driven by r_o (shifted by a ≥ 0, which only helps), so
γ∞ ≥ |y_o(t)| / ‖r_o‖_{L2[0, t]} at every t.  T is the settling time: the last sample of the first
pass (``SETTLE_SAMPLES`` on [0, horizon]) where |y_o − r_o| exceeds band·P, P its peak over the
samples, reached at some sample t* ≤ T.  Hence |y_o(t*)| ≥ P − A and |y_o(t1)| ≥ |r_o(t1)| − band·P at
every later sample t1, so γ∞ ≥ L(T) = min over P ≥ 0 of max[(P − A)/‖r_o‖_T, max_{t1}(|r_o(t1)| −
band·P)/‖r_o‖_{t1}, the later samples combined by weak duality (:func:`_dual_line`)], whatever the gains.  The premise needs γ∞ E(T) ≤ m(T) ≤ U(T) =
β_o/(β_i + β_o β3_min(T)) (β3_min the sinusoidal φ's closed form, else 0) with E(T) ≥ √T: a
settling time with √T·L(T) > U(T) is excluded.

A fourth bound takes the premises ``contraction`` and ``peak`` together (:func:`settle_exclusion`,
whose docstring gives the argument): they keep y_o small on [0, T], and a loop that settles right
after T with so little output before it needs a large impulse response.

When an upper bound of m is ≤ 1 ≤ β1, no design of the family is certified (the premise
``contraction``, β1 < m, fails).  Otherwise :func:`search` evaluates a grid of the family (T the
settling time of each design: m is non-increasing in T and γ∞·max E/m non-decreasing, so a longer
T only loses) and reports the best margin found.

Where no bound excludes a settling time, a design may be certified there: :data:`REPORT_CERTIFIED`
names one of ch. 13 certified at the first pass's first sample (near the edge of the solvability of
Riccati 11.1, β1 is well below the grid's), and :func:`resettle` finds its settling time again on the
certificate's finer samples, where it is not.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from acmm_qpp.errors import ConvergenceError, DesignError
from qpp.design import spheres
from qpp.design.certificate import certify, default_sector
from qpp.design.hinf import hinf_gains
from qpp.design.procedure import weighted_plant
from qpp.io.config import QppConfig, SinusoidalNonlinearity
from mpmath import iv
from scipy.optimize import minimize, nnls


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
    k3 : float
        (Σ max(k_i, k_struct,i)²)^½ of a sinusoidal φ (β3 = k3·sup |sin ωt|), else 0, dimensionless.
    """

    servo_frequencies: list
    beta1_lower: float
    m_upper: float
    y0_term: float
    T_sin: float | None
    m_upper_sin: float | None
    beta_i: float
    k: np.ndarray = field(repr=False)
    k3: float = 0.0

    @property
    def excluded(self) -> bool:
        """Whether the bounds alone exclude every design of the family (m ≤ 1 ≤ β1 for every T)."""
        return bool(self.beta1_lower >= 1.0 and self.m_upper <= self.beta1_lower)


def _servo_frequencies(Ac) -> list:
    """Sorted distinct ω_k ≥ 0 (rad/s) of the poles of the servo-compensator's Ac (1/s, eq 10.2) on
    the imaginary axis: |Re λ| ≤ 1e-9·max(1, |λ|)."""
    lam = np.linalg.eigvals(np.atleast_2d(np.asarray(Ac, float)))
    on = lam[np.abs(lam.real) <= 1e-9 * np.maximum(1.0, np.abs(lam))]
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
    ws = _servo_frequencies(P.Ac)
    m_up = sp.beta_o / (beta_i + y0_term) if beta_i + y0_term > 0 else np.inf
    T_sin = m_sin = None
    k3 = 0.0
    nl = cfg.nonlinearity
    if isinstance(nl, SinusoidalNonlinearity) and nl.omega > 0:
        k3 = float(np.sqrt(np.sum(np.maximum(k, cfg.sinusoidal_half_widths()) ** 2)))
        T_sin = float(np.pi / (2 * nl.omega))
        m_sin = float(sp.beta_o / (beta_i + sp.beta_o * k3))
    return FamilyBounds(ws, 1.0 if ws else 0.0, float(m_up), y0_term, T_sin, m_sin, beta_i, k, k3)


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
    gamma_inf : float
        γ∞, the loop's L2-to-peak gain, output units per input unit·s^½.
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
    gamma_inf: float = np.nan


def _candidate(res, rho, w, a, freqs) -> Candidate:
    """The certificate ``res`` of the design (ρ, w, a in 1/s) as a Candidate; its servo gain is the min
    over ω_k (``freqs``, rad/s) of σ̄(C_z ((a + jω_k) I − A_n)⁻¹ B_z) (= σ̄ of the loop's T(jω_k))."""
    Az, Bz, Cz = res.Az["eq10.7"], res.Bz["eq10.7"], res.Cz
    servo = float(min(np.linalg.svd(Cz @ np.linalg.solve(1j * x * np.eye(len(Az)) - Az, Bz), compute_uv=False)[0]
                      for x in freqs)) if freqs else np.nan
    c = res.consistent
    return Candidate(float(rho), tuple(np.atleast_1d(w).astype(float)), float(a), res.T, res.beta1_ref, c.m,
                     res.gamma_inf * c.E_over_m, servo, res.certified,
                     [k for k, (ok, _) in res.premises.items() if not ok], float(res.gamma_inf))


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
    freqs = _servo_frequencies(P.Ac)
    hc = cfg.hinf
    horizon = max(cfg.simulation.t_final, cfg.spheres.T)
    out = []
    for rho, w, a in itertools.product(rhos, ws_list, a_list):
        try:
            g = hinf_gains(weighted_plant(P, w), rho=float(rho), a=float(a), nu=hc.nu, weight=hc.weight,
                           observer=hc.observer)
            first = certify(cfg, g.K1, g.Kc, g.H, float(a), T=horizon)     # (SETTLE_SAMPLES samples)
            T = float(min(max(first.T_settle, 1e-3 * horizon), horizon))
            res = certify(cfg, g.K1, g.Kc, g.H, float(a), T=T)
        except (DesignError, ConvergenceError, np.linalg.LinAlgError):
            continue
        out.append(_candidate(res, rho, w, a, freqs))
    return out


#: samples of [0, horizon] on which :func:`search`'s first pass finds the settling time
#: (:func:`qpp.design.certificate.certify` at T = horizon samples the nominal loop 801 times)
SETTLE_SAMPLES = 801


@dataclass
class PeakExclusion:
    """Settling times T excluded by the premise ``peak`` for every design (module docstring).

    Attributes
    ----------
    times : (K,) ndarray
        The possible settling times: the samples of the first pass in (0, horizon], s.
    gamma_lower : (K,) ndarray
        L(T), a lower bound of γ∞ of every design settling at T, output units per input unit·s^½.
    m_upper : (K,) ndarray
        U(T) ≥ m(T), dimensionless.
    excluded : (K,) bool ndarray
        √T·L(T) > U(T): no design settling at T meets the premise ``peak`` (dimensionless flags).
    """

    times: np.ndarray
    gamma_lower: np.ndarray
    m_upper: np.ndarray
    excluded: np.ndarray

    def open_below(self, T_max: float) -> np.ndarray:
        """The settling times below ``T_max`` that the bound leaves open.

        Parameters
        ----------
        T_max : float
            Upper end, s.

        Returns
        -------
        ndarray
            The open settling times, s.
        """
        return self.times[(self.times < T_max) & ~self.excluded]


#: later samples whose constraints the weak-duality bound of :func:`_dual_line` combines
DUAL_SAMPLES = 200


def _dual_line(t, A: float, w: float, ph: float, band: float) -> tuple:
    """γ∞ ≥ a0 − a1·P from every later sample at once, by weak duality.

    y_o(t_i) = ⟨h, g_i⟩ with h the loop's impulse response from r (‖h‖₂ ≤ γ∞) and
    g_i(s) = r_o(t_i − s) on [0, t_i]; settling gives s_i y_o(t_i) ≥ |r_o(t_i)| − band·P
    (s_i = sign r_o(t_i)).  For any λ ≥ 0, Σ λ_i s_i y_o(t_i) = ⟨h, Σ λ_i s_i g_i⟩, so
    γ∞ ≥ Σ λ_i (|r_o(t_i)| − band·P) / ‖Σ λ_i s_i g_i‖₂ (Cauchy–Schwarz), the Gram matrix of the g_i
    in closed form; λ from a non-negative least squares (any λ ≥ 0 gives a bound, the number is
    computed from it exactly).  t: sample times after T (s); r_o = A sin(w t + ph) (output units,
    rad/s, rad); band dimensionless; (a0, a1) per input unit·s^½ and per output unit of P.
    """
    if t.size == 0:
        return 0.0, 0.0
    r = A * np.sin(w * t + ph)
    sg = np.where(r >= 0, 1.0, -1.0)
    m = np.minimum(t[:, None], t[None, :])
    s = t[:, None] + t[None, :]
    G = A ** 2 / 2 * (m * np.cos(w * (t[:, None] - t[None, :]))
                      - (np.sin(w * s + 2 * ph) - np.sin(w * (s - 2 * m) + 2 * ph)) / (2 * w))
    G = G * sg[:, None] * sg[None, :]
    # (λ fitted at P = A; the line holds for every P)
    lam = _penalized_nnls(G, np.abs(r) - band * A, 20 * t.size)
    norm = float(np.sqrt(max(lam @ G @ lam, 0.0))) * (1 + 1e-9)
    if norm <= 0.0 or not np.any(lam > 0):
        return 0.0, 0.0
    return float(lam @ np.abs(r)) / norm, float(band * lam.sum()) / norm


def _penalized_nnls(G, c, maxiter: int) -> np.ndarray:
    """λ ≥ 0 minimizing λᵀGλ + pen·(cᵀλ − 1)², pen = 10³·max(λ_max(G), 1) (G symmetrized): the
    least ‖Σ λ_i g_i‖ on the line cᵀλ = 1 as a non-negative least squares (:func:`_dual_line`,
    :func:`_settle_multipliers`)."""
    ev, V = np.linalg.eigh(0.5 * (G + G.T))
    R = (V * np.sqrt(np.maximum(ev, 0.0))).T
    pen = np.sqrt(1e3 * max(float(np.max(ev)), 1.0))
    return nnls(np.vstack([R, pen * c[None, :]]), np.concatenate([np.zeros(R.shape[0]), [pen]]), maxiter=maxiter)[0]


def _min_max(g1, g2, A: float, e: float) -> float:
    """A lower bound of min over P ≥ 0 of max(g1(P), g2(P)), g1 non-increasing, g2 increasing
    (γ∞'s two bounds; :func:`peak_exclusion`): bisection on P to a bracket [lo, hi], then
    min(g1(hi), g2(lo)) — every P is ≤ hi (g1 ≥ g1(hi)) or ≥ lo (g2 ≥ g2(lo))."""
    lo, hi = 0.0, A + max(g1(0.0), 0.0) * e + 1.0
    if g1(lo) <= g2(lo):
        return max(g2(lo), 0.0)
    for _ in range(200):                   # g1(lo) > g2(lo), g1(hi) ≤ g2(hi)
        mid = 0.5 * (lo + hi)
        if g1(mid) > g2(mid):
            lo = mid
        else:
            hi = mid
    return max(min(g1(hi), g2(lo)), 0.0)


def _one_sine(cfg: QppConfig):
    """The one sine term of r_o (a :class:`qpp.io.config.Term`) when r_o is one sine on one channel
    and the nominal loop starts at rest, else None.  At rest: x0 = 0 (the observer starts equal) and
    x_c(0) = 0 (``xc0: zero``, ``equilibrium`` with x0 = 0, or a list of zeros), so that y_o = h * r_o."""
    ro, x0, xc0 = cfg.simulation.r_o, cfg.plant.x0, cfg.plant.xc0
    if cfg.lure_plant().p != 1 or len(ro) != 1 or len(ro[0]) != 1 or ro[0][0].kind != "sin" or ro[0][0].omega <= 0:
        return None
    if x0 is not None and np.any(np.asarray(x0, float) != 0.0):
        return None
    return None if isinstance(xc0, list) and np.any(np.asarray(xc0, float) != 0.0) else ro[0][0]


def peak_exclusion(cfg: QppConfig) -> PeakExclusion | None:
    """The settling times excluded by the premise ``peak`` for every design of the family (module
    docstring), or None when the bound does not apply (a loop that does not start at rest, or an
    r_o other than one sine on one channel).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.

    Returns
    -------
    PeakExclusion or None
        L(T), U(T) and the verdict per possible settling time.
    """
    ro = _one_sine(cfg)
    if ro is None:
        return None
    A, w, ph = abs(ro.amplitude), ro.omega, ro.phase
    band, sp = cfg.spheres.settle_band, cfg.spheres
    horizon = max(cfg.simulation.t_final, sp.T)
    t = np.linspace(0.0, horizon, SETTLE_SAMPLES)[1:]
    # ‖r_o‖_{L2[0, t]}: ‖A sin(ωs + φ)‖² = A² [t/2 − (sin(2(ωt + φ)) − sin 2φ)/(4ω)], (output unit)²·s
    energy = np.sqrt(A ** 2 * (t / 2 - (np.sin(2 * (w * t + ph)) - np.sin(2 * ph)) / (4 * w)))
    r_abs = np.abs(A * np.sin(w * t + ph))
    b = family_bounds(cfg)
    b3 = b.k3 * spheres.sup_abs_sin(cfg.nonlinearity.omega, 0.0, t) if b.k3 > 0 else np.zeros(t.size)
    U = sp.beta_o / (b.beta_i + sp.beta_o * b3)
    L = np.zeros(t.size)
    for j in range(t.size - 1):
        later = slice(j + 1, None)
        # the samples one at a time first; combined by duality only where that excludes nothing
        L[j] = _min_max(lambda p, later=later: float(np.max((r_abs[later] - band * p) / energy[later])),
                        lambda p, j=j: (p - A) / energy[j], A, energy[j])
        if np.sqrt(t[j]) * L[j] <= U[j] * (1 + 1e-9):
            a0, a1 = _dual_line(t[later][:DUAL_SAMPLES], A, w, ph, band)
            L[j] = _min_max(lambda p, later=later, a0=a0, a1=a1: max(
                float(np.max((r_abs[later] - band * p) / energy[later])), a0 - a1 * p),
                lambda p, j=j: (p - A) / energy[j], A, energy[j])
    excluded = np.sqrt(t) * L > U * (1 + 1e-9)
    return PeakExclusion(t, L, U, excluded)


#: later samples (after T) and cells of [0, T] whose constraints :func:`settle_exclusion` combines
SETTLE_LATER, SETTLE_CELLS = 48, 24
#: ν-intervals one settling time may be split into by :func:`settle_exclusion` (multipliers each)
SETTLE_SPLITS = 12
#: the weights τ of ‖μ‖² scanned when :func:`_settle_multipliers` chooses the multipliers
_SETTLE_TAUS = tuple(np.geomspace(1e-8, 1e2, 21))
#: quadrature points on [0, t_N] of the Gram matrices that only choose the multipliers
_SETTLE_QUAD = 4000


@dataclass
class SettleExclusion:
    """Settling times T excluded by the premises ``contraction`` and ``peak`` together, for every
    design (:func:`settle_exclusion`).

    Attributes
    ----------
    times : (K,) ndarray
        The settling times examined (those :func:`peak_exclusion` leaves open), s.
    nu_max : (K,) ndarray
        ν_max(T): ‖y_o‖_{L2[0, T]} of a design meeting ``contraction`` is below it, output units·s^½.
    gamma_lower : (K,) ndarray
        L(T, ν_max), a lower bound of γ∞ of every design settling at T with ‖y_o‖_T ≤ ν_max, output
        units per input unit·s^½.
    nu_low : (K,) ndarray
        The smallest ν the covering reached: 0 where T is excluded, output units·s^½.
    splits : (K,) int ndarray
        The ν-intervals used, dimensionless.
    excluded : (K,) bool ndarray
        Every ν ∈ [0, ν_max) covered: no design settling at T meets both premises (dimensionless flags).
    """

    times: np.ndarray
    nu_max: np.ndarray
    gamma_lower: np.ndarray
    nu_low: np.ndarray
    splits: np.ndarray
    excluded: np.ndarray

    def open_times(self) -> np.ndarray:
        """The settling times the bound leaves open.

        Returns
        -------
        ndarray
            The open settling times, s.
        """
        return self.times[~self.excluded]


def _settle_multipliers(later, sg, edges, c, nu: float, A: float, w: float, ph: float) -> tuple:
    """Multipliers λ ≥ 0 (later samples) and μ (cells of [0, T]) for :func:`settle_exclusion`: for
    each τ of :data:`_SETTLE_TAUS`, μ minimizes ‖q‖² + τ Σ μ_j² |cell_j| for given λ (least squares),
    then λ minimizes the reduced form under cᵀλ = 1 (non-negative least squares); the τ of the
    largest (cᵀλ − ν‖μ‖)/‖q‖ on the quadrature wins.  Any λ ≥ 0, μ give a bound (computed from them
    exactly by :func:`_settle_line`); this only chooses them.  later: sample times after T (s), sg
    signs of r_o there, edges of the cells of [0, T] (s), c = |r_o(t_i)| − band·P (output units), nu
    the bound of ‖y_o‖_{L2[0, T]}; λ dimensionless, μ per s.
    """
    S = _SETTLE_QUAD
    s = (np.arange(S) + 0.5) * later[-1] / S
    # g_i(s) = s_i r_o(t_i − s) (s < t_i) and G_j(s) = ∫_{cell j} r_o(t − s) 1[t > s] dt at the points s
    Pg = sg[:, None] * np.where(s[None, :] < later[:, None], A * np.sin(w * (later[:, None] - s[None, :]) + ph), 0.0)
    c0, c1 = edges[:-1][:, None], edges[1:][:, None]
    lo = np.maximum(c0, s[None, :])
    PG = np.where(s[None, :] < c1,
                  A / w * (np.cos(w * (lo - s[None, :]) + ph) - np.cos(w * (c1 - s[None, :]) + ph)), 0.0)
    dq = later[-1] / S
    Ggg, GgF, GFF = Pg @ Pg.T * dq, Pg @ PG.T * dq, PG @ PG.T * dq
    D = np.diff(edges)
    best = (-np.inf, np.zeros(later.size), np.zeros(D.size))
    for tau in _SETTLE_TAUS:
        K = np.linalg.solve(GFF + tau * np.diag(D), GgF.T)
        lam = _penalized_nnls(Ggg - GgF @ K, c, 50 * later.size)
        mu = K @ lam
        q2 = lam @ Ggg @ lam - 2 * lam @ GgF @ mu + mu @ GFF @ mu
        if q2 > 0:
            val = (c @ lam - nu * np.sqrt(mu @ (D * mu))) / np.sqrt(q2)
            if val > best[0]:
                best = (val, lam, mu)
    return best[1], best[2]


def _settle_line(later, sg, edges, lam, mu, A: float, w: float, ph: float) -> tuple:
    """(Σ λ_i s_i r_o(t_i), Σ λ_i, ‖μ‖_{L2[0, T]}, ‖q‖₂) of :func:`settle_exclusion` in mpmath's
    outward-rounded interval arithmetic (``iv``): q = Σ λ_i g_i − Σ μ_j G_j is, between consecutive
    breakpoints (cell edges and sample times), α + β cos ws + γ sin ws, and ‖q‖² is the sum of the
    pieces' integrals in closed form.  Intervals in output units, 1, output units·s^½ (twice).
    """
    W, Ai, PH = iv.mpf(w), iv.mpf(A), iv.mpf(ph)
    th_i = [W * iv.mpf(float(t)) + PH for t in later]
    th_e = [W * iv.mpf(float(e)) + PH for e in edges]
    bps = np.unique(np.concatenate([[0.0], edges, later]))
    total = iv.mpf(0)
    for s0, s1 in zip(bps[:-1], bps[1:]):
        if s1 <= s0:
            continue
        sm = 0.5 * (s0 + s1)
        al, be, ga = iv.mpf(0), iv.mpf(0), iv.mpf(0)
        for i in np.nonzero((later > sm) & (lam != 0))[0]:       # λ_i s_i A sin(θ_i − ws)
            f = iv.mpf(float(lam[i] * sg[i])) * Ai
            be += f * iv.sin(th_i[i])
            ga -= f * iv.cos(th_i[i])
        # −μ_j (A/w)[cos(w(max(c0, s) − s) + φ) − cos(θ_c1 − ws)]
        for j in np.nonzero((edges[1:] > sm) & (mu != 0))[0]:
            f = -iv.mpf(float(mu[j])) * Ai / W
            be -= f * iv.cos(th_e[j + 1])
            ga -= f * iv.sin(th_e[j + 1])
            if sm < edges[j]:
                be += f * iv.cos(th_e[j])
                ga += f * iv.sin(th_e[j])
            else:
                al += f * iv.cos(PH)
        a, b = iv.mpf(float(s0)), iv.mpf(float(s1))
        L = b - a
        i_c = (iv.sin(W * b) - iv.sin(W * a)) / W
        i_s = (iv.cos(W * a) - iv.cos(W * b)) / W
        i_cc = L / 2 + (iv.sin(2 * W * b) - iv.sin(2 * W * a)) / (4 * W)
        i_ss = L - i_cc
        i_cs = (iv.sin(W * b) ** 2 - iv.sin(W * a) ** 2) / (2 * W)
        total += (al * al * L + 2 * al * be * i_c + 2 * al * ga * i_s + be * be * i_cc + ga * ga * i_ss
                  + 2 * be * ga * i_cs)
    a0 = sum((iv.mpf(float(lam[i] * sg[i])) * Ai * iv.sin(th_i[i]) for i in range(later.size)), iv.mpf(0))
    lsum = sum((iv.mpf(float(x)) for x in lam), iv.mpf(0))
    cm = iv.sqrt(sum((iv.mpf(float(mu[j])) ** 2 * (iv.mpf(float(edges[j + 1])) - iv.mpf(float(edges[j])))
                      for j in range(mu.size)), iv.mpf(0)))
    return a0, lsum, cm, iv.sqrt(iv.mpf([0, total.b]))


@dataclass
class SettleLine:
    """One lower bound L(T, ν) of γ∞ (:func:`settle_exclusion`, step 3) with its multipliers.

    Attributes
    ----------
    T : float
        Settling time, s.
    nu : float
        Bound of ‖y_o‖_{L2[0, T]}, output units·s^½.
    later : (N,) ndarray
        Sample times after T whose settling constraints enter, s.
    signs : (N,) ndarray
        s_i, ±1 (dimensionless).
    edges : (M+1,) ndarray
        Cells of [0, T] of the multiplier μ, s.
    lam : (N,) ndarray
        λ ≥ 0, dimensionless.
    mu : (M,) ndarray
        μ per cell, 1/s.
    a0, lsum, mu_norm, q_norm, r_norm : tuple
        Σ λ_i s_i r_o(t_i), Σ λ_i, ‖μ‖₂, ‖q‖₂ and ‖r_o‖_{L2[0, T]} as (lower, upper) ends of their
        intervals: output units, dimensionless, output units·s^½ (the last three).
    gamma : float
        L(T, ν), the lower end of its interval, output units per input unit·s^½ (0 when the bound is void).
    """

    T: float
    nu: float
    later: np.ndarray
    signs: np.ndarray
    edges: np.ndarray
    lam: np.ndarray
    mu: np.ndarray
    a0: tuple
    lsum: tuple
    mu_norm: tuple
    q_norm: tuple
    r_norm: tuple
    gamma: float


def _settle_gamma(T: float, later, sg, edges, nu: float, A: float, w: float, ph: float, band: float) -> SettleLine:
    """L(T, ν) of :func:`settle_exclusion` from the multipliers fitted at P = A and then at the
    crossing P of the previous fit (three fits, the largest lower end kept)."""
    e_T = iv.sqrt(iv.mpf([0, (A ** 2 * (iv.mpf(T) / 2 - (iv.sin(2 * (w * iv.mpf(T) + ph)) - iv.sin(iv.mpf(2 * ph)))
                                          / (4 * w))).b]))
    r = A * np.sin(w * later + ph)
    z = (0.0, 0.0)
    best = SettleLine(T, nu, later, sg, edges, np.zeros(later.size), np.zeros(edges.size - 1), z, z, z, z,
                      (float(e_T.a), float(e_T.b)), 0.0)
    P_fit = A
    for _ in range(3):
        lam, mu = _settle_multipliers(later, sg, edges, sg * r - band * P_fit, nu, A, w, ph)
        if not np.any(lam > 0):
            break
        a0, lsum, cm, Q = _settle_line(later, sg, edges, lam, mu, A, w, ph)
        L = (a0 - cm * nu - band * lsum * A) / (Q + band * lsum * e_T)
        if float(L.a) > best.gamma:
            ends = [(float(x.a), float(x.b)) for x in (a0, lsum, cm, Q, e_T)]
            best = SettleLine(T, nu, later, sg, edges, lam, mu, *ends, float(L.a))
        P_fit = A + float(L.a) * float(e_T.b)
    return best


def _settle_setup(cfg: QppConfig) -> tuple | None:
    """(A, ω, φ, band, |k|₂, k3, family_bounds) of :func:`settle_exclusion`, or None where it does not apply."""
    ro, b = _one_sine(cfg), family_bounds(cfg)
    k_norm = float(np.sqrt(np.sum(b.k ** 2)))
    if ro is None or b.beta1_lower < 1.0 or k_norm <= 0:
        return None
    ph = float(ro.phase) + (np.pi if ro.amplitude < 0 else 0.0)
    return abs(ro.amplitude), float(ro.omega), ph, cfg.spheres.settle_band, k_norm, b.k3, b


def settle_exclusion(cfg: QppConfig, pe: PeakExclusion | None = None) -> SettleExclusion | None:
    """The settling times excluded by the premises ``contraction`` and ``peak`` together, for every
    design of the family, among those :func:`peak_exclusion` leaves open; None where that bound does
    not apply (a loop not at rest, an r_o other than one sine on one channel) or β1 has no lower bound.

    The argument (r_o = A sin(ωt + φ), a loop at rest, T a settling time of the first pass, as in
    :func:`peak_exclusion`; h the loop's impulse response from r, so y_o = h * r_o):

    1. *Contraction bounds y_o on [0, T].*  The certificate's m is at most its value at T' = T,
       β_o/(β_i + β_o β3(T) + β4(T)), with β3(T) ≥ β3_min(T) (the sinusoidal φ's closed form, else
       0) and β4(T) = e^{aT} ‖(k y_o)_T‖₂ / E(T) ≥ |k|₂ ν/√T, ν = ‖y_o‖_{L2[0, T]}, since
       e^{aT}/E(T) = (2a/(1 − e^{−2aT}))^½ ≥ T^{−½} (eq 10.44).  So m ≤ U(T, ν) = β_o/(β_i +
       β_o β3_min(T) + |k|₂ ν/√T), and β1 ≥ 1 (:func:`family_bounds`) with β1 < m needs
       ν < ν_max = √T (β_o − β_i − β_o β3_min(T)) / |k|₂.
    2. *Peak bounds γ∞ from above.*  γ∞ max E/m ≥ γ∞ E(T)/m(T) ≥ γ∞ √T / U(T, ν) (the
       certificate's E/m at T is at least (E(T)(β_i + β_o β3) + e^{aT}|k|₂ ν)/β_o), so the premise
       needs √T γ∞ ≤ U(T, ν).
    3. *Settling and a small y_o on [0, T] bound γ∞ from below.*  γ∞ ≥ ‖h‖₂ (the Gramian's
       r-column, and ‖e^{a·}h‖₂ ≥ ‖h‖₂ for a ≥ 0).  With g_i(s) = s_i r_o(t_i − s) on [0, t_i]
       (s_i = sign r_o(t_i), t_i the first :data:`SETTLE_LATER` samples after T) and
       G_j(s) = ∫_{cell j} r_o(t − s) 1[t > s] dt (:data:`SETTLE_CELLS` cells of [0, T]), for any
       λ ≥ 0 and μ, q = Σ λ_i g_i − Σ μ_j G_j gives ⟨h, q⟩ = Σ λ_i s_i y_o(t_i) − ∫₀^T μ y_o, hence
       (settling: s_i y_o(t_i) ≥ s_i r_o(t_i) − band·P; Cauchy–Schwarz twice)

           γ∞ ≥ (a_0 − band·P Σλ_i − ‖μ‖₂ ν) / ‖q‖₂,  a_0 = Σ λ_i s_i r_o(t_i),

       and, at the peak error's sample t* ≤ T, γ∞ ≥ (P − A)/‖r_o‖_{L2[0, T]}.  The smaller of the
       two over every P is L(T, ν) = (a_0 − band·A Σλ_i − ‖μ‖₂ ν) / (‖q‖₂ + band Σλ_i ‖r_o‖_T)
       (the lines' crossing), non-increasing in ν.  a_0, Σλ, ‖μ‖₂, ‖q‖₂ and ‖r_o‖_T are computed
       in closed form in interval arithmetic (:func:`_settle_line`) for multipliers chosen by
       :func:`_settle_multipliers`.
    4. *Covering ν.*  From ν_hi = ν_max: the interval [ν_lo, ν_hi] with U(T, ν_lo) < √T L(T, ν_hi)
       is excluded (for ν in it, √T γ∞ ≥ √T L(T, ν_hi) > U(T, ν_lo) ≥ U(T, ν)); then ν_hi ← ν_lo,
       new multipliers, at most :data:`SETTLE_SPLITS` times.  T is excluded when ν_lo ≤ 0.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    pe : PeakExclusion, optional
        :func:`peak_exclusion` of ``cfg`` (computed when not given).

    Returns
    -------
    SettleExclusion or None
        ν_max, L(T, ν_max), the covering and the verdict per open settling time.
    """
    setup = _settle_setup(cfg)
    pe = peak_exclusion(cfg) if pe is None and setup is not None else pe
    if setup is None or pe is None:
        return None
    A, w, ph, band, k_norm, k3, b = setup
    sp, nl = cfg.spheres, cfg.nonlinearity
    times = pe.times[~pe.excluded & (pe.times < (b.T_sin if b.T_sin is not None else np.inf))]
    rows = []
    bo, bi = iv.mpf(sp.beta_o), iv.mpf(b.beta_i)
    for T in times:
        Ti = iv.mpf(float(T))
        b3 = iv.mpf(0)
        if k3 > 0:
            x = iv.mpf(nl.omega) * Ti
            b3 = iv.mpf(k3) * (iv.sin(x) if x.b < np.pi / 2 else iv.mpf(1))
        nu_max = iv.sqrt(Ti) * (bo / iv.mpf(b.beta1_lower) - bi - bo * b3) / iv.mpf(k_norm)
        nu_hi = float(nu_max.b)
        later = pe.times[pe.times > T][:SETTLE_LATER]
        sg = np.where(A * np.sin(w * later + ph) >= 0, 1.0, -1.0)
        edges = np.linspace(0.0, float(T), SETTLE_CELLS + 1)
        gamma0, splits, ok = np.nan, 0, nu_hi <= 0
        while not ok and splits < SETTLE_SPLITS and later.size:
            L = iv.mpf(_settle_gamma(float(T), later, sg, edges, nu_hi, A, w, ph, band).gamma)
            splits += 1
            if splits == 1:
                gamma0 = float(L.a)
            if L.a <= 0:
                break
            # U(T, ν_lo) < √T L  ⟺  ν_lo > √T (β_o/(√T L) − β_i − β_o β3)/|k|₂ (its upper end, widened)
            nu_lo = float((iv.sqrt(Ti) * (bo / (iv.sqrt(Ti) * iv.mpf(L.a)) - bi - bo * b3) / iv.mpf(k_norm)).b)
            nu_lo = nu_lo + 1e-12 * max(abs(nu_lo), nu_hi)
            if nu_lo <= 0:
                nu_hi, ok = 0.0, True
                break
            if nu_lo >= nu_hi * (1 - 1e-3):
                break
            nu_hi = nu_lo
        rows.append((float(nu_max.b), gamma0, max(nu_hi, 0.0), splits, ok))
    cols = np.array(rows, float).reshape(-1, 5).T      # ν_max, L(T, ν_max), ν_low, splits, excluded
    return SettleExclusion(times, cols[0], cols[1], cols[2], cols[3].astype(int), cols[4].astype(bool))


#: evaluations of :func:`refine` from the best grid point
REFINE_EVALS = 30

#: designs of the family (ρ, w, a) that :func:`search` certifies at their settling time, per example
#: (issue 43): found near the edge of the solvability of Riccati 11.1 (large w, ρ just below the
#: largest ρ with a solution), where β1 falls to about 1.6 while the loop settles within the first
#: sample of the first pass; :func:`resettle` shows how they depend on that sampling
REPORT_CERTIFIED = {"qpp_siso": (1.3e-5, 1.69e4, 1e-8)}


def resettle(cfg: QppConfig, c: Candidate) -> Candidate:
    """The settling time of a candidate of :func:`search` taken again from the certificate at its T
    (which samples [0, max(T, t_final)] up to 20 001 times instead of the first pass's
    :data:`SETTLE_SAMPLES`), and the certificate at that settling time.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    c : Candidate
        A design of the family (its first weight w stands for every channel).

    Returns
    -------
    Candidate
        The same design certified at the finer settling time (``T``, s).
    """
    P = cfg.lure_plant()
    g = hinf_gains(weighted_plant(P, c.ws[0]), rho=c.rho, a=c.a, nu=cfg.hinf.nu,
                   weight=cfg.hinf.weight, observer=cfg.hinf.observer)
    T = float(certify(cfg, g.K1, g.Kc, g.H, c.a, T=c.T).T_settle)
    return _candidate(certify(cfg, g.K1, g.Kc, g.H, c.a, T=T), c.rho, c.ws[0], c.a, _servo_frequencies(P.Ac))

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
