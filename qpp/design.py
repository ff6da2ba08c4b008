"""Design procedure of ch. 12.1 and the guarantee certificate (theorem 2, lemma 1).

Steps (the iteration target is the bookkeeping ``design.bookkeeping``): (1) threshold m from β_o, β_ri, ‖d‖∞, β3, β4 (12.1); (2) H∞ gains (ch. 11) and
β1 = ‖C_z (sI − A_n)⁻¹ B_z‖∞; if β1 > m, ρ ← ρ·rho_factor and repeat while that lowers β1; (4) circle criterion on
H(−a + jω); if it fails, a ← a·a_factor and repeat.  T is kept at the configured value (the
report's settling-time choice).

Thresholds are reported in three bookkeepings (NOTES.md, Part III):

* ``"printed"``: the report's printed β3, β4 (when given in the config);
* ``"report"``: the report's arithmetic — sector half-width without the factor N of B = G N
  (0.05 in ch. 13), β3 = k‖(sin ωt)_T‖₂ (10.54), β4 = k‖(y_o)_T‖₂ (10.55);
* ``"circle"``: the same formulas with the half-width of the sector used in the circle check
  (N·γ_max = 0.5 in ch. 13), i.e. one consistent sector for both conditions.
For the polar arm, β3 and β4 are evaluated along the nominal trajectory (sup over M at the
bounds) by central differences; ``"report"`` and ``"circle"`` then coincide.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm.errors import ConvergenceError, DesignError
from qpp import circle as circle_mod
from qpp import spheres
from qpp.config import PolarArmNonlinearity, QppConfig, SinusoidalNonlinearity
from qpp.hinf import HinfGains, hinf_gains, hinf_search
from qpp.lure import channels, closed_loop
from qpp.simulate import eval_signal, initial_state, make_f1, simulate_loop


@dataclass
class Thresholds:
    """β3, β4 and m (12.1) of one bookkeeping."""

    name: str
    half_width: float
    beta3: float
    beta4: float
    m: float


@dataclass
class DesignResult:
    """Everything ``qpp design`` reports and stores."""

    K1: np.ndarray
    Kc: np.ndarray
    H: np.ndarray
    gains_source: str
    hinf: HinfGains | None
    a: float
    T: float
    Az: dict                      #: reading → A_z (same for both readings)
    Bz: dict                      #: reading → B_z
    Cz: np.ndarray
    beta1: dict                   #: reading → dict of spheres.beta1
    thresholds: list
    circle: circle_mod.CircleResult
    sector: np.ndarray
    E: float
    y_o_t: np.ndarray
    y_o: np.ndarray
    iterations: list = field(default_factory=list)

    def threshold(self, name: str) -> Thresholds:
        return next(t for t in self.thresholds if t.name == name)

    def verdicts(self) -> dict:
        """(reading, bookkeeping) → β1 ≤ m."""
        return {(r, t.name): bool(self.beta1[r]["value"] <= t.m) for r in self.beta1 for t in self.thresholds}


def default_sector(cfg: QppConfig) -> np.ndarray:
    """Sector of φ = N (f1 − f1o) for the circle check: config value, else ±N·γ_max·|F_unc| (diagonal)."""
    if cfg.design.sector is not None:
        return np.asarray(cfg.design.sector, float)
    nl = cfg.nonlinearity
    if isinstance(nl, SinusoidalNonlinearity):
        P = cfg.lure_plant()
        k = np.abs(P.N() @ np.asarray(nl.F_unc, float)).sum(axis=1) * nl.gamma_max
        k = np.where(k > 0, k, 1e-12)
        return np.column_stack([-k, k])
    raise DesignError("design.sector must be given for a polar_arm nonlinearity")


def nominal_output(cfg: QppConfig, K1, Kc, H, T: float, n: int = 801):
    """Nominal loop (γ nominal, r = r_o, d = 0) on [0, T]: (t, y_o, x_o)."""
    P = cfg.lure_plant()
    f1, g_nom = make_f1(cfg.nonlinearity, P)
    t = np.linspace(0.0, T, n)
    Z, _ = simulate_loop(P, K1, Kc, H, f1, gamma=g_nom, gamma_nominal=g_nom,
                         r_fun=lambda tt: eval_signal(cfg.simulation.r_o, tt), t_eval=t,
                         z0=initial_state(cfg, P, K1, Kc), rtol=1e-9, atol=1e-11)
    return t, P.C @ Z[:P.n], Z[:P.n]


def _arm_betas(cfg: QppConfig, t, x_o, T):
    """β3, β4 of the polar arm along the nominal trajectory (sup over M ∈ {M_min, M_max})."""
    P = cfg.lure_plant()
    nl = cfg.nonlinearity
    f1, g_nom = make_f1(nl, P)
    N = P.N()
    b3 = b4 = 0.0
    h = 1e-6
    for M in (nl.M_min, nl.M_max):
        phi = np.array([N @ (f1(x, tt, M) - f1(x, tt, g_nom)) for x, tt in zip(x_o.T, t)]).T
        b4 = max(b4, spheres.truncated_l2(t, phi, T))
        grads = []
        for j in range(P.p):           # ∂φ/∂y_j with y_j = x_j (C = [I 0])
            e = np.zeros(P.n)
            e[j] = h
            gp = np.array([N @ (f1(x + e, tt, M) - f1(x + e, tt, g_nom)) for x, tt in zip(x_o.T, t)])
            gm = np.array([N @ (f1(x - e, tt, M) - f1(x - e, tt, g_nom)) for x, tt in zip(x_o.T, t)])
            grads.append(((gp - gm) / (2 * h)).T)
        b3 = max(b3, max(spheres.truncated_l2(t, g, T) for g in grads))
    return b3, b4


def thresholds(cfg: QppConfig, t, y_o, x_o, sector) -> list[Thresholds]:
    """Threshold m (12.1) in each bookkeeping (see module docstring)."""
    sp = cfg.spheres
    nl = cfg.nonlinearity
    out = []
    pub = cfg.published
    if pub.beta3 is not None and pub.beta4 is not None:
        out.append(Thresholds("printed", np.nan, pub.beta3, pub.beta4,
                              spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, pub.beta3, pub.beta4)))
    if isinstance(nl, SinusoidalNonlinearity):
        k_rep = float(np.max(np.abs(np.asarray(nl.F_unc)).sum(axis=1)) * nl.gamma_max)
        k_circ = float(np.max(np.abs(sector)))
        for name, k in (("report", k_rep), ("circle", k_circ)):
            b3 = spheres.beta3_sinusoidal(k, nl.omega, sp.T)
            b4 = spheres.beta4_sector(k, t, y_o, sp.T)
            out.append(Thresholds(name, k, b3, b4, spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))
    else:
        b3, b4 = _arm_betas(cfg, t, x_o, sp.T)
        out.append(Thresholds("trajectory", np.nan, b3, b4,
                              spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))
    return out


def certify(cfg: QppConfig, K1, Kc, H, a: float, gains_source: str = "given",
            hinf: HinfGains | None = None) -> DesignResult:
    """β1 for both B_z readings, thresholds, and the circle criterion for fixed gains."""
    P = cfg.lure_plant()
    K1 = np.atleast_2d(np.asarray(K1, float))
    Kc = np.atleast_2d(np.asarray(Kc, float))
    H = np.asarray(H, float).reshape(P.n, P.p)
    Az = Bz = Cz = None
    Azd, Bzd, b1 = {}, {}, {}
    for reading in ("eq10.7", "printed"):
        Az, Bz, Cz = closed_loop(P, K1, Kc, H, bz=reading)
        Azd[reading], Bzd[reading] = Az, Bz
        b1[reading] = spheres.beta1(Az, Bz, Cz, a)
    sector = default_sector(cfg)
    _, dcols = channels(P)
    circ = circle_mod.circle_criterion(Az, Bzd["eq10.7"][:, dcols], Cz, sector, a=a)
    T = cfg.spheres.T
    t, y_o, x_o = nominal_output(cfg, K1, Kc, H, T)
    return DesignResult(K1, Kc, H, gains_source, hinf, a, T, Azd, Bzd, Cz, b1,
                        thresholds(cfg, t, y_o, x_o, sector), circ, sector, spheres.E_factor(a, T), t, y_o)


def design(cfg: QppConfig) -> DesignResult:
    """Procedure 12.1 (or certification of the printed gains when ``design.gains = published``)."""
    hc, dc = cfg.hinf, cfg.design
    P = cfg.lure_plant()
    if dc.gains == "published":
        p = cfg.published
        return certify(cfg, p.K1, p.Kc, p.H, hc.a, "published")
    rho, a = hc.rho, hc.a
    iterations = []
    best = None
    prev_b1 = np.inf
    for _ in range(dc.max_iter):
        try:
            if hc.search:
                g = hinf_search(P, rho=rho, a=a, nu=None, weight=hc.weight, observer=hc.observer, bz=dc.bz)
            else:
                g = hinf_gains(P, rho=rho, a=a, nu=hc.nu, weight=hc.weight, observer=hc.observer)
        except (DesignError, ConvergenceError) as exc:
            if best is None:
                raise
            iterations.append({"rho": rho, "a": a, "beta1": np.nan, "m": np.nan, "circle": False,
                               "note": str(exc)})
            break
        res = certify(cfg, g.K1, g.Kc, g.H, a, "hinf", g)
        names = [t.name for t in res.thresholds]
        m_ref = res.threshold(dc.bookkeeping if dc.bookkeeping in names else names[-1]).m
        b1 = res.beta1[dc.bz]["value"]
        iterations.append({"rho": rho, "a": a, "beta1": b1, "m": m_ref, "circle": res.circle.passed})
        if best is None or (res.circle.passed and b1 < best.beta1[dc.bz]["value"]):
            best = res
        if not res.circle.passed:
            a *= dc.a_factor
            continue
        if b1 <= m_ref or b1 >= prev_b1:      # met, or lowering rho no longer lowers beta1
            break
        prev_b1 = b1
        rho *= dc.rho_factor
    best.iterations = iterations
    return best
