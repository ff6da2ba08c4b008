"""Quadratic gain schedules versus the TEA (CR-185644 ch. 5.3, Figs 5.3–5.26).

Each design point (:mod:`acmm.design.schedule_points`) gets its TEA (eqs 4.1–4.3), its design model
(eq 4.46) and a sector LQR gain (ch. 5.2); every gain element is then fitted by a least-squares
polynomial (order 2 in the report) in the scheduling variable θ2* (pitch TEA, rad), and with
``schedule.fit: shifted_lqr`` converged on the path's shifted LQR cost
(:func:`acmm.design.schedule_shifted_lqr.refit_shifted_lqr`).  The scheduled gain is re-checked on
the local linear model at every design point and midpoint (:func:`check_schedule`) and along the
whole path (:func:`acmm.design.path_check.check_path`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm.model import linearize as lin
from acmm.design import sector_lqr
from acmm.design.methods import PointGain, with_robust_gain
from acmm.design.settings import DesignSettings
from acmm.design.schedule_points import PointSpec, blend_context
from acmm.model.tea import TEA, solve_tea, solve_tea_near


@dataclass
class PointDesign:
    """One design point: its TEA, design model and gain.

    Attributes
    ----------
    spec : PointSpec
        The configuration.
    tea : acmm.model.tea.TEA
        Its torque equilibrium attitude (eqs 4.1–4.3).
    model : acmm.model.linearize.LinearModel
        Its design model (eq 4.46).
    gain : acmm.design.methods.PointGain
        Its design (ch. 5.2) by the route of ``design.pole_method``.
    """

    spec: PointSpec
    tea: TEA
    model: lin.LinearModel
    gain: PointGain


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
        LQR gains at the design points, units of K.
    form : str
        ``"polynomial"`` or ``"table"``: what :meth:`gain` evaluates.
    method : str
        How the polynomial was fitted: ``"least_squares"`` or ``"shifted_lqr"``.
    refit_info : dict
        Diagnostics of the refit on the path
        (:func:`acmm.design.schedule_shifted_lqr.refit_shifted_lqr`).
    rms_residual : (3, 24) array
        RMS residual of the polynomial at the design points per element (units of K), computed
        from ``coef``, ``variable`` and ``gains``.
    rel_residual : (3, 24) array
        RMS residual relative to max |K_ij| over the points, dimensionless.
    """

    coef: np.ndarray
    variable: np.ndarray
    gains: np.ndarray
    form: str = "polynomial"
    method: str = "least_squares"
    refit_info: dict = field(default_factory=dict)
    rms_residual: np.ndarray = field(init=False)
    rel_residual: np.ndarray = field(init=False)

    def __post_init__(self):
        # the polynomial's residuals at the design points (a table's polynomial too, for the record)
        flat = self.gains.reshape(self.variable.size, -1)
        vander = self.variable[:, None] ** np.arange(self.order + 1)[None, :]
        resid = flat - vander @ self.coef.reshape(self.order + 1, -1)
        self.rms_residual = np.sqrt(np.mean(resid ** 2, axis=0)).reshape(self.gains.shape[1:])
        peak = np.max(np.abs(flat), axis=0).reshape(self.gains.shape[1:])
        self.rel_residual = np.divide(self.rms_residual, peak, out=np.zeros_like(peak), where=peak > 0)

    @property
    def order(self) -> int:
        """Polynomial order of the schedule."""
        return self.coef.shape[0] - 1

    def gain(self, theta2: float) -> np.ndarray:
        """Scheduled K (3×24) at pitch TEA ``theta2`` (rad).

        Parameters
        ----------
        theta2 : float
            Pitch TEA θ2*, rad.

        Returns
        -------
        (3, 24) array
            Scheduled gain, units of K.
        """
        return schedule_gain(self.form, self.coef, self.variable, self.gains, theta2)


