"""The closed-loop refit of a polynomial gain schedule (CR-185644 ch. 5.3; docs/results/design.md, "The gain schedule").

:func:`refit_closed_loop` moves the least-squares coefficients to push the least damped
closed-loop pole along the whole path to the left (smooth maximum by L-BFGS or its epigraph form
by SLSQP).  Split from :mod:`acmm.design.schedule`.

The objective is the smooth maximum ::
    f(c) = (1/β) log Σ_{j,i} exp(β Re λ_i(A_j − B_j K(θ_j; c)) / n)

over the chosen TEAs θ_j; with ``angle_weight`` w > 0 the terms
w·((|Im λ| cos φ + Re λ sin φ)/n − ``angle_offset``) of the sector's φ lines join the max, so
strongly oscillatory poles (which carry the smallest disk margins) are pulled back too;
``re_weight``/``re_offset`` scale and shift the Re λ terms.

Gradient: first-order eigenvalue perturbation ∂λ_i/∂K_ab = −(w_i^H B)_a v_ib (W V = I), chained
through K = Σ c_k u^k; L-BFGS-B (scipy) on the coefficients relative to the least-squares ones,
in the normalized variable u = (θ2* − c)/h ∈ [−1, 1], mapped back to powers of θ2*.  The form
stays the report's: one polynomial of the fit's order per gain element.

``solver="slsqp"`` minimizes the same quantity in its exact (β → ∞) epigraph form, min t subject
to v ≤ t for the ``top`` largest Re λ terms and the ``top`` largest φ-line terms per TEA (poles
with Im λ ≥ 0, each conjugate pair once), by SLSQP with the same analytic eigenvalue gradients;
it reaches a lower worst Re λ in ~10× fewer eigenvalue evaluations than L-BFGS on the smooth
maximum (docs/results/design.md, "The gain schedule").

``solver="trust_lp"`` (``schedule.fit: minimax``, :data:`MINIMAX_DEFAULTS`) minimizes the largest
Re λ itself on every path TEA by a trust-region sequential linear program: at the coefficients x
every eigenvalue (Im λ ≥ 0) of every TEA within ``band`` of the largest is replaced by its
first-order model, the linear program ::

    min s   subject to   Re λ_i(x)/n + ∇Re λ_i(x)/n · d ≤ s,   |d|∞ ≤ Δ

(HiGHS, scipy) gives the step d, and the step is taken only if the true largest Re λ falls by at
least a tenth of the predicted fall (Δ doubled when the ratio exceeds 3/4, halved when a step is
refused).  The largest Re λ therefore never rises (a monotone method), and the search stops on a
stated tolerance: the trust radius below :data:`RADIUS_TOL` (no step of that relative size lowers
the worst pole: converged), the model predicting no fall, or the last :data:`STALL_WINDOW`
accepted steps together lowering it by less than :data:`STALL_TOL` n (stalled; reported).
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from scipy.optimize import linprog

from acmm.design.path_check import PathModels
from acmm.design.schedule import ScheduleFit
from math import comb
from scipy.optimize import minimize


def power_basis(a: np.ndarray, c: float, h: float) -> np.ndarray:
    """Coefficients in powers of θ of Σ_k a[k]·((θ − c)/h)^k.

    Parameters
    ----------
    a : (order+1, ...) array
        Coefficients in the normalized variable u = (θ − c)/h, lowest power first, units of
        the polynomial's value.
    c : float
        Centre of the normalization, rad.
    h : float
        Half-width of the normalization, rad.

    Returns
    -------
    (order+1, ...) array
        The same polynomials' coefficients in powers of θ, units of ``a`` per rad^k.
    """
    order = a.shape[0] - 1
    b = np.zeros_like(a)
    for k in range(order + 1):
        for j in range(k + 1):       # ((θ − c)/h)^k = Σ_j C(k,j) θ^j (−c)^(k−j) / h^k
            b[j] = b[j] + a[k] * comb(k, j) * (-c) ** (k - j) / h ** k
    return b


#: Parameters of the closed-loop refit used by the design stage (``schedule.fit: closed_loop``):
#: the max of Re λ/n and of 0.7·(distance beyond the φ lines/n − 2.2) — the angle term only bites
#: on strongly oscillatory poles and keeps the disk margin up — on every 10th of the path TEAs
#: (21 of 201), in epigraph form (the 4 largest terms of each kind per TEA) by SLSQP run until its
#: own convergence test (``ftol`` :data:`REFIT_FTOL` on the worst term) or until it can no longer
#: make progress; ``max_iter`` is a guard on the work, not the stopping rule.  The problem is a
#: non-convex, non-smooth minimax: where SLSQP stops depends on rounding (docs/results/design.md, "The gain
#: schedule"), which is why the packaged stair-case uses ``form: table``.
REFIT_DEFAULTS = {"every": 10, "beta": 20.0, "max_iter": 2000, "angle_weight": 0.7, "angle_offset": 2.2,
                  "solver": "slsqp", "top": 4}

#: SLSQP's convergence tolerance on the worst term of the refit (units of n).
REFIT_FTOL = 1e-9

#: Parameters of the minimax refit (``schedule.fit: minimax``): the largest Re λ alone on every
#: path TEA, by the trust-region linear program of the module docstring, modelling every
#: eigenvalue within ``band`` (units of n) of the largest.
MINIMAX_DEFAULTS = {"every": 1, "solver": "trust_lp", "angle_weight": 0.0, "band": 0.05,
                    "max_iter": 5000}

#: The refits a ``schedule.fit`` string names (the choice made once, in
#: :func:`acmm.design.design_core.design_schedule`).
REFITS = {"closed_loop": REFIT_DEFAULTS, "minimax": MINIMAX_DEFAULTS}

#: Trust-region linear program: the trust radius at which it stops as converged (relative change
#: of each coefficient, dimensionless).
RADIUS_TOL = 1e-7

#: Trust-region linear program: the first trust radius (relative change of each coefficient).
RADIUS_START = 0.5

#: Trust-region linear program: it stops as stalled when the last STALL_WINDOW accepted steps
#: together lowered the largest Re λ by less than STALL_TOL (units of n).
STALL_WINDOW = 50
STALL_TOL = 1e-3


def refit_closed_loop(fit: ScheduleFit, path: PathModels, n: float, *, every: int = 5,
                      beta: float = 20.0, max_iter: int = 60, angle_weight: float = 0.0,
                      half_angle_deg: float = 45.0, re_weight: float = 1.0,
                      re_offset: float = 0.0, angle_offset: float = 0.0, solver: str = "lbfgs",
                      top: int = 3, band: float = 0.05) -> ScheduleFit:
    """Refine a least-squares polynomial schedule against the closed loop along the path.

    The coefficients are moved to minimize the smooth maximum f(c) of the module docstring over
    every ``every``-th TEA of ``path`` (the ends included), pushing the least damped closed-loop
    pole along the whole path to the left.  The result is accepted only if it lowers the
    largest Re λ on those TEAs; it is re-checked on every TEA by
    :func:`acmm.design.path_check.check_path`.

    Parameters
    ----------
    fit : acmm.design.schedule.ScheduleFit
        The least-squares polynomial schedule to refine.
    path : acmm.design.path_check.PathModels
        Local models along the path.
    n : float
        Orbital rate, rad/s.
    every : int
        Use every ``every``-th TEA of ``path`` (the ends included).
    beta : float
        Sharpness β of the smooth maximum (L-BFGS), dimensionless.
    max_iter : int
        Guard on the optimizer iterations (the optimizer stops on its own convergence test first
        on the packaged configs; ``refit_info["converged"]`` says whether it did).
    angle_weight : float
        Weight w of the φ-line terms, dimensionless (0: Re λ terms only).
    half_angle_deg : float
        Sector half-angle φ, deg.
    re_weight : float
        Weight of the Re λ terms, dimensionless.
    re_offset : float
        Shift of the Re λ terms, units of n.
    angle_offset : float
        Shift of the φ-line terms, units of n.
    solver : {"lbfgs", "slsqp", "trust_lp"}
        Smooth maximum by L-BFGS-B, the epigraph form by SLSQP, or the largest Re λ by the
        trust-region linear program (module docstring; Re λ terms only: ``angle_weight`` must be 0).
    top : int
        ``solver="slsqp"``: number of largest terms of each kind per TEA.
    band : float
        ``solver="trust_lp"``: eigenvalues within ``band`` of the largest Re λ are modelled, units of n.

    Returns
    -------
    acmm.design.schedule.ScheduleFit
        The refitted schedule (``method="closed_loop"``, or ``"minimax"`` for ``solver="trust_lp"``),
        or the least-squares one when the refit does not lower the largest Re λ; ``refit_info``
        records the outcome.

    Raises
    ------
    ValueError
        ``fit`` is not a polynomial schedule, or ``solver`` is unknown.
    """
    if fit.form != "polynomial":
        raise ValueError("refit_closed_loop refines a polynomial schedule")
    st = refit_start(fit, path, every)
    a0, sc, up, shape = st["a0"], st["sc"], st["up"], st["shape"]
    As_t, Bs_t = np.array(st["As"]), np.array(st["Bs"])              # (T, N, N), (T, N, M)
    x0 = np.zeros(a0.size)
    w0 = worst_real(st, x0, n)
    if solver == "slsqp":
        res = _minimax_slsqp(a0, sc, up, As_t, Bs_t, n, max_iter, top, re_weight, re_offset,
                             angle_weight, angle_offset, half_angle_deg)
    elif solver == "trust_lp":
        if angle_weight or re_weight != 1.0 or re_offset:
            raise ValueError("the trust-region refit minimizes the largest Re λ alone (angle_weight 0, "
                             "re_weight 1, re_offset 0)")
        res = _minimax_trust_lp(a0, sc, up, As_t, Bs_t, n, band, max_iter)
        return _refit_outcome(fit, st, res, w0, worst_real(st, res.x, n), beta, "minimax")
    elif solver == "lbfgs":
        fg = _smooth_max(a0, sc, shape, up, As_t, Bs_t, n, beta, re_weight, re_offset, angle_weight,
                         angle_offset, half_angle_deg)
        res = minimize(fg, x0, jac=True, method="L-BFGS-B", options={"maxiter": max_iter, "ftol": 1e-12,
                                                                      "gtol": 1e-9})
    else:
        raise ValueError(f"unknown refit solver {solver!r}")
    return _refit_outcome(fit, st, res, w0, worst_real(st, res.x, n), beta)


def _refit_outcome(fit: ScheduleFit, st: dict, res, w0: float, w1: float, beta: float,
                   method: str = "closed_loop") -> ScheduleFit:
    """The refitted schedule (``method``) when the optimizer's result ``res`` lowers the largest
    Re λ / n (``w0`` → ``w1``), else ``fit`` again; ``refit_info`` records the outcome either way."""
    info = {"beta": beta, "iterations": int(res.nit), "evaluations": int(res.nfev),
            "converged": bool(res.status == 0), "message": str(res.message),
            "n_tea": len(st["idx"]), "max_real_before": float(w0), "max_real_after": float(w1),
            "accepted": bool(w1 < w0)}
    if not w1 < w0:
        return ScheduleFit(fit.coef, fit.variable, fit.gains, fit.rms_residual, fit.rel_residual,
                           fit.form, "least_squares", info)
    a = st["a0"] + res.x.reshape(st["shape"]) * st["sc"]
    return refitted(fit, power_basis(a, st["c0"], st["h0"]) / st["d"][None, None, :], info, method)


def worst_real(st: dict, x: np.ndarray, n: float) -> float:
    """Largest Re λ / n of the scheduled loop over the refit's TEAs.

    Parameters
    ----------
    st : dict
        The refit's TEAs, models and starting coefficients (:func:`refit_start`).
    x : array
        Change of the coefficients from ``st["a0"]``, in units of ``st["sc"]``.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    float
        The largest real part of a closed-loop pole, units of n.
    """
    a = st["a0"] + x.reshape(st["shape"]) * st["sc"]
    return max(np.max(np.linalg.eigvals(A - B @ np.tensordot(tp, a, axes=1)).real)
               for A, B, tp in zip(st["As"], st["Bs"], st["up"])) / n


def refit_start(fit: ScheduleFit, path: PathModels, every: int) -> dict:
    """The TEAs, models and starting coefficients of a refit of ``fit`` on ``path``.

    Parameters
    ----------
    fit : acmm.design.schedule.ScheduleFit
        The polynomial schedule the refit starts from.
    path : acmm.design.path_check.PathModels
        Local models along the path.
    every : int
        Use every ``every``-th TEA of ``path`` (the ends included).

    Returns
    -------
    dict
        ``idx`` (the TEAs' indices), ``c0``, ``h0`` (the normalized variable u = (θ2* − c0)/h0,
        rad), ``d`` (the state scaling), ``As``, ``Bs`` (the scaled models), ``up`` (powers of u
        at each TEA), ``shape``, ``a0`` (the starting coefficients in u, scaled gains) and ``sc``
        (their scale: the largest |a0| of each element).
    """
    idx = sorted(set(range(0, path.theta2.size, max(1, every))) | {path.theta2.size - 1})
    th = path.theta2[idx]
    c0, h0 = 0.5 * (th.max() + th.min()), 0.5 * (th.max() - th.min())
    d = path.scales
    As = [path.A[j] / d[:, None] * d[None, :] for j in idx]
    Bs = [path.B[j] / d[:, None] for j in idx]
    order = fit.order
    u = (th - c0) / h0
    up = u[:, None] ** np.arange(order + 1)[None, :]                     # (T, order+1)
    # the starting coefficients (fit.coef, powers of θ) in u, scaled gains: sample and refit
    shape = (order + 1,) + fit.gains.shape[1:]
    us = np.linspace(-1.0, 1.0, order + 1)
    ks = np.array([fit.gain(c0 + h0 * x) * d[None, :] for x in us]).reshape(order + 1, -1)
    a0 = np.linalg.solve(us[:, None] ** np.arange(order + 1)[None, :], ks).reshape(shape)
    sc = np.broadcast_to(np.maximum(np.abs(a0).max(axis=0, keepdims=True), 1e-12), shape)
    return {"idx": idx, "c0": c0, "h0": h0, "d": d, "As": As, "Bs": Bs, "up": up, "shape": shape,
            "a0": a0, "sc": sc}


def _smooth_max(a0, sc, shape, up, As_t, Bs_t, n, beta, re_weight, re_offset, angle_weight,
                angle_offset, half_angle_deg):
    """The smooth maximum f(x) of :func:`refit_closed_loop` and its gradient, as one function
    of the scaled coefficient change x (for L-BFGS-B)."""
    sphi, cphi = np.sin(np.radians(half_angle_deg)), np.cos(np.radians(half_angle_deg))

    def fg(x):
        # all TEAs at once: batched eigendecompositions and first-order gradients
        a = a0 + x.reshape(shape) * sc
        Kt = np.einsum("tk,kab->tab", up, a)
        lam, V = np.linalg.eig(As_t - Bs_t @ Kt)                      # (T, N), (T, N, N)
        terms = [re_weight * (lam.real / n - re_offset)]
        if angle_weight > 0:
            # distance beyond the φ lines, |Im λ| cos φ + Re λ sin φ (> 0 outside), weighted
            terms.append(angle_weight * ((np.abs(lam.imag) * cphi + lam.real * sphi) / n - angle_offset))
        v = np.stack(terms, axis=1)                                     # (T, terms, N)
        vm = v.max()
        e = np.exp(beta * (v - vm))
        s_ = e.sum()
        wgt = e / s_
        try:
            W = np.linalg.inv(V)
        except np.linalg.LinAlgError:
            W = np.linalg.pinv(V)
        dlc = -np.einsum("tia,tbi->tiab", W @ Bs_t, V) / n              # ∂λ_i/∂K_ab / n
        gK = np.einsum("ti,tiab->tab", wgt[:, 0] * re_weight, dlc.real)
        if angle_weight > 0:
            g2 = np.sign(lam.imag)[:, :, None, None] * dlc.imag * cphi + dlc.real * sphi
            gK = gK + np.einsum("ti,tiab->tab", wgt[:, 1] * angle_weight, g2)
        g = np.einsum("tk,tab->kab", up, gK)
        return vm + np.log(s_) / beta, (g * sc).ravel()

    return fg


def refitted(fit: ScheduleFit, coef: np.ndarray, info: dict, method: str = "closed_loop") -> ScheduleFit:
    """The refitted schedule with its residuals against the design-point gains.

    Parameters
    ----------
    fit : acmm.design.schedule.ScheduleFit
        The schedule that was refitted (its points and gains).
    coef : (order+1, 3, N) array
        The new coefficients in powers of θ2*, units of K per rad^k.
    info : dict
        The refit's diagnostics (``refit_info``).
    method : str
        The refit's name (``ScheduleFit.method``).

    Returns
    -------
    acmm.design.schedule.ScheduleFit
        The polynomial schedule with ``coef``.
    """
    order = fit.order
    P = fit.variable.size
    vander_th = fit.variable[:, None] ** np.arange(order + 1)[None, :]
    resid = fit.gains.reshape(P, -1) - vander_th @ coef.reshape(order + 1, -1)
    rms = np.sqrt(np.mean(resid ** 2, axis=0)).reshape(fit.gains.shape[1:])
    peak = np.max(np.abs(fit.gains.reshape(P, -1)), axis=0).reshape(fit.gains.shape[1:])
    rel = np.divide(rms, peak, out=np.zeros_like(rms), where=peak > 0)
    return ScheduleFit(coef, fit.variable, fit.gains, rms, rel, fit.form, method, info)


def _minimax_slsqp(a0, sc, up, As_t, Bs_t, n, max_iter, top, re_weight, re_offset, angle_weight,
                   angle_offset, half_angle_deg):
    """Epigraph form of :func:`refit_closed_loop`'s objective solved by SLSQP.

    Variables z = (x, t), x the coefficient change relative to ``a0`` in units of ``sc``;
    minimize t subject to t − v ≥ 0 for the ``top`` largest terms of each kind per TEA.
    Returns the scipy result with ``x`` set to the coefficient part.
    """
    shape = a0.shape
    sphi, cphi = np.sin(np.radians(half_angle_deg)), np.cos(np.radians(half_angle_deg))
    T = As_t.shape[0]
    rows = np.arange(T)[:, None]
    memo = {}

    def terms(z):
        key = z.tobytes()
        if key in memo:
            return memo[key]
        a = a0 + z[:-1].reshape(shape) * sc
        Kt = np.einsum("tk,kab->tab", up, a)
        lam, V = np.linalg.eig(As_t - Bs_t @ Kt)
        try:
            W = np.linalg.inv(V)
        except np.linalg.LinAlgError:
            W = np.linalg.pinv(V)
        dlc = -np.einsum("tia,tbi->tiab", W @ Bs_t, V) / n                # ∂λ_i/∂K_ab / n
        kinds = [(re_weight * (lam.real / n - re_offset), re_weight * dlc.real)]
        if angle_weight > 0:
            kinds.append((angle_weight * ((np.abs(lam.imag) * cphi + lam.real * sphi) / n - angle_offset),
                          angle_weight * (np.sign(lam.imag)[:, :, None, None] * dlc.imag * cphi
                                          + dlc.real * sphi)))
        upper = lam.imag >= 0
        vals, jacs = [], []
        for v, g in kinds:
            o = np.argsort(-np.where(upper, v, -np.inf), axis=1)[:, :top]
            vals.append(v[rows, o].ravel())
            gk = g[rows, o]                                                 # (T, top, M, N)
            jacs.append((up[:, None, :, None, None] * gk[:, :, None] * sc[None, None]).reshape(-1, a0.size))
        out = (np.concatenate(vals), np.vstack(jacs))
        memo.clear()
        memo[key] = out
        return out

    def cons(z):
        return z[-1] - terms(z)[0]

    def cons_jac(z):
        J = terms(z)[1]
        return np.hstack([-J, np.ones((J.shape[0], 1))])

    e_t = np.zeros(a0.size + 1)
    e_t[-1] = 1.0
    z0 = np.zeros(a0.size + 1)
    z0[-1] = float(np.max(terms(z0)[0]))
    res = minimize(lambda z: z[-1], z0, jac=lambda z: e_t, method="SLSQP",
                   constraints=[{"type": "ineq", "fun": cons, "jac": cons_jac}],
                   options={"maxiter": max_iter, "ftol": REFIT_FTOL})
    res.x = res.x[:-1]
    return res


def _modelled_poles(a0, sc, up, As_t, Bs_t, n, x, band):
    """The largest Re λ/n over the TEAs at the scaled coefficient change ``x`` and, for every
    eigenvalue (Im λ ≥ 0) within ``band`` of it, Re λ/n and its gradient with respect to x."""
    a = a0 + x.reshape(a0.shape) * sc
    lam, V = np.linalg.eig(As_t - Bs_t @ np.einsum("tk,kab->tab", up, a))
    f = float(lam.real.max()) / n
    t, i = np.nonzero((lam.real / n >= f - band) & (lam.imag >= 0))
    rows = np.unique(t)
    try:
        W = np.linalg.inv(V[rows])
    except np.linalg.LinAlgError:           # a defective eigenvalue: its gradient is unbounded anyway
        W = np.linalg.pinv(V[rows])
    slot = np.searchsorted(rows, t)
    # ∂λ/∂K_ab = −(w_i B)_a v_bi (W V = I), chained through K = Σ_k up[t, k] a_k, a_k = a0_k + x_k sc_k
    dK = -np.einsum("ja,jb->jab", np.einsum("jn,jnm->jm", W[slot, i], Bs_t[t]), V[t, :, i]).real / n
    jac = (up[t][:, :, None, None] * dK[:, None] * sc[None]).reshape(t.size, -1)
    return f, lam.real[t, i] / n, jac


def _minimax_trust_lp(a0, sc, up, As_t, Bs_t, n, band, max_iter):
    """The largest Re λ over the TEAs minimized by the trust-region linear program of the module
    docstring.  Returns a result with ``x`` (scaled coefficient change), ``fun`` (largest Re λ/n),
    ``nit`` (linear programs), ``nfev`` (eigen-decompositions of every TEA), ``status`` (0:
    stopped on a tolerance) and ``message``."""
    nx = a0.size
    x, radius = np.zeros(nx), RADIUS_START
    f, vals, jac = _modelled_poles(a0, sc, up, As_t, Bs_t, n, x, band)
    history, nfev = [f], 1
    status, message = 1, f"{max_iter} linear programs (the guard) before a tolerance was met"
    for it in range(1, max_iter + 1):
        lp = linprog(np.r_[np.zeros(nx), 1.0], A_ub=np.hstack([jac, -np.ones((vals.size, 1))]), b_ub=-vals,
                     bounds=[(-radius, radius)] * nx + [(None, None)], method="highs")
        if lp.status != 0:
            status, message = 2, f"the linear program failed: {lp.message}"
            break
        predicted = f - float(lp.x[-1])
        if not predicted > 1e-12:
            status, message = 0, "the linear model predicts no fall of the largest Re λ (stationary)"
            break
        trial = _modelled_poles(a0, sc, up, As_t, Bs_t, n, x + lp.x[:-1], band)
        nfev += 1
        ratio = (f - trial[0]) / predicted
        if ratio > 0.1:
            x = x + lp.x[:-1]
            f, vals, jac = trial
            history.append(f)
            if ratio > 0.75:
                radius = min(2.0 * radius, RADIUS_START)
            if len(history) > STALL_WINDOW and history[-STALL_WINDOW - 1] - f < STALL_TOL:
                status, message = 0, (f"the last {STALL_WINDOW} accepted steps lowered the largest Re λ by "
                                      f"less than {STALL_TOL:g} n (stalled)")
                break
        else:
            radius *= 0.5
            if radius < RADIUS_TOL:
                status, message = 0, f"trust radius below {RADIUS_TOL:g}: no smaller step lowers the largest Re λ"
                break
    return SimpleNamespace(x=x, fun=f, nit=it, nfev=nfev, status=status, message=message)
