"""Nonlinear closed-loop simulation of a Lure plant with observer and servo-compensator.

State z = [x; x_c; x̂] (eq 10.7).  With f1 the plant nonlinearity and f1o its nominal value
(γ = nominal), the loop is (sign conventions of ``docs/ERRATA.md`` § QPP signs and :mod:`qpp.lure`):

    u   = K1 x̂ + Kc x_c − f1o                       (eq 10.6, "computed torque" in ch. 14)
    x'  = A x + B u + G d + B f1(x, y, γ, t)         (eqs 13.1, 14.2)
    x_c'= Ac x_c + Bc (r − y)                        (eq 10.2)
    x̂'  = A x̂ + B u + B f1o + L (y − C x̂),  L = −H  (eq 10.5)

The nominal output y_o is the same loop with r = r_o, γ = nominal and d = 0 (eq 10.29).  The
sphere check is ‖y − y_o‖∞ = max_i sup_t |y_i − y_oi| ≤ β_o (eq 10.35).  The nonlinear feedback
terms are evaluated at the true state x (the report's φ(x, M, t) in ch. 14 uses x).
"""
from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np
from scipy.integrate import solve_ivp

from common.errors import ConvergenceError
from qpp.config import (ExpressionNonlinearity, PolarArmNonlinearity, QppConfig, Scenario,
                        SinusoidalNonlinearity, Term)
from qpp.lure import LurePlant


def eval_terms(terms: list[Term], t: float) -> float:
    """Value of a sum of :class:`~qpp.config.Term` at time t (s).

    Parameters
    ----------
    terms : list of Term
        Sine, step and ramp terms of one channel.
    t : float
        Time, s.

    Returns
    -------
    float
        The sum, in the units of the channel's signal.
    """
    v = 0.0
    for tm in terms:
        if tm.kind == "sin":
            v += tm.amplitude * np.sin(tm.omega * t + tm.phase)
        elif tm.kind == "step":
            on = -np.inf if tm.t_on is None else tm.t_on
            off = np.inf if tm.t_off is None else tm.t_off
            v += tm.amplitude if on <= t < off else 0.0
        else:  # ramp
            on = 0.0 if tm.t_on is None else tm.t_on
            off = np.inf if tm.t_off is None else tm.t_off
            v += tm.amplitude * (min(max(t, on), off) - on)
    return v


def eval_signal(signal, t: float) -> np.ndarray:
    """Vector signal (one list of terms per channel) at time t.

    Parameters
    ----------
    signal : list of list of Term
        One list of terms per channel (empty or None: no channel).
    t : float
        Time, s.

    Returns
    -------
    (p,) ndarray
        The signal's value per channel, in the units of the channels.
    """
    return np.array([eval_terms(ch, t) for ch in signal]) if signal else np.zeros(0)


def make_f1(nl, plant: LurePlant, model=None):
    """Matched nonlinearity f1(x, t, γ) ∈ R^m (f = B f1) of the config's kind and the nominal γ.

    For ``kind: expression`` γ is the vector of parameter values and ``model`` the config's
    :meth:`~qpp.config.QppConfig.expression_model`.

    Parameters
    ----------
    nl : ExpressionNonlinearity or SinusoidalNonlinearity or PolarArmNonlinearity
        The config's nonlinearity section.
    plant : LurePlant
        The Lure plant and servo-compensator.
    model : object, optional
        The compiled expression model (``kind: expression`` only).

    Returns
    -------
    f1 : callable
        ``f1(x, t, γ)``, in the units of the config's u.
    gamma_nominal : float or ndarray
        The nominal γ (M for the polar arm, the parameter vector for expressions), in the
        config's units.

    Raises
    ------
    TypeError
        ``nl`` is of no known kind.
    """
    if isinstance(nl, ExpressionNonlinearity):
        C = plant.C

        def f1(x, t, g):
            return model.f1(C @ x, t, g)
        return f1, model.nom.copy()
    if isinstance(nl, SinusoidalNonlinearity):
        F0, F1, Fu = (np.asarray(getattr(nl, k), float) for k in ("F0", "F1", "F_unc"))
        C = plant.C

        def f1(x, t, g):
            y = C @ x
            return F0 @ y + (F1 + g * Fu) @ y * np.sin(nl.omega * t)
        return f1, 0.0
    if isinstance(nl, PolarArmNonlinearity):
        mu, J, a = nl.mu, nl.J1 + nl.J2, nl.a

        def f1(x, t, M):
            x1, _, x3, x4 = x
            R = mu * x1 + M * (x1 + a)
            I = J + mu * x1 ** 2 + M * (x1 + a) ** 2
            return np.array([R / (mu + M) * x4 ** 2, -2.0 * R * x3 * x4 / I])
        return f1, nl.M_nominal
    raise TypeError(f"unknown nonlinearity {type(nl).__name__}")


