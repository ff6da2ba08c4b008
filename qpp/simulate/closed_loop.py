"""Nonlinear closed-loop simulation of a Lure plant with observer and servo-compensator.

Each scenario runs the loop of eqs 10.2, 10.5–10.7 with its reference r = r_o + Δr, uncertain
parameter γ and disturbance impulse.  The nominal output y_o is the same loop with r = r_o,
γ = nominal and d = 0 (eq 10.29).  The sphere check is ‖y − y_o‖∞ = max_i sup_t |y_i − y_oi| ≤ β_o
(eq 10.35).  The nonlinear feedback terms are evaluated at the true state x (the report's
φ(x, M, t) in ch. 14 uses x); f1 comes from :mod:`qpp.model.matched_nonlinearity`; γ is the
scenario's (γ or M, or for an expression its parameter values, the nominal where it names none).

State z = [x; x_c; x̂] (eq 10.7).  With f1 the plant nonlinearity and f1o its nominal value
(γ = nominal), the loop is (sign conventions of ``docs/ERRATA.md`` § QPP signs and :mod:`qpp.model.lure`):
    u   = K1 x̂ + Kc x_c − f1o                       (eq 10.6, "computed torque" in ch. 14)
    x'  = A x + B u + G d + B f1(x, y, γ, t)         (eqs 13.1, 14.2)
    x_c'= Ac x_c + Bc (r − y)                        (eq 10.2)
    x̂'  = A x̂ + B u + B f1o + L (y − C x̂),  L = −H  (eq 10.5)

A disturbance impulse I δ(t − t_i) is the jump x(t_i⁺) = x(t_i⁻) + G I.

The reference r = r_o + Δr of each scenario and the nominal reference r_o (ch. 10.2, eqs 10.2, 10.29) are
one list of :class:`~qpp.io.config.Term` (sine, step, ramp) per channel (:func:`eval_signal`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from acmm_qpp.errors import ConfigError, ConvergenceError
from acmm_qpp.limits import how_to_raise, limit
from qpp import LIMITS
from qpp.io.config import ExpressionNonlinearity, QppConfig, Scenario, Term
from qpp.model.lure import LurePlant, closed_loop
from qpp.model.matched_nonlinearity import config_f1


def _terms_value(terms: list[Term], t: float) -> float:
    """Value of one channel's sum of sine, step and ramp terms at time t (s), in its units."""
    v = 0.0
    for tm in terms:
        off = np.inf if tm.t_off is None else tm.t_off
        if tm.kind == "sin":
            v += tm.amplitude * np.sin(tm.omega * t + tm.phase)
        elif tm.kind == "step":
            on = -np.inf if tm.t_on is None else tm.t_on
            v += tm.amplitude if on <= t < off else 0.0
        else:  # ramp
            on = 0.0 if tm.t_on is None else tm.t_on
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
    return np.array([_terms_value(ch, t) for ch in signal]) if signal else np.zeros(0)


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
    x0 = np.zeros(plant.n) if cfg.plant.x0 is None else np.asarray(cfg.plant.x0, float)
    if isinstance(cfg.plant.xc0, list):
        xc0 = np.asarray(cfg.plant.xc0, float)
    elif cfg.plant.xc0 == "equilibrium":
        xc0 = np.linalg.lstsq(np.atleast_2d(Kc), -np.atleast_2d(K1) @ x0, rcond=None)[0]
    else:
        xc0 = np.zeros(plant.q)
    return np.concatenate([x0, xc0, x0])


#: a scenario's loop whose state exceeds this many times the size of the nominal loop's (and of
#: z(0), and 1) has diverged (:func:`simulate_scenario`)
DIVERGED_FACTOR = 1e6


def _simulate_loop(plant: LurePlant, K1, Kc, H, f1, *, gamma: float, gamma_nominal: float, r_fun,
                  t_eval, z0, impulse_time=None, impulse=None, rtol=1e-8, atol=1e-10,
                  diverged_beyond: float | None = None, failed_beyond: float | None = None):
    """Integrate the nonlinear loop (state z = [x; x_c; x̂], the units of the config); returns
    (z samples (N_z, N), u samples (m, N)), NaN after a divergence.

    A disturbance impulse I δ(t − t_i) is applied as the jump x(t_i⁺) = x(t_i⁻) + G I.  With
    ``diverged_beyond`` a loop that diverges (‖z‖∞ beyond it, or beyond a thousandth of it and
    growing until the integrator cannot follow) is a result: the samples after that time are NaN.
    With only ``failed_beyond`` the loop is never stopped early (a stable loop is integrated as
    without it), but an integrator failure after ‖z‖∞ has passed a thousandth of it is that
    result too (the nominal loop of an unstable design); any other integrator failure raises
    ConvergenceError.  ``f1(x, t, γ)`` is the matched nonlinearity, ``r_fun(t)`` the reference.
    """
    control, rhs = _loop_functions(plant, K1, Kc, H, f1, gamma, gamma_nominal, r_fun)
    n, G = plant.n, plant.G
    t_eval = np.asarray(t_eval, float)
    t0, tf = t_eval[0], t_eval[-1]
    segments = [(t0, tf)]
    if impulse_time is not None and t0 < impulse_time < tf:
        segments = [(t0, impulse_time), (impulse_time, tf)]
    elif impulse_time is not None and impulse_time <= t0:
        z0 = z0.copy()
        z0[:n] += G @ np.asarray(impulse, float)
    Z = _integrate_segments(rhs, segments, np.asarray(z0, float), t_eval, n, G, impulse, rtol, atol,
                            diverged_beyond, failed_beyond)
    U = np.array([control(Z[:, i], t)[0] if np.all(np.isfinite(Z[:, i])) else np.full(plant.m, np.nan)
                  for i, t in enumerate(t_eval)]).T
    return Z, U


