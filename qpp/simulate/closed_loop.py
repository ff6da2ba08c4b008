"""Nonlinear closed-loop simulation of a Lure plant with observer and servo-compensator.

Each scenario runs the loop of eqs 10.2, 10.5–10.7 (integrated by :mod:`qpp.simulate.loop`, which states
it with the sign conventions of ``docs/ERRATA.md`` § QPP signs) with its reference r = r_o + Δr,
uncertain parameter γ and disturbance impulse.  The nominal output y_o is the same loop with
r = r_o, γ = nominal and d = 0 (eq 10.29).  The sphere check is
‖y − y_o‖∞ = max_i sup_t |y_i − y_oi| ≤ β_o (eq 10.35).  The nonlinear feedback terms are
evaluated at the true state x (the report's φ(x, M, t) in ch. 14 uses x).

The loop's inputs come from :func:`qpp.simulate.loop.eval_signal` (r, r_o) and :mod:`qpp.model.matched_nonlinearity`
(f1, γ); this module runs the scenarios and checks the sphere.
"""
from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np

from qpp.io.config import ExpressionNonlinearity, QppConfig, Scenario
from qpp.simulate.loop import DIVERGED_FACTOR, eval_signal, initial_state, nominal_diverged_beyond, simulate_loop, simulate_nominal
from qpp.model.matched_nonlinearity import config_f1, scenario_gamma
from acmm_qpp.errors import ConfigError
from acmm_qpp.limits import how_to_raise, limit
from qpp import LIMITS


@dataclass
class SimResult:
    """One scenario: samples of r, r_o, y, y_o, u and the sphere check.

    Attributes
    ----------
    name : str
        Scenario name.
    t : (N,) ndarray
        Sample times, s.
    r : (p, N) ndarray
        Reference, in the config's units of y.
    r_o : (p, N) ndarray
        Nominal reference, in the config's units of y.
    y : (p, N) ndarray
        Output, in the config's units of y.
    y_o : (p, N) ndarray
        Nominal output, in the config's units of y.
    u : (m, N) ndarray
        Control including −f1o, in the config's units of u.
    u_o : (m, N) ndarray
        Nominal control, in the config's units of u.
    x : (n, N) ndarray
        Plant state, in the config's units of x.
    x_o : (n, N) ndarray
        Nominal plant state, in the config's units of x.
    gamma : float
        γ / payload; expression kind: first parameter value (all in ``parameters``), in the
        config's units.
    error_inf : float
        ‖y − y_o‖∞, in the config's units of y.
    error_per_output : (p,) ndarray
        sup_t |y_i − y_oi| per output, in the config's units of y.
    beta_o : float
        Sphere radius β_o (eq 10.35), in the config's units of y.
    parameters : dict or None
        Expression kind: parameter values of the scenario.
    diverged_at : float or None
        Time the loop diverged (its samples after it are NaN, ``error_inf`` is inf), s; None
        when it did not.
    """

    name: str
    t: np.ndarray
    r: np.ndarray       #: (p, N)
    r_o: np.ndarray     #: (p, N)
    y: np.ndarray       #: (p, N)
    y_o: np.ndarray     #: (p, N)
    u: np.ndarray       #: (m, N) control including −f1o
    u_o: np.ndarray     #: (m, N) nominal control
    x: np.ndarray       #: (n, N) plant state
    x_o: np.ndarray     #: (n, N) nominal plant state
    gamma: float        #: γ / payload; expression kind: first parameter value (all in ``parameters``)
    error_inf: float    #: ‖y − y_o‖∞
    error_per_output: np.ndarray
    beta_o: float
    parameters: dict = None   #: expression kind: parameter values of the scenario
    diverged_at: float | None = None   #: time the loop diverged, s (None: it did not)

    @property
    def passed(self) -> bool:
        """Whether ‖y − y_o‖∞ ≤ β_o (eq 10.35)."""
        return bool(self.error_inf <= self.beta_o)

    def broken_premises(self, beta_ri: float, y_range=None) -> list[str]:
        """The premises of the certificate this run breaks: ‖r − r_o‖∞ ≤ β_ri (eq 10.52) and, for
        an expression nonlinearity, y within ``y_range`` (where its sector holds).  A run that
        breaks one is outside what the certificate speaks about, whatever its error.

        Parameters
        ----------
        beta_ri : float
            Reference sphere radius, output units.
        y_range : list of [lo, hi] or None
            The outputs' range of the sector, output units; None: not checked.

        Returns
        -------
        list of str
            One phrase per broken premise (empty: none).
        """
        out = []
        dr = float(np.nanmax(np.abs(np.asarray(self.r) - np.asarray(self.r_o)))) if np.size(self.r) else 0.0
        if dr > beta_ri * (1 + 1e-9) + 1e-15:
            out.append(f"||r - r_o||inf = {dr:.4g} > beta_ri = {beta_ri:g}")
        if y_range is not None:
            y = np.asarray(self.y, float)
            for i, (lo, hi) in enumerate(y_range):
                yi = y[i][np.isfinite(y[i])]
                if yi.size and (yi.min() < lo or yi.max() > hi):
                    out.append(f"y{i + 1} leaves y_range [{lo:g}, {hi:g}] (reaches "
                               f"{yi.min() if yi.min() < lo else yi.max():.4g})")
        return out