def initial_state(cfg: QppConfig, plant: LurePlant, K1, Kc) -> np.ndarray:
    """z(0) = [x0; x_c0; x̂0 = x0].

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    plant : LurePlant
        The Lure plant and servo-compensator.
    K1 : (m, n) array
        Observer-state gain (eq 10.6), in the units of the config's u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of the config's u per unit of x_c.

    Returns
    -------
    (2n+q,) ndarray
        z(0), in the config's units of x and x_c.
    """
    n, q = plant.n, plant.q
    x0 = np.zeros(n) if cfg.plant.x0 is None else np.asarray(cfg.plant.x0, float)
    if isinstance(cfg.plant.xc0, list):
        xc0 = np.asarray(cfg.plant.xc0, float)
    elif cfg.plant.xc0 == "equilibrium":
        xc0 = np.linalg.lstsq(np.atleast_2d(Kc), -np.atleast_2d(K1) @ x0, rcond=None)[0]
    else:
        xc0 = np.zeros(q)
    return np.concatenate([x0, xc0, x0])


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

    @property
    def passed(self) -> bool:
        """Whether ‖y − y_o‖∞ ≤ β_o (eq 10.35)."""
        return bool(self.error_inf <= self.beta_o)


def simulate_loop(plant: LurePlant, K1, Kc, H, f1, *, gamma: float, gamma_nominal: float, r_fun,
                  t_eval, z0, impulse_time=None, impulse=None, rtol=1e-8, atol=1e-10):
    """Integrate the nonlinear loop; returns (z samples (N_z, N), u samples (m, N)).

    A disturbance impulse I δ(t − t_i) is applied as the jump x(t_i⁺) = x(t_i⁻) + G I.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    K1 : (m, n) array
        Observer-state gain (eq 10.6), in the units of the config's u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of the config's u per unit of x_c.
    H : (n, p) array
        Observer gain, printed sign (L = −H), in the units of the config's x per unit of y and s.
    f1 : callable
        ``f1(x, t, γ)``, the matched nonlinearity (:func:`make_f1`), in the units of u.
    gamma : float or ndarray
        The uncertain parameter(s) of the run, in the config's units.
    gamma_nominal : float or ndarray
        The nominal parameter(s), used by the observer's f1o, in the config's units.
    r_fun : callable
        ``r_fun(t)``, the reference at time t (s), in the units of y.
    t_eval : (N,) array
        Sample times, s.
    z0 : (2n+q,) array
        Initial state z(0), in the units of x and x_c.
    impulse_time : float, optional
        Time of the disturbance impulse, s.
    impulse : (r,) array, optional
        Impulse I, in the units of d times s.
    rtol : float
        Relative tolerance of the integrator, dimensionless.
    atol : float
        Absolute tolerance of the integrator, in the units of z.

    Returns
    -------
    Z : (2n+q, N) ndarray
        Samples of z, in the units of x and x_c.
    U : (m, N) ndarray
        Samples of u, in the units of u.

    Raises
    ------
    ConvergenceError
        The integrator failed.
    """
    A, B, C, G, Ac, Bc = plant.A, plant.B, plant.C, plant.G, plant.Ac, plant.Bc
    K1, Kc, L = np.atleast_2d(K1), np.atleast_2d(Kc), -np.atleast_2d(H)
    n, q = plant.n, plant.q

    def control(z, t):
        x, xc, xh = z[:n], z[n:n + q], z[n + q:]
        f1o = f1(x, t, gamma_nominal)
        return K1 @ xh + Kc @ xc - f1o, f1o

    def rhs(t, z):
        x, xc, xh = z[:n], z[n:n + q], z[n + q:]
        y = C @ x
        u, f1o = control(z, t)
        dx = A @ x + B @ (u + f1(x, t, gamma))
        dxc = Ac @ xc + Bc @ (r_fun(t) - y)
        dxh = A @ xh + B @ (u + f1o) + L @ (y - C @ xh)
        return np.concatenate([dx, dxc, dxh])

    t_eval = np.asarray(t_eval, float)
    t0, tf = t_eval[0], t_eval[-1]
    segments = [(t0, tf)]
    if impulse_time is not None and t0 < impulse_time < tf:
        segments = [(t0, impulse_time), (impulse_time, tf)]
    elif impulse_time is not None and impulse_time <= t0:
        z0 = z0.copy()
        z0[:n] += G @ np.asarray(impulse, float)
    zs = []
    z = np.asarray(z0, float)
    for k, (ta, tb) in enumerate(segments):
        if k == 1:
            z = z.copy()
            z[:n] += G @ np.asarray(impulse, float)
        mask = (t_eval >= ta) & ((t_eval < tb) if k < len(segments) - 1 else (t_eval <= tb))
        te = np.concatenate([[ta], t_eval[mask], [tb]])
        max_step = (tf - t0) / 200
        sol = solve_ivp(rhs, (ta, tb), z, method="DOP853", t_eval=np.unique(te), rtol=rtol, atol=atol,
                        max_step=max_step)
        if not sol.success:
            raise ConvergenceError(f"simulation failed at t = {sol.t[-1]:.4g} s: {sol.message}")
        keep = np.isin(sol.t, t_eval[mask])
        zs.append(sol.y[:, keep])
        z = sol.y[:, -1]
    Z = np.hstack(zs)
    U = np.array([control(Z[:, i], t)[0] for i, t in enumerate(t_eval)]).T
    return Z, U


