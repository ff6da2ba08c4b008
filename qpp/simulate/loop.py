"""Integration of the nonlinear closed loop of plant, servo-compensator and observer.

State z = [x; x_c; x̂] (eq 10.7).  With f1 the plant nonlinearity and f1o its nominal value
(γ = nominal), the loop is (sign conventions of ``docs/ERRATA.md`` § QPP signs and :mod:`qpp.model.lure`):
    u   = K1 x̂ + Kc x_c − f1o                       (eq 10.6, "computed torque" in ch. 14)
    x'  = A x + B u + G d + B f1(x, y, γ, t)         (eqs 13.1, 14.2)
    x_c'= Ac x_c + Bc (r − y)                        (eq 10.2)
    x̂'  = A x̂ + B u + B f1o + L (y − C x̂),  L = −H  (eq 10.5)

A disturbance impulse I δ(t − t_i) is the jump x(t_i⁺) = x(t_i⁻) + G I.

The reference r = r_o + Δr of each scenario and the nominal reference r_o (eqs 10.2, 10.29) are
one list of :class:`~qpp.io.config.Term` (sine, step, ramp) per channel (:func:`eval_signal`).
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from acmm_qpp.errors import ConfigError, ConvergenceError
from qpp.io.config import QppConfig, Term
from qpp.model.lure import LurePlant
from acmm_qpp.limits import how_to_raise, limit
from qpp import LIMITS


def _terms_value(terms: list[Term], t: float) -> float:
    """Value of one channel's sum of sine, step and ramp terms at time t (s), in its units."""
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
    n, q = plant.n, plant.q
    x0 = np.zeros(n) if cfg.plant.x0 is None else np.asarray(cfg.plant.x0, float)
    if isinstance(cfg.plant.xc0, list):
        xc0 = np.asarray(cfg.plant.xc0, float)
    elif cfg.plant.xc0 == "equilibrium":
        xc0 = np.linalg.lstsq(np.atleast_2d(Kc), -np.atleast_2d(K1) @ x0, rcond=None)[0]
    else:
        xc0 = np.zeros(q)
    return np.concatenate([x0, xc0, x0])


#: a scenario's loop whose state exceeds this many times the size of the nominal loop's (and of
#: z(0), and 1) has diverged (:func:`qpp.simulate.closed_loop.simulate_scenario`)
DIVERGED_FACTOR = 1e6


def simulate_loop(plant: LurePlant, K1, Kc, H, f1, *, gamma: float, gamma_nominal: float, r_fun,
                  t_eval, z0, impulse_time=None, impulse=None, rtol=1e-8, atol=1e-10,
                  diverged_beyond: float | None = None, failed_beyond: float | None = None):
    """Integrate the nonlinear loop; returns (z samples (N_z, N), u samples (m, N)).

    A disturbance impulse I δ(t − t_i) is applied as the jump x(t_i⁺) = x(t_i⁻) + G I.  With
    ``diverged_beyond`` a loop that diverges (‖z‖∞ beyond it, or beyond a thousandth of it and
    growing until the integrator cannot follow) is a result: the samples after that time are NaN.
    With only ``failed_beyond`` the loop is never stopped early (a stable loop is integrated as
    without it), but an integrator failure after ‖z‖∞ has passed a thousandth of it is that
    result too (the nominal loop of an unstable design).

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
        ``f1(x, t, γ)``, the matched nonlinearity (:func:`qpp.model.matched_nonlinearity.make_f1`), in the units of u.
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
    diverged_beyond : float, optional
        ‖z‖∞ of a diverged loop, in the units of z (None: a failing integration is an error).
    failed_beyond : float, optional
        Without ``diverged_beyond``: ‖z‖∞ (units of z) a thousandth of which, passed before the
        integrator fails, makes the failure a divergence.

    Returns
    -------
    Z : (2n+q, N) ndarray
        Samples of z, in the units of x and x_c (NaN after a divergence).
    U : (m, N) ndarray
        Samples of u, in the units of u (NaN after a divergence).

    Raises
    ------
    ConvergenceError
        The integrator failed (on a loop that had not diverged).
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
    loop (eqs 10.2, 10.5, 10.6) for :func:`simulate_loop`."""
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
    """The nominal loop (γ = γ_nominal, r = r_o, no disturbance) of :func:`simulate_loop`, whose
    growth until the integrator fails is a divergence (``failed_beyond`` =
    :func:`nominal_diverged_beyond`): the gains of an unstable design give a result, not an error.

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
        (Z, U) as :func:`simulate_loop` returns them: z in the units of x and x_c, u in the
        units of u (NaN after a divergence).
    """
    t_eval = np.asarray(t_eval, float)
    return simulate_loop(plant, K1, Kc, H, f1, gamma=gamma_nominal, gamma_nominal=gamma_nominal,
                         r_fun=lambda tt: eval_signal(r_o, tt), t_eval=t_eval, z0=z0, rtol=rtol, atol=atol,
                         failed_beyond=nominal_diverged_beyond(r_o, t_eval, z0))


def nominal_diverged_beyond(r_o, t: np.ndarray, z0: np.ndarray) -> float:
    """The ``failed_beyond`` of a nominal loop (:func:`simulate_loop`): :data:`DIVERGED_FACTOR`
    times the larger of 1, the initial state and the reference r_o over the samples ``t``, all in
    the config's units.  The nominal loop of an unstable design, which grows until the integrator
    fails, is then a result (its samples NaN from there on), not an integrator error; a stable
    one is integrated as before.

    Parameters
    ----------
    r_o : list of qpp.io.config.Term
        The nominal reference r_o(t) (config ``simulation.r_o``), output units.
    t : (N,) array
        Sample times, s.
    z0 : array
        Initial loop state, the units of z.

    Returns
    -------
    float
        The threshold, the units of z.
    """
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
    ``diverged_beyond`` or ``failed_beyond`` (see :func:`simulate_loop`) the integration stops
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
        keep = np.isin(sol.t, t_eval[mask])
        got = sol.y[:, keep]
        zs.append(got)
        if stopped:                 # diverged: the samples from here on are NaN
            done = np.hstack(zs)
            return np.hstack([done, np.full((done.shape[0], t_eval.size - done.shape[1]), np.nan)])
        z = sol.y[:, -1]
    return np.hstack(zs)