def simulate_scenario(cfg: QppConfig, K1, Kc, H, scenario: Scenario, nominal=None) -> SimResult:
    """Run one scenario and its nominal loop; compare ‖y − y_o‖∞ with β_o.

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    K1 : (m, n) array
        Observer-state gain (eq 10.6), in the units of the config's u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of the config's u per unit of x_c.
    H : (n, p) array
        Observer gain, printed sign (L = −H), in the units of the config's x per unit of y and s.
    scenario : Scenario
        The scenario to run.
    nominal : tuple, optional
        ``(Z_o, U_o)`` of the nominal loop (:func:`simulate_loop`); integrated when None.

    Returns
    -------
    SimResult
        The samples and the sphere check.
    """
    plant = cfg.lure_plant()
    sim = cfg.simulation
    f1, g_nom = config_f1(cfg, plant)
    gam = scenario_gamma(cfg, scenario)
    t = np.linspace(0.0, sim.t_final, sim.n_samples)
    z0 = initial_state(cfg, plant, K1, Kc)
    r_o_fun = lambda tt: eval_signal(sim.r_o, tt)  # noqa: E731
    if scenario.delta_r is None:
        r_fun = r_o_fun
    else:
        r_fun = lambda tt: r_o_fun(tt) + eval_signal(scenario.delta_r, tt)  # noqa: E731
    if nominal is None:
        nominal = simulate_nominal(plant, K1, Kc, H, f1, g_nom, sim.r_o, t, z0, sim.rtol, sim.atol)
    Zo, Uo = nominal
    if np.all(np.isfinite(Zo)):        # diverged: DIVERGED_FACTOR × the nominal loop's size
        beyond = DIVERGED_FACTOR * max(1.0, float(np.max(np.abs(z0))), float(np.max(np.abs(Zo))))
    else:                              # the nominal loop itself diverged (an unstable design)
        beyond = nominal_diverged_beyond(sim.r_o, t, z0)
    Z, U = simulate_loop(plant, K1, Kc, H, f1, gamma=gam, gamma_nominal=g_nom, r_fun=r_fun,
                         t_eval=t, z0=z0, impulse_time=scenario.impulse_time, impulse=scenario.impulse,
                         rtol=sim.rtol, atol=sim.atol, diverged_beyond=beyond)
    n = plant.n
    y, yo = plant.C @ Z[:n], plant.C @ Zo[:n]
    lost = ~(np.all(np.isfinite(Z), axis=0) & np.all(np.isfinite(Zo), axis=0))   # either loop
    diverged_at = float(t[np.argmax(lost)]) if lost.any() else None
    err = np.max(np.abs(y - yo), axis=1) if diverged_at is None else np.full(plant.p, np.inf)
    R = np.array([r_fun(tt) for tt in t]).T
    Ro = np.array([r_o_fun(tt) for tt in t]).T
    pars = None
    if isinstance(cfg.nonlinearity, ExpressionNonlinearity):
        pars = dict(zip(cfg.nonlinearity.parameters, map(float, np.atleast_1d(gam))))
    g_scalar = float(np.atleast_1d(gam)[0]) if np.size(gam) else 0.0
    return SimResult(scenario.name, t, R, Ro, y, yo, U, Uo, Z[:n], Zo[:n], g_scalar,
                     float(err.max()), err, cfg.spheres.beta_o, pars, diverged_at)


