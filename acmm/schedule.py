"""Quadratic gain schedules versus the TEA (CR-185644 ch. 5.3, Figs 5.3–5.26).

Design points lie on the blend I(s) = (1−s)·I_start + s·I_to (bias blended alike) and/or are
named configurations.  Each gets its TEA (eqs 4.1–4.3), its design model (eq 4.46) and a sector
LQR gain (ch. 5.2); every gain element is then fitted by a least-squares polynomial (order 2 in
the report) in the scheduling variable θ2* (pitch TEA, rad).  The scheduled gain is re-checked
on the local linear model at every design point and at the midpoints between them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm import linearize as lin
from acmm import lqr
from acmm.tea import TEA, resolve_bias, solve_tea


@dataclass(frozen=True)
class PointSpec:
    """A station configuration to design for: name, inertia (slug·ft²), bias (ft·lbf), blend s."""

    name: str
    inertia: np.ndarray
    bias: np.ndarray
    s: float = float("nan")


@dataclass
class PointDesign:
    """One design point: its TEA, design model and sector-LQR result."""

    spec: PointSpec
    tea: TEA
    model: lin.LinearModel
    lqr: object


@dataclass
class ScheduleFit:
    """K_ij(θ2*) = Σ_k coef[k, i, j]·θ2*^k (θ2* in rad), fitted by least squares.

    Attributes
    ----------
    coef : (order+1, 3, 24) array
        Polynomial coefficients, lowest power first; units of K per rad^k.
    variable : (P,) array
        Pitch TEA of each design point, rad.
    rms_residual : (3, 24) array
        RMS fit residual per element (units of K).
    rel_residual : (3, 24) array
        RMS residual relative to max |K_ij| over the points.
    """

    coef: np.ndarray
    variable: np.ndarray
    rms_residual: np.ndarray
    rel_residual: np.ndarray

    @property
    def order(self) -> int:
        return self.coef.shape[0] - 1

    def gain(self, theta2: float) -> np.ndarray:
        """Scheduled K (3×24) at pitch TEA ``theta2`` (rad)."""
        powers = theta2 ** np.arange(self.coef.shape[0])
        return np.tensordot(powers, self.coef, axes=1)


@dataclass
class ScheduleCheck:
    """Sector margins (units of n; > 0 means inside) of the scheduled gain on local models."""

    names: list[str]
    theta2: np.ndarray
    margin: np.ndarray
    kind: list[str] = field(default_factory=list)

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


def point_specs(cfg) -> list[PointSpec]:
    """Design points of a config: the blend start → ``schedule.to`` plus ``schedule.points``.

    Without a ``schedule`` section, the config's own configuration is the only point.
    """
    n = cfg.orbit_rate
    inertia = cfg.inertia.matrix()
    start = PointSpec(cfg.name, inertia, resolve_bias(cfg.disturbance, inertia, n), 0.0)
    sch = cfg.schedule
    if sch is None:
        return [start]
    specs = [start]
    if sch.to is not None:
        i_to = sch.to.inertia.matrix()
        end = PointSpec(sch.to.name, i_to, resolve_bias(sch.to.disturbance, i_to, n), 1.0)
        specs = blend_points(start, end, sch.n_points)
    for p in sch.points:
        i_p = p.inertia.matrix()
        specs.append(PointSpec(p.name, i_p, resolve_bias(p.disturbance, i_p, n)))
    return specs


def design_one(spec: PointSpec, cfg) -> PointDesign:
    """TEA, design model and sector LQR of one design point (config's ``design`` section)."""
    d = cfg.design
    n = cfg.orbit_rate
    t = solve_tea(spec.inertia, n, spec.bias)
    model = lin.design_point(spec.inertia, t.theta, n, model=d.model, drf_mode=d.drf_mode)
    res = lqr.sector_lqr(model.A, model.B, d.R * np.eye(3), n, sigma=d.sector.sigma,
                         half_angle_deg=d.sector.half_angle_deg,
                         Q0=d.Q0 * np.diag(1.0 / model.scales ** 2) if d.Q0 > 0 else None,
                         scale=model.scales, method=d.pole_method, riccati_method=d.riccati_method,
                         residual_tol=d.residual_tol)
    return PointDesign(spec, t, model, res)


def fit_schedule(theta2: np.ndarray, gains: np.ndarray, order: int = 2) -> ScheduleFit:
    """Least-squares polynomial fit of every gain element versus θ2* (ch. 5.3).

    Parameters
    ----------
    theta2 : (P,) array
        Pitch TEA of each design point, rad.
    gains : (P, 3, 24) array
        LQR gains per point.
    order : int
        Polynomial order (2 in the report); reduced to P−1 when there are fewer points.
    """
    theta2 = np.asarray(theta2, float)
    gains = np.asarray(gains, float)
    p = theta2.size
    order = min(order, p - 1)
    vander = theta2[:, None] ** np.arange(order + 1)[None, :]
    flat = gains.reshape(p, -1)
    coef, *_ = np.linalg.lstsq(vander, flat, rcond=None)
    resid = flat - vander @ coef
    rms = np.sqrt(np.mean(resid ** 2, axis=0)).reshape(3, -1)
    peak = np.max(np.abs(flat), axis=0).reshape(3, -1)
    rel = np.divide(rms, peak, out=np.zeros_like(rms), where=peak > 0)
    return ScheduleFit(coef.reshape(order + 1, 3, -1), theta2, rms, rel)


def check_schedule(fit: ScheduleFit, points: list[PointDesign], cfg) -> ScheduleCheck:
    """Sector margin of the scheduled gain at each design point and each blend midpoint."""
    d = cfg.design
    n = cfg.orbit_rate
    names, th2, margins, kinds = [], [], [], []

    def _check(name, model, theta2, kind):
        poles = np.linalg.eigvals(model.A - model.B @ fit.gain(theta2))
        names.append(name)
        th2.append(theta2)
        kinds.append(kind)
        margins.append(np.min(lqr.sector_margin(poles, n, d.sector.sigma, d.sector.half_angle_deg)))

    for p in points:
        _check(p.spec.name, p.model, p.tea.theta[1], "design point")
    blended = [p for p in points if np.isfinite(p.spec.s)]
    for a, b in zip(blended, blended[1:]):
        spec = PointSpec(f"mid_{0.5 * (a.spec.s + b.spec.s):.3f}", 0.5 * (a.spec.inertia + b.spec.inertia),
                         0.5 * (a.spec.bias + b.spec.bias), 0.5 * (a.spec.s + b.spec.s))
        t = solve_tea(spec.inertia, n, spec.bias)
        model = lin.design_point(spec.inertia, t.theta, n, model=d.model, drf_mode=d.drf_mode)
        _check(spec.name, model, t.theta[1], "midpoint")
    return ScheduleCheck(names, np.array(th2), np.array(margins), kinds)
