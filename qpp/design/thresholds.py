"""The threshold m of eq 12.1 in each bookkeeping (CR-185644 ch. 12.1, eqs 10.53–10.55, 14.8).

β3 and β4 are computed along the nominal loop (γ nominal, r = r_o, d = 0) for the nonlinearity's
kind: the sinusoidal feedback of ch. 13 (``report`` and ``circle`` half-widths), a user
expression (``computed``, ``stated``), the polar arm of ch. 14 (``trajectory``), plus the
``printed`` values when the config gives them.  The bookkeepings are described in
:mod:`qpp.design.procedure` (``docs/ERRATA.md`` § QPP thresholds).  They reproduce the report's
arithmetic; the certificate itself is :func:`consistent` (one sector, one norm: the Euclidean one,
``docs/qpp-certificates.md``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import cumulative_trapezoid

from qpp.design import spheres
from qpp.design.nominal_enclosure import PAD, NominalEnclosure, enclose
from qpp.io.config import ExpressionNonlinearity, QppConfig, SinusoidalNonlinearity
from qpp.simulate.closed_loop import initial_state, simulate_nominal
from qpp.model.arm_bounds import arm_slope_bound
from qpp.model.matched_nonlinearity import config_f1


@dataclass
class Thresholds:
    """β3, β4 and m (12.1) of one bookkeeping.

    Attributes
    ----------
    name : str
        Bookkeeping: ``printed``, ``report``, ``circle``, ``computed``, ``stated``,
        ``trajectory`` (the report's arithmetic, reproduced) or ``consistent`` (the certificate:
        :func:`consistent`).
    half_width : float
        Sector half-width k used for β3 and β4 (dimensionless gain; NaN when not applicable).
    beta3 : float
        β3 (10.54), dimensionless gain of the truncated L2 norms.
    beta4 : float
        β4 (10.55), in the units of the plant output (truncated L2 norm, unit·s^½).
    m : float
        Threshold m = β_o/(β_ri + ‖d‖∞ + β_o·β3 + β4) of eq 12.1, dimensionless.
    """

    name: str
    half_width: float
    beta3: float
    beta4: float
    m: float


def nominal_output(cfg: QppConfig, K1, Kc, H, T: float, n: int = 801, extra=()):
    """Nominal loop (γ nominal, r = r_o, d = 0) on [0, T]: (t, y_o, x_o).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (units: s, rad/s, the plant's own units).
    K1 : (m, n) array
        State-feedback gain, input units per state unit.
    Kc : (m, q) array
        Compensator gain, input units per compensator-state unit.
    H : (n, p) array
        Observer gain, state units per output unit per s.
    T : float
        Horizon, s.
    n : int
        Number of samples.
    extra : sequence of float
        Further sample times in [0, T], s (the truncation time of the certificate).

    Returns
    -------
    tuple of arrays
        t (n,) in s, y_o (p, n) in output units, x_o (n_x, n) in state units.
    """
    P = cfg.lure_plant()
    f1, g_nom = config_f1(cfg, P)
    t = np.union1d(np.linspace(0.0, T, n), [x for x in extra if 0.0 <= x <= T])
    Z, _ = simulate_nominal(P, K1, Kc, H, f1, g_nom, cfg.simulation.r_o, t, initial_state(cfg, P, K1, Kc),
                            rtol=1e-9, atol=1e-11)
    return t, P.C @ Z[:P.n], Z[:P.n]


def _arm_betas(cfg: QppConfig, t, x_o, T):
    """β3, β4 of the polar arm along the nominal trajectory (sup over M ∈ {M_min, M_max})."""
    P = cfg.lure_plant()
    nl = cfg.nonlinearity
    f1, g_nom = config_f1(cfg, P)
    N = P.N()
    b3 = b4 = 0.0
    h = 1e-6

    def phi(X, M):
        return np.array([N @ (f1(x, tt, M) - f1(x, tt, g_nom)) for x, tt in zip(X.T, t)])

    for M in (nl.M_min, nl.M_max):
        b4 = max(b4, spheres.truncated_l2(t, phi(x_o, M).T, T))
        for j in range(P.p):           # ∂φ/∂y_j with y_j = x_j (C = [I 0])
            e = np.zeros((P.n, 1))
            e[j] = h
            b3 = max(b3, spheres.truncated_l2(t, ((phi(x_o + e, M) - phi(x_o - e, M)) / (2 * h)).T, T))
    return b3, b4


def thresholds(cfg: QppConfig, t, y_o, x_o, sector, T: float) -> list[Thresholds]:
    """Threshold m (12.1) in each bookkeeping (see :mod:`qpp.design.procedure`) at truncation time T (s).

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (units: s, rad/s, the plant's own units).
    t : (S,) array
        Sample times of the nominal loop, s.
    y_o : (p, S) array
        Nominal output, output units.
    x_o : (n, S) array
        Nominal plant state, state units.
    sector : (r, 2) array
        Sector of the circle check, dimensionless gains.
    T : float
        Truncation time, s.

    Returns
    -------
    list of Thresholds
        One per bookkeeping available for this nonlinearity.
    """
    sp = cfg.spheres
    nl = cfg.nonlinearity
    out = []

    def add(name, k, b3, b4):
        out.append(Thresholds(name, k, b3, b4, spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))

    pub = cfg.published
    if pub.beta3 is not None and pub.beta4 is not None:
        add("printed", np.nan, pub.beta3, pub.beta4)
    if isinstance(nl, SinusoidalNonlinearity):
        k_rep = float(np.max(np.abs(np.asarray(nl.F_unc)).sum(axis=1)) * nl.gamma_max)
        for name, k in (("report", k_rep), ("circle", float(np.max(np.abs(sector))))):
            add(name, k, spheres.beta3_sinusoidal(k, nl.omega, T), spheres.beta4_sector(k, t, y_o, T))
    elif isinstance(nl, ExpressionNonlinearity):
        M = cfg.expression_model()
        b3, b4 = M.beta3(T), M.beta4(t, y_o, T)
        k = float(np.max(np.abs(sector)))
        add("computed", k, b3, b4)
        if nl.beta3 is not None or nl.beta4 is not None:
            add("stated", k, b3 if nl.beta3 is None else nl.beta3, b4 if nl.beta4 is None else nl.beta4)
    else:
        add("trajectory", np.nan, *_arm_betas(cfg, t, x_o, T))
    return out


#: The signal norm of the consistent certificate (stated in the output, qpp_design.h5 and the docs)
NORM = ("Euclidean: |v(t)|_2 at each t, truncated L2 in time; beta1 = H-infinity norm sigma_max "
        "(eq 10.36), the induced L2 gain")


@dataclass
class Consistent:
    """The certificate's threshold in one sector and one norm (Euclidean; ``docs/qpp-certificates.md``).

    Attributes
    ----------
    beta_i : float
        Euclidean input radius √p·β_ri + √r·‖d‖∞ (a sphere stated per component, ch. 9), output units.
    beta3 : float
        sup over t ∈ [0, T], y in range, θ of the spectral norm of ∇_yφ (eq 10.40, the induced L2
        gain of the increment of φ; bounded by (Σ_i g_i²)^½, g_i the row sum of |∂φ_i/∂y_j|),
        dimensionless.
    beta4 : float
        e^{aT}·‖(φ(y_o) − φ_o)_T‖₂ / E with |φ_i(y_o)| ≤ k_i |y_o,i| (k_i the largest |bound| of the
        circle's sector; |y_o|₂ for a coupled channel), the bound on β2/E of eq 10.53, output units.
    m : float
        β_o / (β_i + β_o β3 + β4), dimensionless.
    half_width : (r,) array
        k_i of the circle's sector, dimensionless gains.
    T_worst : float
        The end of the enclosure's cell of the smallest m, s: the sphere at time t rests on the
        truncation at t, so m is bounded for every T' ∈ (0, T] (cell by cell) and m is the least
        bound.
    E_over_m : float
        An upper bound of max over T' ∈ (0, T] of E(T')/m(T'), s^½; γ∞ · E_over_m ≤ 1 closes the
        step 10.45.
    m_sampled : float
        m of the trapezoid rule on the nominal loop's samples (smallest over them), dimensionless: an estimate
        that ``m`` bounds from below; (m_sampled − m)/m_sampled is the enclosure's gap.
    enclosure : qpp.design.nominal_enclosure.NominalEnclosure or None
        The nominal loop enclosed on cells of [0, T] (state units).
    note : dict
        ``unbounded``: why the nominal loop could not be enclosed (then m = 0); for the polar arm: ``rho_v`` (the rates' sphere, m/s and rad/s), ``dq_upper`` and ``dq_gap``
        (the bound of sup |Δq| and its enclosure's width, 1/m²).
    """

    beta_i: float
    beta3: float
    beta4: float
    m: float
    half_width: np.ndarray
    T_worst: float = np.nan
    E_over_m: float = np.nan
    m_sampled: float = np.nan
    enclosure: NominalEnclosure | None = None
    note: dict = field(default_factory=dict)


def _arm_beta3_cells(cfg: QppConfig, enc: NominalEnclosure, loop, a: float, beta_o: float):
    """The polar arm's β3 proved over the sphere around the nominal trajectory, per group of the
    enclosure's cells (:data:`ARM_GROUPS` groups of [0, T]): y = (x1, x2) within β_o of the
    enclosure of y_o, the rates (x3, x4) within ρ_v = γ_v β_o / γ∞ of theirs (γ_v the L2-to-peak gain
    to the rates, γ∞ to y: the step 10.45 that bounds |y − y_o| by β_o bounds the rates by ρ_v under
    the same premise ``peak``), M ∈ [M_min, M_max] (:func:`qpp.model.arm_bounds.arm_slope_bound`).

    Returns (group ends in s, cumulative bounds, ρ_v, the Δq branch and bound)."""
    P = cfg.lure_plant()
    Az, Bz, Cz, _ = loop
    An = Az + float(a) * np.eye(len(Az))
    Cv = np.zeros((2, Az.shape[0]))
    Cv[0, 2] = Cv[1, 3] = 1.0                     # the rates x3, x4 of z = [x; x_c; x̂]
    g_inf = spheres.l2_to_peak_gain(An, Bz, Cz)
    rho_v = spheres.l2_to_peak_gain(An, Bz, Cv) * beta_o / g_inf if g_inf > 0 else np.inf
    K = enc.lo.shape[1]
    groups = np.array_split(np.arange(K), min(ARM_GROUPS, K))
    x3, x4 = (np.array([[enc.lo[i, g].min() - rho_v for g in groups], [enc.hi[i, g].max() + rho_v for g in groups]])
              for i in (2, 3))
    x1 = (float(enc.lo[0].min() - beta_o), float(enc.hi[0].max() + beta_o))
    g, dq = arm_slope_bound(cfg.nonlinearity, P.N(), x1, x3, x4)
    ends = np.array([enc.edges[gr[-1] + 1] for gr in groups])
    return ends, np.maximum.accumulate(g), rho_v, dq


#: groups of the enclosure's cells on which the polar arm's β3 is bounded
ARM_GROUPS = 128


def _beta3_at(cfg: QppConfig, T: float, te: np.ndarray, k: np.ndarray, enc, loop, a: float, beta_o):
    """Upper bounds of β3(T') = sup over [0, T'] (nondecreasing in T') at the times ``te`` (s), and
    a note for the arm (ρ_v, the gap of sup |Δq|); see :func:`consistent`."""
    nl = cfg.nonlinearity
    if isinstance(nl, SinusoidalNonlinearity):     # closed form: k·sup_{[0, T']} |sin ωt|
        kk = np.maximum(k, cfg.sinusoidal_half_widths())
        return np.sqrt(np.sum(kk ** 2)) * spheres.sup_abs_sin(nl.omega, 0.0, te), {}
    if isinstance(nl, ExpressionNonlinearity):
        M = cfg.expression_model()
        if M.proof.slope_ok:         # proved bounds on cells of [0, T]; a T' takes every cell it reaches
            edges, G = M.proved_slope_cells(T)
            gn = np.maximum.accumulate(np.sqrt(np.sum(np.asarray(G, float) ** 2, axis=0)))
            idx = np.clip(np.searchsorted(edges, te, side="left") - 1, 0, gn.size - 1)
            return gn[idx], {}
        tg, g = M.slope_profile(T)   # not proved (the premise ``slope`` fails): the sampled profile
        g = np.array(g, float)
        if tg.size == 1:
            g = np.maximum(g, np.asarray(M.sector_info.slope_bound, float)[:, None])
            return np.full(te.size, float(np.max(np.sqrt(np.sum(g ** 2, axis=0)), initial=0.0))), {}
        gn = np.maximum.accumulate(np.sqrt(np.sum(g ** 2, axis=0)))
        return gn[np.clip(np.searchsorted(tg, te, side="left"), 0, tg.size - 1)], {}
    ends, gcum, rho_v, dq = _arm_beta3_cells(cfg, enc, loop, a, beta_o)
    return (gcum[np.clip(np.searchsorted(ends, te - 1e-12 * max(T, 1.0), side="left"), 0, gcum.size - 1)],
            {"rho_v": float(rho_v), "dq_gap": float(dq.gap), "dq_upper": float(dq.upper)})


def consistent(cfg: QppConfig, t, y_o, sector, coupled, T: float, a: float, loop) -> Consistent:
    """Threshold m (10.57, 12.1) in one sector (the circle criterion's) and one norm (Euclidean),
    bounded for every truncation time T' ∈ (0, T] from an enclosure of the nominal loop.

    The contraction of eqs 10.37–10.43 in the truncated L2 norm with the Euclidean vector norm:
    β1 ≤ m with β_i = √p·β_ri + √r·‖d‖∞ (10.44, |w − w_o|₂ of spheres stated per component),
    β3 the induced gain of eq 10.40 (a supremum over t, not the report's L2 norm in time of 10.54),
    β2 ≤ e^{aT} ‖(φ(y_o) − φ_o)_T‖₂ (the report's E·β4 of 10.53 holds only when E ≥ e^{aT}).

    The integral I(T') = ∫₀^{T'} Σ_i k_i² y_o,i² dt of β4 is bounded from the enclosure of the
    nominal loop (:mod:`qpp.design.nominal_enclosure`): each cell adds its width times the
    integrand's largest value f_j on its box.  For T' = t_j + x in a cell of width h:
    I(T')/E(T')² ≤ (I(t_j) + x f_j)/(E(t_j)² + x) (dE²/dT' = e^{2aT'} ≥ 1), monotone in x, so at most
    the larger of its values at x = 0 and x = h, and β4(T') ≤ e^{a t_{j+1}} (that value)^½; β3(T') ≤ β3(t_{j+1}) (a supremum over [0, T']); and
    E(T')/m(T') ≤ [E(t_{j+1})(β_i + β_o β3(t_{j+1})) + e^{a t_{j+1}} I(t_{j+1})^½] / β_o.  m is the
    smallest of the cells' lower bounds, E/m the largest of their upper bounds: no T' is missed.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config.
    t : (S,) array
        Sample times of the nominal loop, s (the trapezoid rule on them gives ``m_sampled``).
    y_o : (p, S) array
        Nominal output, output units.
    sector : (r, 2) array
        The circle criterion's sector, dimensionless gains.
    coupled : (r,) bool array
        Channels whose φ_i depends on other outputs than y_i.
    T : float
        Truncation time, s.
    a : float
        Exponential weighting a, 1/s.
    loop : tuple
        (A_z in 1/s, B_z of eq 10.7, C_z, z(0)) of the nominal loop.

    Returns
    -------
    Consistent
        β_i, β3, β4, m at the worst truncation time T' ≤ T, and max E/m.
    """
    sp = cfg.spheres
    P = cfg.lure_plant()
    Az, Bz, Cz, z0 = loop
    k = np.max(np.abs(np.asarray(sector, float)), axis=1)
    beta_i = float(np.sqrt(P.p) * sp.beta_ri + np.sqrt(P.r) * sp.d_inf)
    try:
        enc = enclose(Az, np.asarray(Bz)[:, :P.p], z0, cfg.simulation.r_o, T)
    except ValueError as exc:            # a loop too stiff for the cell budget: m is not bounded
        return Consistent(beta_i, np.inf, np.inf, 0.0, k, float(T), np.inf, note={"unbounded": str(exc)})
    te = enc.edges[1:]
    h = enc.h
    b3, note = _beta3_at(cfg, T, te, k, enc, loop, a, sp.beta_o)
    ylo, yhi = enc.box(Cz)
    ysup = np.maximum(np.abs(ylo), np.abs(yhi))
    ysq = np.sum(ysup ** 2, axis=0)
    f = sum(k[i] ** 2 * (ysq if (coupled[i] or i >= ysup.shape[0]) else ysup[i] ** 2) for i in range(k.size))
    f = np.asarray(f, float) * (1 + PAD)
    I_right = np.cumsum(h * f) * (1 + PAD)
    I_left = np.concatenate([[0.0], I_right[:-1]])
    E = spheres.E_factor(a, enc.edges)           # eq 10.44 at every edge
    E_lo, E_hi = E * (1 - PAD), E * (1 + PAD)
    grow = np.exp(a * te) * (1 + PAD)
    B = E_lo[:-1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(B > 0, I_left / B, 0.0)
    # (I_left + x f)/(B + x) is monotone in x ∈ [0, h]: its largest value is at an end
    b4 = grow * np.sqrt(np.maximum(ratio, (I_left + h * f) / (B + h)))
    with np.errstate(divide="ignore"):
        m = sp.beta_o / ((beta_i + sp.beta_o * b3 + b4) * (1 + PAD))
    j = int(np.argmin(m))
    e_over_m = (E_hi[1:] * (beta_i + sp.beta_o * b3) + grow * np.sqrt(I_right)) / sp.beta_o * (1 + PAD)
    m_s = _sampled_m(cfg, t, y_o, T, a, k, coupled, beta_i, b3, te)
    return Consistent(beta_i, float(b3[j]), float(b4[j]), float(m[j]), k, float(te[j]), float(np.max(e_over_m)),
                      m_sampled=m_s, enclosure=enc, note=note)


def _sampled_m(cfg, t, y_o, T, a, k, coupled, beta_i, b3, te) -> float:
    """m of the trapezoid rule on the nominal loop's samples, smallest over those samples (the
    estimate the enclosure bounds from below; their difference is the bound's gap)."""
    sp = cfg.spheres
    t = np.asarray(t, float)
    keep = (t <= T + 1e-12) & (t > 0)
    tk = np.concatenate([[0.0], t[keep]])
    yk = np.atleast_2d(np.asarray(y_o, float))[:, np.concatenate([[np.argmin(np.abs(t))], np.nonzero(keep)[0]])]
    ynorm = np.sqrt(np.sum(yk ** 2, axis=0))
    bound = np.array([k[i] * (ynorm if (coupled[i] or i >= yk.shape[0]) else np.abs(yk[i])) for i in range(k.size)])
    l2 = np.sqrt(np.maximum(cumulative_trapezoid(np.sum(bound ** 2, axis=0), tk, initial=0.0), 0.0))[1:]
    E = spheres.E_factor(a, tk[1:])
    b3s = b3[np.clip(np.searchsorted(te, tk[1:], side="left"), 0, b3.size - 1)]
    return float(np.min(sp.beta_o / (beta_i + sp.beta_o * b3s + np.exp(a * tk[1:]) * l2 / E), initial=np.inf))