def check_work(cfg: QppConfig, K1, Kc, H, runs: int | None = None, horizon: float | None = None) -> float:
    """Refuse a simulation that would run for minutes (issue 13), before integrating.

    An explicit integrator needs a number of steps proportional to t_final × (the fastest rate
    of the loop): the largest |eigenvalue| of the linear closed loop (plant, servo-compensator,
    observer) plus the size of the nonlinearity's output feedback and the fastest signal
    frequency.  Work = that × (scenarios + 1) is bounded by the ``QPP_WORK`` limit
    (``qpp.LIMITS``).  Returns the work estimate.

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    K1 : (m, n) array
        Observer-state gain (eq 10.6), in the units of the config's u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of the config's u per unit of x_c.
    H : (n, p) array
        Observer gain, printed sign (L = −H), in the units of the config's x per unit of y and s.
    runs : int, optional
        Loops integrated (default: the scenarios + the nominal loop).
    horizon : float, optional
        Time integrated, s (default ``simulation.t_final``).

    Returns
    -------
    float
        The work estimate, dimensionless (integrator steps, up to a constant).

    Raises
    ------
    ConfigError
        The work exceeds the ``QPP_WORK`` limit.
    """
    P = cfg.lure_plant()
    A, B, C, Ac, Bc = (np.atleast_2d(np.asarray(x, float)) for x in (P.A, P.B, P.C, P.Ac, P.Bc))
    K1, Kc, L = np.atleast_2d(K1), np.atleast_2d(Kc), -np.atleast_2d(H)
    n, q = P.n, P.q
    Acl = np.block([[A, B @ Kc, B @ K1], [-Bc @ C, Ac, np.zeros((q, n))], [L @ C, B @ Kc, A + B @ K1 - L @ C]])
    with np.errstate(all="ignore"):
        rate = float(np.max(np.abs(np.linalg.eigvals(Acl)))) if np.all(np.isfinite(Acl)) else math.inf
    nl = cfg.nonlinearity
    sim = cfg.simulation
    if hasattr(nl, "F0"):
        gain = sum(float(np.linalg.norm(np.asarray(getattr(nl, k), float), 2)) for k in ("F0", "F1"))
        gain += nl.gamma_max * float(np.linalg.norm(np.asarray(nl.F_unc, float), 2))
        rate += gain * float(np.linalg.norm(B, 2) * np.linalg.norm(C, 2)) + nl.omega
    omegas = [t.omega for sig in [sim.r_o] + [s.delta_r or [] for s in sim.scenarios] for ch in sig for t in ch]
    rate = max([rate] + omegas)
    runs = len(sim.scenarios) + 1 if runs is None else int(runs)
    horizon = sim.t_final if horizon is None else float(horizon)
    work = horizon * rate * runs
    if not work <= limit("QPP_WORK", LIMITS):
        raise ConfigError(f"simulation.t_final: {horizon:g} s × the loop's fastest rate {rate:.4g} 1/s × "
                          f"{runs} run(s) needs too many integrator steps (work {work:.3g}); "
                          f"shorten t_final, use fewer scenarios or slower gains ({how_to_raise('QPP_WORK', LIMITS)})")
    return work


def simulate(cfg: QppConfig, K1, Kc, H, progress=None) -> list[SimResult]:
    """All scenarios of a config (the nominal loop is integrated once); ``progress(done, total,
    name)`` is called after each scenario.

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    K1 : (m, n) array
        Observer-state gain (eq 10.6), in the units of the config's u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of the config's u per unit of x_c.
    H : (n, p) array
        Observer gain, printed sign (L = −H), in the units of the config's x per unit of y and s.
    progress : callable, optional
        ``progress(done, total, name)``, called after each scenario.

    Returns
    -------
    list of SimResult
        One result per scenario, in the config's order.
    """
    check_work(cfg, K1, Kc, H)
    plant = cfg.lure_plant()
    sim = cfg.simulation
    t = np.linspace(0.0, sim.t_final, sim.n_samples)
    z0 = initial_state(cfg, plant, K1, Kc)
    f1, g_nom = config_f1(cfg, plant)
    nominal = simulate_nominal(plant, K1, Kc, H, f1, g_nom, sim.r_o, t, z0, sim.rtol, sim.atol)
    out = []
    for s in sim.scenarios:
        out.append(simulate_scenario(cfg, K1, Kc, H, s, nominal))
        if progress is not None:
            progress(len(out), len(sim.scenarios), s.name)
    return out