def schedule_gain(form: str, coef: np.ndarray, nodes: np.ndarray, gains: np.ndarray,
                  theta2: float) -> np.ndarray:
    """Evaluate a schedule given as arrays (see :class:`ScheduleFit`).

    Parameters
    ----------
    form : str
        ``"polynomial"`` or ``"table"``.
    coef : (order+1, 3, 24) array
        Polynomial coefficients, lowest power first; units of K per rad^k.
    nodes : (P,) array
        Pitch TEA of each design point, rad.
    gains : (P, 3, 24) array
        Gains at the design points, units of K.
    theta2 : float
        Pitch TEA θ2* at which to evaluate, rad.

    Returns
    -------
    (3, 24) array
        Scheduled gain, units of K.

    Raises
    ------
    ValueError
        ``form`` is unknown.
    """
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
    n; < 0 means stable) of the scheduled gain on the local linear models.

    Attributes
    ----------
    names : list of str
        Name of each checked point.
    theta2 : (P,) array
        Pitch TEA of each checked point, rad.
    margin : (P,) array
        Worst sector margin at each point, units of n.
    kind : list of str
        ``"design point"`` or ``"midpoint"``.
    max_real : (P,) array
        Largest pole real part at each point, units of n.
    """

    names: list[str]
    theta2: np.ndarray
    margin: np.ndarray
    kind: list[str] = field(default_factory=list)
    max_real: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def worst(self) -> float:
        """Worst sector margin over the checked points, units of n."""
        return float(np.min(self.margin))


def design_one(spec: PointSpec, s: DesignSettings) -> PointDesign:
    """TEA, design model and gain of one design point (settings ``s``).

    Parameters
    ----------
    spec : PointSpec
        The configuration.
    s : DesignSettings
        The design settings.

    Returns
    -------
    PointDesign
        Its TEA, design model and gain.
    """
    n = s.orbit_rate
    if spec.theta_guess is not None:
        t = solve_tea_near(spec.inertia, n, spec.bias, spec.theta_guess, expected=spec.expected)
    else:
        with blend_context(spec.name if spec.s == 1.0 else None, spec.s if spec.s > 0 else 0.0):
            t = solve_tea(spec.inertia, n, spec.bias, expected=spec.expected)
    model = lin.design_point(spec.inertia, t.theta, n, model=s.model, drf_mode=s.drf_mode)
    res = sector_design(model.A, model.B, model.scales, s)
    if s.robust is not None:
        res = with_robust_gain(res, model.A, model.B, model.scales, spec.inertia, spec.bias, t.theta, s, s.robust)
    return PointDesign(spec, t, model, res)


def sector_design(A, B, scales, s: DesignSettings):
    """The design of one linear model by the route of the settings ``s`` (``s.method``:
    :mod:`acmm.design.methods`; R, Q0, sector, Riccati solver, tolerances, orbital rate
    ``s.orbit_rate``) — the one call the pipeline, the sweep's redesign and the report's errata
    evidence share.

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s.
    B : (N, 3) array
        Control input matrix, state units per ft·lbf.
    scales : (N,) array
        Nominal state magnitudes, in the units of each state.
    s : DesignSettings
        The design settings.

    Returns
    -------
    acmm.design.methods.PointGain
        The verified design.
    """
    return s.method.design(A, B, scales, s)


def fit_schedule(theta2: np.ndarray, gains: np.ndarray, order: int = 2, form: str = "polynomial") -> ScheduleFit:
    """Least-squares polynomial fit of every gain element versus θ2* (ch. 5.3).

    Parameters
    ----------
    theta2 : (P,) array
        Pitch TEA of each design point, rad.
    gains : (P, 3, 24) array
        LQR gains per point, units of K.
    order : int
        Polynomial order (2 in the report); reduced to P−1 when there are fewer points.
    form : {"polynomial", "table"}
        Which form :meth:`ScheduleFit.gain` evaluates; the polynomial and its residuals are
        computed in both cases, for the record.

    Returns
    -------
    ScheduleFit
        The fitted schedule with its residuals.
    """
    theta2 = np.asarray(theta2, float)
    gains = np.asarray(gains, float)
    p = theta2.size
    order = min(order, p - 1)
    vander = theta2[:, None] ** np.arange(order + 1)[None, :]
    coef, *_ = np.linalg.lstsq(vander, gains.reshape(p, -1), rcond=None)
    return ScheduleFit(coef.reshape(order + 1, 3, -1), theta2, gains, form)


def check_schedule(fit: ScheduleFit, points: list[PointDesign], s: DesignSettings) -> ScheduleCheck:
    """Sector margin of the scheduled gain at each design point and each blend midpoint.

    Parameters
    ----------
    fit : ScheduleFit
        The schedule.
    points : list of PointDesign
        The design points.
    s : DesignSettings
        The design settings (sector, orbital rate, design model).

    Returns
    -------
    ScheduleCheck
        Margins and largest pole real parts, units of n.
    """
    n = s.orbit_rate
    rows = []                           # (name, θ2*, kind, worst margin, largest Re λ), units of n

    def _check(name, model, theta2, kind):
        poles = np.linalg.eigvals(model.A - model.B @ fit.gain(theta2))
        margin = np.min(sector_lqr.sector_margin(poles, n, s.sector.sigma, s.sector.half_angle_deg))
        rows.append((name, theta2, kind, margin, np.max(poles.real) / n))

    for p in points:
        _check(p.spec.name, p.model, p.tea.theta[1], "design point")
    blended = sorted((p for p in points if np.isfinite(p.spec.s)), key=lambda p: p.spec.s)
    for a, b in zip(blended, blended[1:]):
        spec = PointSpec(f"mid_{0.5 * (a.spec.s + b.spec.s):.3f}", 0.5 * (a.spec.inertia + b.spec.inertia),
                         0.5 * (a.spec.bias + b.spec.bias), 0.5 * (a.spec.s + b.spec.s))
        t = solve_tea_near(spec.inertia, n, spec.bias, 0.5 * (a.tea.theta + b.tea.theta))
        model = lin.design_point(spec.inertia, t.theta, n, model=s.model, drf_mode=s.drf_mode)
        _check(spec.name, model, t.theta[1], "midpoint")
    names, th2, kinds, margins, max_real = zip(*rows)
    return ScheduleCheck(list(names), np.array(th2), np.array(margins), list(kinds), np.array(max_real))