def config_f1(cfg: QppConfig, plant: LurePlant):
    """:func:`make_f1` of a config (compiles the expression model when needed).

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    plant : LurePlant
        The Lure plant and servo-compensator.

    Returns
    -------
    tuple
        ``(f1, gamma_nominal)`` as returned by :func:`make_f1`.
    """
    nl = cfg.nonlinearity
    return make_f1(nl, plant, cfg.expression_model() if isinstance(nl, ExpressionNonlinearity) else None)


def scenario_gamma(cfg: QppConfig, scenario: Scenario):
    """Value of the uncertain parameter(s) in a scenario: γ, M, or the parameter vector.

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    scenario : Scenario
        One scenario of the config.

    Returns
    -------
    float or ndarray
        γ, M or the parameter vector, in the config's units.
    """
    nl = cfg.nonlinearity
    if not isinstance(nl, ExpressionNonlinearity):
        return scenario.gamma
    vals = scenario.parameters or {}
    return np.array([vals.get(k, r.nominal_value) for k, r in nl.parameters.items()], float)


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
        nominal = simulate_loop(plant, K1, Kc, H, f1, gamma=g_nom, gamma_nominal=g_nom, r_fun=r_o_fun,
                                t_eval=t, z0=z0, rtol=sim.rtol, atol=sim.atol)
    Zo, Uo = nominal
    Z, U = simulate_loop(plant, K1, Kc, H, f1, gamma=gam, gamma_nominal=g_nom, r_fun=r_fun,
                         t_eval=t, z0=z0, impulse_time=scenario.impulse_time, impulse=scenario.impulse,
                         rtol=sim.rtol, atol=sim.atol)
    n = plant.n
    y, yo = plant.C @ Z[:n], plant.C @ Zo[:n]
    err = np.max(np.abs(y - yo), axis=1)
    R = np.array([r_fun(tt) for tt in t]).T
    Ro = np.array([r_o_fun(tt) for tt in t]).T
    pars = None
    if isinstance(cfg.nonlinearity, ExpressionNonlinearity):
        pars = dict(zip(cfg.nonlinearity.parameters, map(float, np.atleast_1d(gam))))
    g_scalar = float(np.atleast_1d(gam)[0]) if np.size(gam) else 0.0
    return SimResult(scenario.name, t, R, Ro, y, yo, U, Uo, Z[:n], Zo[:n], g_scalar,
                     float(err.max()), err, cfg.spheres.beta_o, pars)


def check_work(cfg: QppConfig, K1, Kc, H) -> float:
    """Refuse a simulation that would run for minutes (issue 13), before integrating.

    An explicit integrator needs a number of steps proportional to t_final × (the fastest rate
    of the loop): the largest |eigenvalue| of the linear closed loop (plant, servo-compensator,
    observer) plus the size of the nonlinearity's output feedback and the fastest signal
    frequency.  Work = that × (scenarios + 1) is bounded by the ``QPP_WORK`` limit
    (:mod:`common.limits`).  Returns the work estimate.

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

    Returns
    -------
    float
        The work estimate, dimensionless (integrator steps, up to a constant).

    Raises
    ------
    ConfigError
        The work exceeds the ``QPP_WORK`` limit.
    """
    from common.errors import ConfigError
    from common.limits import how_to_raise, limit

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
    work = sim.t_final * rate * (len(sim.scenarios) + 1)
    if not work <= limit("QPP_WORK"):
        raise ConfigError(f"simulation.t_final: {sim.t_final:g} s × the loop's fastest rate {rate:.4g} 1/s × "
                          f"{len(sim.scenarios) + 1} runs needs too many integrator steps (work {work:.3g}); "
                          f"shorten t_final, use fewer scenarios or slower gains ({how_to_raise('QPP_WORK')})")
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
    nominal = simulate_loop(plant, K1, Kc, H, f1, gamma=g_nom, gamma_nominal=g_nom,
                            r_fun=lambda tt: eval_signal(sim.r_o, tt), t_eval=t, z0=z0,
                            rtol=sim.rtol, atol=sim.atol)
    out = []
    for s in sim.scenarios:
        out.append(simulate_scenario(cfg, K1, Kc, H, s, nominal))
        if progress is not None:
            progress(len(out), len(sim.scenarios), s.name)
    return out
