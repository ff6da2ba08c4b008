"""Quadratic gain schedules versus the TEA (CR-185644 ch. 5.3, Figs 5.3–5.26).

Design points lie on the blend I(s) = (1−s)·I_start + s·I_to (bias blended alike) and/or are
named configurations.  Each gets its TEA (eqs 4.1–4.3), its design model (eq 4.46) and a sector
LQR gain (ch. 5.2); every gain element is then fitted by a least-squares polynomial (order 2 in
the report) in the scheduling variable θ2* (pitch TEA, rad), optionally refined against the
closed loop along the path (:func:`refit_closed_loop`).  The scheduled gain is re-checked on the
local linear model at every design point and midpoint (:func:`check_schedule`) and at
``schedule.n_check`` TEAs evenly spaced along the whole path (:func:`check_path`: largest Re λ,
worst sector margin, disk margin at the plant input).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm import linearize as lin
from acmm import lqr
from acmm.settings import DesignSettings, ScheduleSettings, Sector  # noqa: F401  (re-exported)
from acmm.tea import TEA, resolve_bias, solve_tea, solve_tea_near


@dataclass(frozen=True)
class PointSpec:
    """A station configuration to design for: name, inertia (slug·ft²), bias (ft·lbf), blend s."""

    name: str
    inertia: np.ndarray
    bias: np.ndarray
    s: float = float("nan")
    theta_guess: np.ndarray | None = None


@dataclass
class PointDesign:
    """One design point: its TEA, design model and sector-LQR result."""

    spec: PointSpec
    tea: TEA
    model: lin.LinearModel
    lqr: object


@dataclass
class ScheduleFit:
    """A gain schedule K(θ2*) over the design points (θ2* = pitch TEA, rad).

    ``form="polynomial"`` (report ch. 5.3): K_ij(θ2*) = Σ_k coef[k, i, j]·θ2*^k, least squares.
    ``form="table"`` (the look-up alternative of ch. 6–7): K linear in θ2* between design points,
    held constant outside them.

    Attributes
    ----------
    coef : (order+1, 3, 24) array
        Polynomial coefficients, lowest power first; units of K per rad^k.
    variable : (P,) array
        Pitch TEA of each design point, rad.
    gains : (P, 3, 24) array
        LQR gains at the design points.
    rms_residual : (3, 24) array
        RMS residual of the polynomial per element (units of K).
    rel_residual : (3, 24) array
        RMS residual relative to max |K_ij| over the points.
    form : str
    """

    coef: np.ndarray
    variable: np.ndarray
    gains: np.ndarray
    rms_residual: np.ndarray
    rel_residual: np.ndarray
    form: str = "polynomial"
    method: str = "least_squares"
    refit_info: dict = field(default_factory=dict)

    @property
    def order(self) -> int:
        return self.coef.shape[0] - 1

    def gain(self, theta2: float) -> np.ndarray:
        """Scheduled K (3×24) at pitch TEA ``theta2`` (rad)."""
        return schedule_gain(self.form, self.coef, self.variable, self.gains, theta2)


def schedule_gain(form: str, coef: np.ndarray, nodes: np.ndarray, gains: np.ndarray,
                  theta2: float) -> np.ndarray:
    """Evaluate a schedule given as arrays (see :class:`ScheduleFit`)."""
    if form == "polynomial":
        powers = theta2 ** np.arange(coef.shape[0])
        return np.tensordot(powers, coef, axes=1)
    if form == "table":
        order = np.argsort(nodes)
        x, g = nodes[order], gains[order]
        k = int(np.clip(np.searchsorted(x, theta2) - 1, 0, len(x) - 2))
        w = float(np.clip((theta2 - x[k]) / (x[k + 1] - x[k]), 0.0, 1.0))
        return (1 - w) * g[k] + w * g[k + 1]
    raise ValueError(f"unknown schedule form {form!r}")


@dataclass
class ScheduleCheck:
    """Sector margins (units of n; > 0 means inside) and the largest pole real part (units of
    n; < 0 means stable) of the scheduled gain on the local linear models."""

    names: list[str]
    theta2: np.ndarray
    margin: np.ndarray
    kind: list[str] = field(default_factory=list)
    max_real: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def worst(self) -> float:
        return float(np.min(self.margin))


def blend_points(start: PointSpec, end: PointSpec, n_points: int) -> list[PointSpec]:
    """``n_points`` configurations on I(s) = (1−s)·I_start + s·I_end, bias blended alike."""
    out = []
    for k, s in enumerate(np.linspace(0.0, 1.0, n_points)):
        name = start.name if k == 0 else end.name if k == n_points - 1 else f"blend_{s:.3f}"
        out.append(PointSpec(name, (1 - s) * start.inertia + s * end.inertia,
                             (1 - s) * start.bias + s * end.bias, float(s)))
    return out


def tea_spaced_blend(start: PointSpec, end: PointSpec, n_points: int, n: float,
                     n_track: int = 81) -> list[PointSpec]:
    """``n_points`` blend configurations whose pitch TEAs are evenly spaced.

    The TEA is tracked along the blend by Newton continuation on ``n_track`` values of s (the
    physical branch, starting from the start configuration's TEA), then s is interpolated at
    evenly spaced θ2*.  Falls back to evenly spaced s when θ2*(s) is not monotonic.
    """
    s_grid = np.linspace(0.0, 1.0, n_track)
    thetas = _tea_track(start, end, n, n_track)
    th2 = thetas[:, 1]
    d = np.diff(th2)
    if not (np.all(d > 0) or np.all(d < 0)):
        return blend_points(start, end, n_points)
    order = np.argsort(th2)
    targets = np.linspace(th2[0], th2[-1], n_points)
    s_pts = np.interp(targets, th2[order], s_grid[order])
    s_pts[0], s_pts[-1] = 0.0, 1.0
    out = []
    for k, s in enumerate(s_pts):
        name = start.name if k == 0 else end.name if k == n_points - 1 else f"blend_{s:.3f}"
        guess = np.array([np.interp(s, s_grid, thetas[:, i]) for i in range(3)])
        out.append(PointSpec(name, (1 - s) * start.inertia + s * end.inertia,
                             (1 - s) * start.bias + s * end.bias, float(s), guess))
    return out


_TRACKS: dict = {}


def _tea_track(start: PointSpec, end: PointSpec, n: float, n_track: int) -> np.ndarray:
    """TEA (n_track, 3) along the blend start → end by Newton continuation on evenly spaced s,
    remembered per (start, end, n, n_track): the design points and the path check of one design
    track the same blend."""
    key = tuple(np.asarray(x, dtype=float).tobytes() for x in (start.inertia, start.bias, end.inertia, end.bias)) + (
        float(n), int(n_track))
    if key in _TRACKS:
        return _TRACKS[key].copy()
    t = solve_tea(start.inertia, n, start.bias).theta
    thetas = []
    for s in np.linspace(0.0, 1.0, n_track):
        t = solve_tea_near((1 - s) * start.inertia + s * end.inertia, n, (1 - s) * start.bias + s * end.bias,
                           t).theta
        thetas.append(t)
    thetas = np.array(thetas)
    if len(_TRACKS) > 16:
        _TRACKS.clear()
    _TRACKS[key] = thetas
    return thetas.copy()


def point_specs(cfg) -> list[PointSpec]:
    """Design points of a config: the blend start → ``schedule.to`` plus ``schedule.points``.

    Without a ``schedule`` section, the config's own configuration is the only point.  This is
    where the config's inertias and biases become :class:`PointSpec` s (with
    :func:`acmm.settings.design_settings`, the one reading of the config on the design path).
    """
    from acmm.settings import schedule_settings

    n = cfg.orbit_rate
    inertia = cfg.inertia.matrix()
    start = PointSpec(cfg.name, inertia, resolve_bias(cfg.disturbance, inertia, n), 0.0)
    sch = cfg.schedule
    if sch is None:
        return [start]
    end = None
    if sch.to is not None:
        i_to = sch.to.inertia.matrix()
        end = PointSpec(sch.to.name, i_to, resolve_bias(sch.to.disturbance, i_to, n), 1.0)
    extras = []
    for p in sch.points:
        i_p = p.inertia.matrix()
        extras.append(PointSpec(p.name, i_p, resolve_bias(p.disturbance, i_p, n)))
    return schedule_specs(start, end, extras, schedule_settings(cfg), n)


def schedule_specs(start: PointSpec, end: PointSpec | None, extras: list[PointSpec], sched, n: float
                   ) -> list[PointSpec]:
    """The design points: ``start`` alone (``sched`` None), else the blend ``start`` → ``end``
    (``sched.n_points`` points spaced by ``sched.spacing``; none when ``end`` is None) followed by
    the named ``extras``.  ``n``: orbital rate, rad/s."""
    if sched is None:
        return [start]
    specs = [start]
    if end is not None:
        if sched.spacing == "tea":
            specs = tea_spaced_blend(start, end, sched.n_points, n)
        else:
            specs = blend_points(start, end, sched.n_points)
    return specs + list(extras)


def design_one(spec: PointSpec, s: DesignSettings) -> PointDesign:
    """TEA, design model and sector LQR of one design point (settings ``s``)."""
    n = s.orbit_rate
    if spec.theta_guess is not None:
        t = solve_tea_near(spec.inertia, n, spec.bias, spec.theta_guess)
    else:
        t = solve_tea(spec.inertia, n, spec.bias)
    model = lin.design_point(spec.inertia, t.theta, n, model=s.model, drf_mode=s.drf_mode)
    res = sector_design(model.A, model.B, model.scales, s)
    return PointDesign(spec, t, model, res)


def sector_design(A, B, scales, s: DesignSettings):
    """The sector LQR of one linear model with the design settings ``s`` (R, Q0, sector, pole
    method, Riccati solver, tolerances; orbital rate ``s.orbit_rate``) — the one call the
    pipeline, the sweep's redesign and the report's errata evidence share."""
    return lqr.sector_lqr(A, B, s.R * np.eye(3), s.orbit_rate, sigma=s.sector.sigma,
                          half_angle_deg=s.sector.half_angle_deg,
                          Q0=s.q0_weight(A.shape[0]),   # on the scaled states
                          scale=scales, method=s.pole_method, riccati_method=s.riccati_method,
                          residual_tol=s.residual_tol, min_margin=s.min_margin,
                          line_spacing=s.line_spacing)


def design_q0(d, nx: int):
    """The initial state weight of a config's ``design`` section on the scaled states:
    Q0·I plus ``Q0_groups`` on the diagonal; None when zero (minimum energy)."""
    q = np.full(nx, float(d.Q0))
    if d.Q0_groups is not None:
        g = d.Q0_groups.diagonal()
        if g.size != nx:
            raise ValueError(f"Q0_groups gives {g.size} weights for a {nx}-state model")
        q = q + g
    return np.diag(q) if np.any(q > 0) else None


def fit_schedule(theta2: np.ndarray, gains: np.ndarray, order: int = 2, form: str = "polynomial",
                 weights=None) -> ScheduleFit:
    """Least-squares polynomial fit of every gain element versus θ2* (ch. 5.3).

    Parameters
    ----------
    theta2 : (P,) array
        Pitch TEA of each design point, rad.
    gains : (P, 3, 24) array
        LQR gains per point.
    order : int
        Polynomial order (2 in the report); reduced to P−1 when there are fewer points.
    form : {"polynomial", "table"}
        Which form :meth:`ScheduleFit.gain` evaluates; the polynomial and its residuals are
        computed in both cases, for the record.
    weights : (P,) array or None
        Least-squares weight of each design point (default 1).
    """
    theta2 = np.asarray(theta2, float)
    gains = np.asarray(gains, float)
    p = theta2.size
    order = min(order, p - 1)
    vander = theta2[:, None] ** np.arange(order + 1)[None, :]
    flat = gains.reshape(p, -1)
    w = np.ones(p) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    coef, *_ = np.linalg.lstsq(vander * w[:, None], flat * w[:, None], rcond=None)
    resid = flat - vander @ coef
    rms = np.sqrt(np.mean(resid ** 2, axis=0)).reshape(3, -1)
    peak = np.max(np.abs(flat), axis=0).reshape(3, -1)
    rel = np.divide(rms, peak, out=np.zeros_like(rms), where=peak > 0)
    return ScheduleFit(coef.reshape(order + 1, 3, -1), theta2, gains, rms, rel, form)


def check_schedule(fit: ScheduleFit, points: list[PointDesign], s: DesignSettings) -> ScheduleCheck:
    """Sector margin of the scheduled gain at each design point and each blend midpoint."""
    d = s
    n = s.orbit_rate
    names, th2, margins, kinds, max_real = [], [], [], [], []

    def _check(name, model, theta2, kind):
        poles = np.linalg.eigvals(model.A - model.B @ fit.gain(theta2))
        names.append(name)
        th2.append(theta2)
        kinds.append(kind)
        margins.append(np.min(lqr.sector_margin(poles, n, d.sector.sigma, d.sector.half_angle_deg)))
        max_real.append(np.max(poles.real) / n)

    for p in points:
        _check(p.spec.name, p.model, p.tea.theta[1], "design point")
    blended = [p for p in points if np.isfinite(p.spec.s)]
    for a, b in zip(blended, blended[1:]):
        spec = PointSpec(f"mid_{0.5 * (a.spec.s + b.spec.s):.3f}", 0.5 * (a.spec.inertia + b.spec.inertia),
                         0.5 * (a.spec.bias + b.spec.bias), 0.5 * (a.spec.s + b.spec.s))
        t = solve_tea_near(spec.inertia, n, spec.bias, 0.5 * (a.tea.theta + b.tea.theta))
        model = lin.design_point(spec.inertia, t.theta, n, model=d.model, drf_mode=d.drf_mode)
        _check(spec.name, model, t.theta[1], "midpoint")
    return ScheduleCheck(names, np.array(th2), np.array(margins), kinds, np.array(max_real))


# ---------------------------------------------------------------------------------------------
# The scheduled gain judged on the closed loop along the whole path
# ---------------------------------------------------------------------------------------------
@dataclass
class PathModels:
    """Local design models at TEAs evenly spaced along the blend path (``schedule.n_check``)."""

    theta2: np.ndarray          # (P,) pitch TEA, rad
    s: np.ndarray               # (P,) blend parameter
    A: np.ndarray               # (P, N, N) physical units
    B: np.ndarray               # (P, N, M)
    scales: np.ndarray          # (N,) state scaling of the design models


@dataclass
class PathCheck:
    """The scheduled gain on the local model at every TEA of a :class:`PathModels`.

    Attributes
    ----------
    theta2 : (P,) array
        Pitch TEA, rad.
    s : (P,) array
        Blend parameter.
    max_real : (P,) array
        Largest Re λ(A − BK(θ2*)), units of n.
    margin : (P,) array
        Worst :func:`acmm.lqr.sector_margin`, units of n (> 0: every pole in the sector).
    disk_margin : (P,) array
        Balanced (skew 0) multiloop disk margin α at the plant input (loop broken at u),
        dimensionless (:func:`disk_margin_input`).
    disk_gain_margin_db, disk_phase_margin_deg : (P,) arrays
        The gain (dB) and phase (deg) variations that α guarantees simultaneously in all loops.
    poles : (P, N) complex array
        Closed-loop poles, rad/s.
    """

    theta2: np.ndarray
    s: np.ndarray
    max_real: np.ndarray
    margin: np.ndarray
    disk_margin: np.ndarray
    disk_gain_margin_db: np.ndarray
    disk_phase_margin_deg: np.ndarray
    poles: np.ndarray

    @property
    def fraction_in_sector(self) -> float:
        return float(np.mean(self.margin >= 0.0))


def path_models(points: list[PointDesign], s: DesignSettings, n_check: int) -> PathModels | None:
    """Design models at ``n_check`` TEAs evenly spaced between the first and last blend point.

    None when the config has no blend (``schedule.to``).  The TEA of each model is solved
    exactly (Newton from the continuation guess), so the θ2* are evenly spaced to within the
    interpolation of the 81-point continuation track.
    """
    d = s
    n = s.orbit_rate
    blended = [p for p in points if np.isfinite(p.spec.s)]
    if len(blended) < 2:
        return None
    start, end = blended[0].spec, blended[-1].spec
    start = PointSpec(start.name, start.inertia, start.bias, 0.0)
    end = PointSpec(end.name, end.inertia, end.bias, 1.0)
    specs = tea_spaced_blend(start, end, n_check, n)
    th, ss, As, Bs = [], [], [], []
    scales = None
    for sp in specs:
        if sp.theta_guess is not None:
            t = solve_tea_near(sp.inertia, n, sp.bias, sp.theta_guess)
        else:
            t = solve_tea(sp.inertia, n, sp.bias)
        m = lin.design_point(sp.inertia, t.theta, n, model=d.model, drf_mode=d.drf_mode)
        th.append(t.theta[1])
        ss.append(sp.s)
        As.append(m.A)
        Bs.append(m.B)
        scales = m.scales
    return PathModels(np.array(th), np.array(ss), np.array(As), np.array(Bs), scales)


#: Frequencies of the disk-margin evaluation, units of n (log-spaced).
DISK_OMEGA_N = np.logspace(-2.0, 3.0, 121)


def _mu_upper(M: np.ndarray, iters: int = 25, floor=None) -> np.ndarray:
    """min over diagonal D > 0 of σ̄(D M D⁻¹) for stacked square complex M (F, m, m).

    Osborne balancing start, then the fixed point |u_i| = |v_i| of the top singular vectors
    (the optimality condition of the D-scaling for a simple σ̄).  Every iterate is an upper
    bound on μ with respect to m independent complex scalars; for m ≤ 3 the infimum equals μ
    (Packard & Doyle 1993), the iteration approaches it from above.  With ``floor`` (F,), a
    row stops iterating once its bound is below its floor (the caller's lower bound on the
    largest μ that matters), returning that bound.
    """
    F, m, _ = M.shape
    d = np.ones((F, m))
    aM = np.abs(M)
    offdiag = 1.0 - np.eye(m)
    for _ in range(5):
        A = aM * offdiag * d[:, :, None] / d[:, None, :]
        r = np.sqrt((A ** 2).sum(axis=2)) + 1e-300
        c = np.sqrt((A ** 2).sum(axis=1)) + 1e-300
        d = d * np.sqrt(np.sqrt(c / r))
    best = np.full(F, np.inf)
    act = np.arange(F)                      # rows whose D-scaling is still moving
    for _ in range(iters):
        Ma = M[act] * d[act, :, None] / d[act, None, :]
        # σ̄ and the top singular vectors from the 3×3 Hermitian MᴴM (faster than a batched
        # SVD; u = M v/σ̄ — same values to rounding)
        w, X = np.linalg.eigh(np.conj(np.swapaxes(Ma, 1, 2)) @ Ma)
        sig = np.sqrt(np.maximum(w[:, -1], 0.0))
        vv = X[:, :, -1]
        best[act] = np.minimum(best[act], sig)
        u = np.abs(np.einsum("fab,fb->fa", Ma, vv)) / (sig[:, None] + 1e-300) + 1e-300
        v = np.abs(vv) + 1e-300
        step = np.sqrt(v / u)
        d[act] = d[act] * step
        # a row whose scaling no longer moves (relative 1e-12) has reached its fixed point:
        # further iterates repeat its σ̄ to rounding
        keep = np.max(np.abs(step - 1.0), axis=1) > 1e-12
        if floor is not None:
            keep &= best[act] >= floor[act]
        act = act[keep]
        if act.size == 0:
            break
    return best


def disk_margin_input(A, B, K, n: float, scale=None, omega_n=None, *, refine: int = 6):
    """Balanced multiloop disk margin at the plant input of ẋ = Ax + Bu, u = −Kx.

    Loop broken at u: L(s) = K(sI − A)⁻¹B, S = (I + L)⁻¹ = I − K(sI − A + BK)⁻¹B.  With
    skew 0 (Seiler, Packard & Gahinet 2020; python-control ``disk_margins``) ::

        α = 1 / max_ω μ_Δ(S(jω) − I/2),   Δ = diag(δ1, δ2, δ3) complex,

    evaluated here with μ_Δ replaced by its D-scaled upper bound (:func:`_mu_upper`, equal to μ
    for three scalar loops), found by branch and bound over the frequency grid: the bound is
    computed at the frequencies whose cheap upper bound √(‖M‖₁‖M‖∞) or σ̄ still exceeds the
    largest μ found, so α is a guaranteed *lower* bound of the disk margin on the grid and equals
    the D-scaled value there.  python-control's ``disk_margins`` (SLICOT AB13MD
    per frequency, ~2 ms each) computes the same quantity; the tests compare the two on the
    same loops (agreement to 1e-4 relative), this vectorized form keeps the 201-TEA check of
    the design stage at ~0.3 s.

    Parameters
    ----------
    A, B, K : arrays
        Model (physical units) and gain.  Must give a stable closed loop (else α = 0).
    n : float
        Orbital rate, rad/s (frequency unit of ``omega_n``).
    scale : (N,) array or None
        State scaling for the computation (the transfer function is unchanged).
    omega_n : array or None
        Frequencies in units of n; default :data:`DISK_OMEGA_N` (0.01n … 1000n, 121 points).

    Returns
    -------
    (α, gain margin dB, phase margin deg) : tuple of float
        The disk, and the gain/phase variations it guarantees simultaneously in all loops.
    """
    A, B, K = (np.asarray(x, dtype=float) for x in (A, B, K))
    if scale is not None:
        d = np.asarray(scale, dtype=float)
        A, B, K = A / d[:, None] * d[None, :], B / d[:, None], K * d[None, :]
    alpha = float(_disk_alpha_batch([_disk_parts(A, B, K, n, omega_n)], refine)[0])
    return (alpha,) + disk_gain_phase(alpha)


def _disk_parts(A, B, K, n, omega_n=None, refine=6, eig=None):
    """S(jω) − I/2 on the frequency grid (stacked) and the cheap upper bound √(‖M‖₁‖M‖∞) of
    σ̄ ≥ μ at each frequency; None for an unstable closed loop.  Scaled inputs.  ``eig``:
    the eigendecomposition (λ, V, V⁻¹ or None, cond V) of A − BK when already computed."""
    Acl = A - B @ K
    if eig is None:
        lam, V = np.linalg.eig(Acl)
        W, ok = None, False
        if np.max(lam.real) < 0:
            try:
                W = np.linalg.inv(V)
                ok = np.linalg.cond(V) < 1e8
            except np.linalg.LinAlgError:
                ok = False
    else:
        lam, V, W, condV = eig
        ok = W is not None and condV < 1e8
    if np.max(lam.real) >= 0:
        return None
    w = n * (DISK_OMEGA_N if omega_n is None else np.asarray(omega_n, dtype=float))
    m = B.shape[1]
    if ok:
        KV, WB = K @ V, W @ B
        S = np.eye(m)[None] - np.einsum("ak,fk,kb->fab", KV, 1.0 / (1j * w[:, None] - lam[None, :]), WB)
    else:
        eye = np.eye(A.shape[0])
        S = np.array([np.eye(m) - K @ np.linalg.solve(1j * wk * eye - Acl, B) for wk in w])
    M = S - 0.5 * np.eye(m)[None]
    aM = np.abs(M)
    cheap = np.sqrt(aM.sum(axis=1).max(axis=1) * aM.sum(axis=2).max(axis=1))
    return M, cheap


def _disk_alpha_batch(parts, refine: int = 6, rounds: int = 6) -> np.ndarray:
    """Disk margin α = 1/max_ω μ(M(ω)) for several loops at once (None → 0), exact to the
    D-scaling bound on the grid by branch and bound: μ is computed (batched over loops) at the
    frequencies whose upper bound (√(‖M‖₁‖M‖∞), then σ̄) still exceeds the largest μ found."""
    P = len(parts)
    ub = [None if p is None else p[1].copy() for p in parts]      # current upper bound per freq
    exact = [None if p is None else np.zeros(p[1].size, bool) for p in parts]
    best = np.zeros(P)
    # a lower bound of the largest μ per loop: max|M_ii| ≤ μ(M) and ρ(M) ≤ μ(M) at every
    # frequency, so a frequency whose D-scaled bound falls below the largest of these cannot
    # set α (its iteration may stop there; α is unchanged)
    low = np.zeros(P)
    for j, p in enumerate(parts):
        if p is not None:
            low[j] = float(np.max(np.abs(np.diagonal(p[0], axis1=1, axis2=2))))
    for rnd in range(rounds + 1):
        pick = []
        for j, p in enumerate(parts):
            if p is None:
                continue
            open_ = np.flatnonzero(~exact[j] & (ub[j] > best[j] * (1 + 1e-9)))
            if open_.size == 0:
                continue
            order = open_[np.argsort(-ub[j][open_])]
            pick.append((j, order if rnd == rounds else order[:refine]))
        if not pick:
            break
        Ms = np.concatenate([parts[j][0][f] for j, f in pick])
        rho = np.max(np.abs(np.linalg.eigvals(Ms)), axis=1)
        k = 0
        for j, f in pick:
            low[j] = max(low[j], float(np.max(rho[k:k + f.size])))
            k += f.size
        floor = np.concatenate([np.full(f.size, max(low[j], best[j])) for j, f in pick])
        sig = np.linalg.norm(Ms, ord=2, axis=(1, 2))
        mu = np.minimum(sig, _mu_upper(Ms, floor=floor))
        k = 0
        for j, f in pick:
            r = f.size
            ub[j][f] = mu[k:k + r]
            exact[j][f] = True
            best[j] = max(best[j], float(np.max(mu[k:k + r])))
            k += r
    out = np.zeros(P)
    for j, p in enumerate(parts):
        if p is not None:
            out[j] = 1.0 / max(np.max(ub[j]), best[j])
    return out


def disk_gain_phase(alpha: float) -> tuple[float, float]:
    """Gain (dB) and phase (deg) margins guaranteed by a balanced disk of size α (skew 0)."""
    if alpha >= 2.0:
        return float("inf"), 90.0
    gmin = (1 - 0.5 * alpha) / (1 + 0.5 * alpha)
    gmax = (1 + 0.5 * alpha) / (1 - 0.5 * alpha)
    dgm = 20.0 * np.log10(min(1.0 / gmin, gmax))
    c = (1 + gmin * gmax) / (gmin + gmax)
    dpm = float(np.degrees(np.arccos(c))) if abs(c) < 1 else float("inf")
    return float(dgm), dpm


def check_path(gain_at, path: PathModels, n: float, sigma: float = 0.5,
               half_angle_deg: float = 45.0, disk: bool = True) -> PathCheck:
    """Largest Re λ, worst sector margin and disk margin of the scheduled gain along a path.

    ``gain_at(θ2*)`` returns the scheduled K (physical units) at pitch TEA θ2* (rad).
    """
    P = path.theta2.size
    mr, mg, dm, dg, dp = (np.full(P, np.nan) for _ in range(5))
    poles, parts = [], []
    d = path.scales
    Ks = np.array([gain_at(path.theta2[j]) for j in range(P)]) * d[None, None, :]
    As = path.A / d[None, :, None] * d[None, None, :]
    Bs = path.B / d[None, :, None]
    # one batched eigendecomposition of every closed loop, reused by the disk margin
    lam_all, V_all = np.linalg.eig(As - Bs @ Ks)
    if disk:
        condV = np.linalg.cond(V_all)
        try:
            W_all = np.linalg.inv(V_all)
        except np.linalg.LinAlgError:
            W_all = None
    for j in range(P):
        lam = lam_all[j]
        lam = lam[np.lexsort((lam.imag, lam.real))]
        poles.append(lam)
        mr[j] = np.max(lam.real) / n
        mg[j] = np.min(lqr.sector_margin(lam, n, sigma, half_angle_deg))
    if disk:
        # S(jω) − I/2 of every stable, well-conditioned loop in one modal evaluation
        # (as in _disk_parts); the others one by one
        fast = (np.max(lam_all.real, axis=1) < 0) & (condV < 1e8) & (W_all is not None)
        parts = [None] * P
        if np.any(fast):
            idx = np.flatnonzero(fast)
            w = n * DISK_OMEGA_N
            m = Bs.shape[2]
            KV = Ks[idx] @ V_all[idx]                                   # (Q, M, N)
            WB = W_all[idx] @ Bs[idx]                                   # (Q, N, M)
            res = 1.0 / (1j * w[None, :, None] - lam_all[idx][:, None, :])   # (Q, F, N)
            M_all = (0.5 * np.eye(m))[None, None] - np.einsum("qak,qfk,qkb->qfab", KV, res, WB,
                                                                optimize=True)
            aM = np.abs(M_all)
            cheap = np.sqrt(aM.sum(axis=2).max(axis=2) * aM.sum(axis=3).max(axis=2))
            for r, j in enumerate(idx):
                parts[j] = (M_all[r], cheap[r])
        for j in np.flatnonzero(~fast):
            eig = (lam_all[j], V_all[j], None if W_all is None else W_all[j], condV[j])
            parts[j] = _disk_parts(As[j], Bs[j], Ks[j], n, eig=eig)
    if disk:
        # batched branch and bound over every TEA's frequencies
        dm[:] = _disk_alpha_batch(parts)
        for j in range(P):
            dg[j], dp[j] = disk_gain_phase(dm[j]) if dm[j] > 0 else (0.0, 0.0)
    return PathCheck(path.theta2.copy(), path.s.copy(), mr, mg, dm, dg, dp, np.array(poles))


def _power_basis(a: np.ndarray, c: float, h: float) -> np.ndarray:
    """Coefficients in powers of θ of Σ_k a[k]·((θ − c)/h)^k (a: (order+1, ...))."""
    from math import comb

    order = a.shape[0] - 1
    b = np.zeros_like(a)
    for k in range(order + 1):
        for j in range(k + 1):       # ((θ − c)/h)^k = Σ_j C(k,j) θ^j (−c)^(k−j) / h^k
            b[j] = b[j] + a[k] * comb(k, j) * (-c) ** (k - j) / h ** k
    return b


#: Parameters of the closed-loop refit used by the design stage, chosen by measurement on the
#: stair-case (README "Gain schedule"): the max of Re λ/n and of 0.7·(distance beyond the φ lines/n
#: − 2.2) — the angle term only bites on strongly oscillatory poles and keeps the disk margin up —
#: on every 10th of the path TEAs (21 of 201), in epigraph form (the 4 largest terms of each kind
#: per TEA) by 25 SLSQP iterations (~0.3 s; the former smooth max β = 20 by 300 L-BFGS iterations
#: took ~3 s and reached a worse worst Re λ on the same design points).
REFIT_DEFAULTS = {"every": 10, "beta": 20.0, "max_iter": 25, "angle_weight": 0.7, "angle_offset": 2.2,
                  "solver": "slsqp", "top": 4}


def refit_closed_loop(fit: ScheduleFit, path: PathModels, n: float, *, every: int = 5,
                      beta: float = 20.0, max_iter: int = 60, angle_weight: float = 0.0,
                      half_angle_deg: float = 45.0, re_weight: float = 1.0,
                      re_offset: float = 0.0, angle_offset: float = 0.0, solver: str = "lbfgs",
                      top: int = 3) -> ScheduleFit:
    """Refine a least-squares polynomial schedule against the closed loop along the path.

    The coefficients are moved to minimize the smooth maximum ::

        f(c) = (1/β) log Σ_{j,i} exp(β Re λ_i(A_j − B_j K(θ_j; c)) / n)

    over every ``every``-th TEA of ``path`` (the ends included), i.e. to push the least damped
    closed-loop pole along the whole path to the left; with ``angle_weight`` w > 0 the terms
    w·((|Im λ| cos φ + Re λ sin φ)/n − ``angle_offset``) of the sector's φ lines join the max, so
    strongly oscillatory poles (which carry the smallest disk margins) are pulled back too.
    ``re_weight``/``re_offset`` scale and shift the Re λ terms.  Gradient: first-order eigenvalue
    perturbation ∂λ_i/∂K_ab = −(w_i^H B)_a v_ib (W V = I), chained through K = Σ c_k u^k;
    L-BFGS-B (scipy) on the coefficients relative to the least-squares ones, in the normalized
    variable u = (θ2* − c)/h ∈ [−1, 1], mapped back to powers of θ2*.  The form stays the
    report's: one polynomial of the fit's order per gain element.  The result is accepted only
    if it lowers the largest Re λ on those TEAs; it is re-checked on every TEA by
    :func:`check_path`.

    ``solver="slsqp"`` minimizes the same quantity in its exact (β → ∞) epigraph form,
    min t subject to v ≤ t for the ``top`` largest Re λ terms and the ``top`` largest φ-line
    terms per TEA (poles with Im λ ≥ 0, each conjugate pair once), by SLSQP with the same
    analytic eigenvalue gradients; it reaches a lower worst Re λ in ~10× fewer eigenvalue
    evaluations than L-BFGS on the smooth maximum (README "Gain schedule").
    """
    from scipy.optimize import minimize

    if fit.form != "polynomial":
        raise ValueError("refit_closed_loop refines a polynomial schedule")
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
    sphi, cphi = np.sin(np.radians(half_angle_deg)), np.cos(np.radians(half_angle_deg))

    As_t, Bs_t = np.array(As), np.array(Bs)                          # (T, N, N), (T, N, M)

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

    def worst(x):
        a = a0 + x.reshape(shape) * sc
        return max(np.max(np.linalg.eigvals(A - B @ np.tensordot(tp, a, axes=1)).real)
                   for A, B, tp in zip(As, Bs, up)) / n

    x0 = np.zeros(a0.size)
    w0 = worst(x0)
    if solver == "slsqp":
        res = _minimax_slsqp(a0, sc, up, As_t, Bs_t, n, max_iter, top, re_weight, re_offset,
                             angle_weight, angle_offset, half_angle_deg)
    elif solver == "lbfgs":
        res = minimize(fg, x0, jac=True, method="L-BFGS-B", options={"maxiter": max_iter})
    else:
        raise ValueError(f"unknown refit solver {solver!r}")
    w1 = worst(res.x)
    info = {"beta": beta, "iterations": int(res.nit), "evaluations": int(res.nfev),
            "n_tea": len(idx), "max_real_before": float(w0), "max_real_after": float(w1),
            "accepted": bool(w1 < w0)}
    if not w1 < w0:
        return ScheduleFit(fit.coef, fit.variable, fit.gains, fit.rms_residual, fit.rel_residual,
                           fit.form, "least_squares", info)
    a = a0 + res.x.reshape(shape) * sc
    coef = _power_basis(a, c0, h0) / d[None, None, :]
    P = fit.variable.size
    vander_th = fit.variable[:, None] ** np.arange(order + 1)[None, :]
    resid = fit.gains.reshape(P, -1) - vander_th @ coef.reshape(order + 1, -1)
    rms = np.sqrt(np.mean(resid ** 2, axis=0)).reshape(fit.gains.shape[1:])
    peak = np.max(np.abs(fit.gains.reshape(P, -1)), axis=0).reshape(fit.gains.shape[1:])
    rel = np.divide(rms, peak, out=np.zeros_like(rms), where=peak > 0)
    return ScheduleFit(coef, fit.variable, fit.gains, rms, rel, fit.form, "closed_loop", info)


def _minimax_slsqp(a0, sc, up, As_t, Bs_t, n, max_iter, top, re_weight, re_offset, angle_weight,
                   angle_offset, half_angle_deg):
    """Epigraph form of :func:`refit_closed_loop`'s objective solved by SLSQP.

    Variables z = (x, t), x the coefficient change relative to ``a0`` in units of ``sc``;
    minimize t subject to t − v ≥ 0 for the ``top`` largest terms of each kind per TEA.
    Returns the scipy result with ``x`` set to the coefficient part.
    """
    from scipy.optimize import minimize

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
                   options={"maxiter": max_iter, "ftol": 1e-6})
    res.x = res.x[:-1]
    return res