def _loop_functions(plant: LurePlant, K1, Kc, H, f1, gamma, gamma_nominal, r_fun):
    """The control law ``control(z, t) -> (u, f1o)`` and the right-hand side ``rhs(t, z)`` of the
    loop (eqs 10.2, 10.5, 10.6) for :func:`_simulate_loop`."""
    A, B, C, Ac, Bc = plant.A, plant.B, plant.C, plant.Ac, plant.Bc
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

    return control, rhs


def simulate_nominal(plant: LurePlant, K1, Kc, H, f1, gamma_nominal, r_o, t_eval, z0, rtol: float, atol: float):
    """The nominal loop (γ = γ_nominal, r = r_o, no disturbance) of :func:`_simulate_loop`, whose
    growth until the integrator fails is a divergence (``failed_beyond`` =
    :func:`_nominal_diverged_beyond`): the gains of an unstable design give a result, not an error.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    K1, Kc, H : arrays
        The gains (eqs 10.5–10.6), in the units of the config's u per unit of x and of x_c, and
        of x per unit of y and s.
    f1 : callable
        ``f1(x, t, γ)``, the matched nonlinearity, in the units of u.
    gamma_nominal : float or ndarray
        The nominal parameter(s), in the config's units.
    r_o : list of qpp.io.config.Term
        The nominal reference (config ``simulation.r_o``), output units.
    t_eval : (N,) array
        Sample times, s.
    z0 : (2n+q,) array
        Initial state z(0), in the units of x and x_c.
    rtol, atol : float
        Integrator tolerances (dimensionless; the units of z).

    Returns
    -------
    tuple of ndarray
        (Z, U) as :func:`_simulate_loop` returns them: z in the units of x and x_c, u in the
        units of u (NaN after a divergence).
    """
    t_eval = np.asarray(t_eval, float)
    return _simulate_loop(plant, K1, Kc, H, f1, gamma=gamma_nominal, gamma_nominal=gamma_nominal,
                         r_fun=lambda tt: eval_signal(r_o, tt), t_eval=t_eval, z0=z0, rtol=rtol, atol=atol,
                         failed_beyond=_nominal_diverged_beyond(r_o, t_eval, z0))


