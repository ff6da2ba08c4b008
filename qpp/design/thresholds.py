"""The threshold m of eq 12.1 in each bookkeeping (CR-185644 ch. 12.1, eqs 10.53–10.55, 14.8).

β3 and β4 are computed along the nominal loop (γ nominal, r = r_o, d = 0) for the nonlinearity's
kind: the sinusoidal feedback of ch. 13 (``report`` and ``circle`` half-widths), a user
expression (``computed``, ``stated``), the polar arm of ch. 14 (``trajectory``), plus the
``printed`` values when the config gives them.  The bookkeepings are described in
:mod:`qpp.design.procedure` (``docs/ERRATA.md`` § QPP thresholds).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from qpp.design import spheres
from qpp.io.config_nonlin import ExpressionNonlinearity, SinusoidalNonlinearity
from qpp.io.config import QppConfig
from qpp.simulate.loop import initial_state, simulate_nominal
from qpp.model.matched_nonlinearity import config_f1


@dataclass
class Thresholds:
    """β3, β4 and m (12.1) of one bookkeeping.

    Attributes
    ----------
    name : str
        Bookkeeping: ``printed``, ``report``, ``circle``, ``computed``, ``stated`` or
        ``trajectory``.
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


def nominal_output(cfg: QppConfig, K1, Kc, H, T: float, n: int = 801):
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

    Returns
    -------
    tuple of arrays
        t (n,) in s, y_o (p, n) in output units, x_o (n_x, n) in state units.
    """
    P = cfg.lure_plant()
    f1, g_nom = config_f1(cfg, P)
    t = np.linspace(0.0, T, n)
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


def thresholds(cfg: QppConfig, t, y_o, x_o, sector, T: float | None = None) -> list[Thresholds]:
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
    T : float, optional
        Truncation time, s (default ``spheres.T``).

    Returns
    -------
    list of Thresholds
        One per bookkeeping available for this nonlinearity.
    """
    sp = cfg.spheres
    T = sp.T if T is None else T
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
            b3 = spheres.beta3_sinusoidal(k, nl.omega, T)
            b4 = spheres.beta4_sector(k, t, y_o, T)
            out.append(Thresholds(name, k, b3, b4, spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))
    elif isinstance(nl, ExpressionNonlinearity):
        M = cfg.expression_model()
        b3, b4 = M.beta3(T), M.beta4(t, y_o, T)
        k = float(np.max(np.abs(sector)))
        out.append(Thresholds("computed", k, b3, b4, spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))
        if nl.beta3 is not None or nl.beta4 is not None:
            s3 = b3 if nl.beta3 is None else nl.beta3
            s4 = b4 if nl.beta4 is None else nl.beta4
            out.append(Thresholds("stated", k, s3, s4, spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, s3, s4)))
    else:
        b3, b4 = _arm_betas(cfg, t, x_o, T)
        out.append(Thresholds("trajectory", np.nan, b3, b4,
                              spheres.threshold_m(sp.beta_o, sp.beta_ri, sp.d_inf, b3, b4)))
    return out


def pick_bookkeeping(cfg: QppConfig, names: list[str]) -> str:
    """The threshold the design iterates against: ``design.bookkeeping`` when available, else the
    stated values, else the last (most specific) bookkeeping.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        Validated config (units: s, rad/s, the plant's own units).
    names : list of str
        Bookkeepings available (:func:`thresholds`).

    Returns
    -------
    str
        The chosen bookkeeping.
    """
    if cfg.design.bookkeeping in names:
        return cfg.design.bookkeeping
    return "stated" if "stated" in names else names[-1]