def _nominal_diverged_beyond(r_o, t: np.ndarray, z0: np.ndarray) -> float:
    """The ``failed_beyond`` of a nominal loop (:func:`simulate_nominal`): DIVERGED_FACTOR times the
    larger of 1, |z0| and |r_o| over the samples ``t`` (s), in the units of z."""
    step = max(1, t.size // 200)
    r_peak = max((float(np.max(np.abs(eval_signal(r_o, tt)), initial=0.0)) for tt in t[::step]), default=0.0)
    return DIVERGED_FACTOR * max(1.0, float(np.max(np.abs(z0), initial=0.0)), r_peak)


class _TooManyEvaluations(Exception):
    """Raised inside the integrator by :func:`_counted` (caught in :func:`_integrate_segments`)."""


def _counted(rhs):
    """``rhs`` refusing to be evaluated more than ``QPP_RHS_EVALS`` times (``qpp.LIMITS``): the
    static work bound (t_final × the loop's rates) cannot see a fast t inside an expression
    nonlinearity, e.g. sin(1e6·t), whose run never ended (a review)."""
    budget, count = limit("QPP_RHS_EVALS", LIMITS), [0]

    def counted(t, z):
        count[0] += 1
        if count[0] > budget:
            raise _TooManyEvaluations(t)
        return rhs(t, z)
    return counted


def _integrate_segments(rhs, segments, z, t_eval, n, G, impulse, rtol, atol, diverged_beyond=None,
                        failed_beyond=None):
    """Integrate ``rhs`` over ``segments`` (one, or two split at the impulse time, where
    x jumps by G I), sampled at ``t_eval`` (s); the samples of z, (2n+q, N).  With
    ``diverged_beyond`` or ``failed_beyond`` (see :func:`_simulate_loop`) the integration stops
    when the loop diverges, the later samples NaN."""
    t0, tf = t_eval[0], t_eval[-1]
    rhs = _counted(rhs)
    zs = []
    events = None
    if diverged_beyond is not None:
        def diverged(t, zz):
            return diverged_beyond - np.max(np.abs(zz))
        diverged.terminal = True
        events = diverged
    for k, (ta, tb) in enumerate(segments):
        if k == 1:
            z = z.copy()
            z[:n] += G @ np.asarray(impulse, float)
        mask = (t_eval >= ta) & ((t_eval < tb) if k < len(segments) - 1 else (t_eval <= tb))
        te = np.concatenate([[ta], t_eval[mask], [tb]])
        max_step = (tf - t0) / 200
        with np.errstate(all="ignore"):
            try:
                sol = solve_ivp(rhs, (ta, tb), z, method="DOP853", t_eval=np.unique(te), rtol=rtol, atol=atol,
                                max_step=max_step, events=events)
            except _TooManyEvaluations as exc:
                raise ConfigError(
                    f"simulation.t_final: the integration reached t = {float(exc.args[0]):.4g} s of {tf:g} s "
                    f"after {limit('QPP_RHS_EVALS', LIMITS):.3g} evaluations of the loop: something in it varies much "
                    "faster than its closed-loop rates (a t inside a nonlinearity's expression, e.g. "
                    "sin(1e6*t)?), or simulation.rtol / atol are very tight; shorten t_final, slow it down or "
                    f"loosen the tolerances ({how_to_raise('QPP_RHS_EVALS', LIMITS)})") from None
        # the largest finite |z| of the samples reached (a loop can leap from large to inf or NaN
        # within one step, past the event, and fail the integrator there)
        reached = np.abs(np.column_stack([z, sol.y]) if sol.y.size else z)
        peak = float(np.max(reached, initial=0.0, where=np.isfinite(reached)))
        beyond = diverged_beyond if diverged_beyond is not None else failed_beyond
        stopped = beyond is not None and (sol.status == 1 or (not sol.success and peak > 1e-3 * beyond))
        if not sol.success and not stopped:
            raise ConvergenceError(f"simulation failed at t = {sol.t[-1]:.4g} s: {sol.message}",
                                   hint="the loop is stiff or escapes: check the gains, or loosen "
                                        "simulation.rtol / simulation.atol")
        zs.append(sol.y[:, np.isin(sol.t, t_eval[mask])])
        if stopped:                 # diverged: the samples from here on are NaN
            done = np.hstack(zs)
            return np.hstack([done, np.full((done.shape[0], t_eval.size - done.shape[1]), np.nan)])
        z = sol.y[:, -1]
    return np.hstack(zs)


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
        ``(Z_o, U_o)`` of the nominal loop (:func:`_simulate_loop`); integrated when None.

    Returns
    -------
    SimResult
        The samples and the sphere check.
    """
    plant = cfg.lure_plant()
    sim = cfg.simulation
    f1, g_nom = config_f1(cfg, plant)
    nl, pars = cfg.nonlinearity, None
    if isinstance(nl, ExpressionNonlinearity):      # γ: the parameter vector, nominal where unnamed
        vals = scenario.parameters or {}
        gam = np.array([vals.get(k, r.nominal_value) for k, r in nl.parameters.items()], float)
        pars = dict(zip(nl.parameters, map(float, gam)))
    else:
        gam = scenario.gamma
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
        beyond = _nominal_diverged_beyond(sim.r_o, t, z0)
    Z, U = _simulate_loop(plant, K1, Kc, H, f1, gamma=gam, gamma_nominal=g_nom, r_fun=r_fun,
                         t_eval=t, z0=z0, impulse_time=scenario.impulse_time, impulse=scenario.impulse,
                         rtol=sim.rtol, atol=sim.atol, diverged_beyond=beyond)
    n = plant.n
    y, yo = plant.C @ Z[:n], plant.C @ Zo[:n]
    lost = ~(np.all(np.isfinite(Z), axis=0) & np.all(np.isfinite(Zo), axis=0))   # either loop
    diverged_at = float(t[np.argmax(lost)]) if lost.any() else None
    err = np.max(np.abs(y - yo), axis=1) if diverged_at is None else np.full(plant.p, np.inf)
    R = np.array([r_fun(tt) for tt in t]).T
    Ro = np.array([r_o_fun(tt) for tt in t]).T
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
    Acl = closed_loop(P, K1, Kc, H)[0]
    with np.errstate(all="ignore"):
        rate = float(np.max(np.abs(np.linalg.eigvals(Acl)))) if np.all(np.isfinite(Acl)) else math.inf
    nl = cfg.nonlinearity
    sim = cfg.simulation
    if hasattr(nl, "F0"):
        gain = sum(float(np.linalg.norm(np.asarray(getattr(nl, k), float), 2)) for k in ("F0", "F1"))
        gain += nl.gamma_max * float(np.linalg.norm(np.asarray(nl.F_unc, float), 2))
        rate += gain * float(np.linalg.norm(P.B, 2) * np.linalg.norm(P.C, 2)) + nl.omega
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
