"""The design pipeline on explicit arguments: design points → sector LQR each → schedule → checks.

:func:`design_schedule` is what :func:`acmm.stages.runners.compute_design` runs for a config and what the
sweep's redesign runs for a perturbed plant: it takes :class:`acmm.design.schedule.PointSpec` s and the
settings objects of :mod:`acmm.design.settings`, never a Config.

Each point: TEA (eqs 4.1–4.3), design model (eq 4.46) and sector LQR (report ch. 5.2, Fig 5.2,
eqs 5.2–5.4); then the gain schedule and its checks (ch. 5.3).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
import numpy as np

from acmm.design import schedule as sch
from acmm.design.path_check import check_path, path_models
from acmm.design.schedule_points import PointSpec
from acmm.design.schedule_shifted_lqr import refit_shifted_lqr
from acmm.design.settings import DesignSettings, ScheduleSettings
from acmm_qpp.errors import ConfigError


@dataclass(frozen=True)
class Refinement:
    """What the table schedule's refinement did (``schedule.refine_points``).

    Attributes
    ----------
    added : int
        Table nodes added between the levels.
    rounds : int
        Bisection rounds (each designs the midpoints of every interval that failed).
    limit : int
        The most nodes it could add.
    margin : float
        The sector margin asked of every path TEA, units of n.
    met : bool
        Every path TEA has that margin with the final table.
    """

    added: int
    rounds: int
    limit: int
    margin: float
    met: bool


@dataclass
class DesignedSchedule:
    """Point designs, the fitted schedule and its checks (None with a single point).

    Attributes
    ----------
    points : list of acmm.design.schedule.PointDesign
        The design of every point.
    fit : acmm.design.schedule.ScheduleFit or None
        The fitted schedule.
    check : acmm.design.schedule.ScheduleCheck or None
        The schedule at the design points and blend midpoints.
    path_check : acmm.design.path_check.PathCheck or None
        The schedule along the path (``schedule.n_check``).
    refinement : Refinement or None
        What the refinement of a table schedule did (None: not asked for).
    """

    points: list            # list[acmm.design.schedule.PointDesign]
    fit: object             # acmm.design.schedule.ScheduleFit or None
    check: object           # acmm.design.schedule.ScheduleCheck or None
    path_check: object      # acmm.design.path_check.PathCheck or None
    refinement: Refinement | None = None


def design_schedule(specs: list, s: DesignSettings, sched: ScheduleSettings | None,
                    progress=None, map_points=map) -> DesignedSchedule:
    """Design every point of ``specs`` with settings ``s`` and fit the schedule ``sched``
    (when there are ≥ 2 points); ``progress(name)`` is called after each point.

    The points are independent: ``map_points(fn, specs)`` designs them (the built-in ``map`` in
    this process, or a process pool's map-like callable from the stage, as scipy's ``workers``),
    and must yield the results in the order of ``specs``; each point's result does not depend on
    where it was computed.

    Parameters
    ----------
    specs : list of acmm.design.schedule.PointSpec
        The design points.
    s : DesignSettings
        The design settings.
    sched : ScheduleSettings or None
        The schedule settings (None: order 2 polynomial, no path check).
    progress : callable or None
        Called with each point's name after its design.
    map_points : callable, optional
        ``map_points(fn, specs)`` → iterable of ``fn(spec)`` in order (default: ``map``).

    Returns
    -------
    DesignedSchedule
        The point designs, the schedule and its checks.

    Raises
    ------
    ConfigError
        A schedule whose design points are all one station, or all at one pitch TEA.
    """
    # (a blend of a station with itself differs from it only by rounding)
    if len(specs) >= 2 and all(np.allclose(p.inertia, specs[0].inertia, rtol=1e-12, atol=0)
                               and np.allclose(p.bias, specs[0].bias, rtol=1e-12, atol=1e-300) for p in specs[1:]):
        raise ConfigError(f"schedule: the {len(specs)} design points all have the pitch TEA of one station "
                          "(is schedule.to the same station as the config itself?): a gain schedule in θ2* "
                          "needs stations whose TEAs differ")
    points = []
    # TEA, model and sector LQR (or regional LMI) of each point (ch. 5.2)
    for spec, point in zip(specs, map_points(partial(sch.design_one, s=s), specs)):
        points.append(point)
        if progress is not None:
            progress(spec.name)
    if len(points) < 2:
        return DesignedSchedule(points, None, None, None)
    path = path_models(points, s, sched.n_check) if sched is not None else None
    refinement = None
    if path is not None and sched.refine_points > 0 and sched.form == "table":
        points, refinement = _refine(points, s, sched, path, map_points, progress)
    fit = _schedule(points, s, sched, path)
    check = sch.check_schedule(fit, points, s)
    path_check = (None if path is None else
                  check_path(fit.gain, path, s.orbit_rate, s.sector.sigma, s.sector.half_angle_deg))
    return DesignedSchedule(points, fit, check, path_check, refinement)


def _refine(points: list, s: DesignSettings, sched: ScheduleSettings, path, map_points, progress):
    """Table nodes added where the scheduled loop leaves the sector along ``path`` (a table is
    linear in θ2* between nodes that are each in the sector, the loop between them need not be).

    Each round designs a node at the middle s of every blend interval holding a path TEA below
    ``sched.refine_margin`` (worst first, TEA from the neighbours' mean), until none fails,
    ``sched.refine_points`` were added or no failing interval lies on the blend.  The nodes are
    gains, not levels (``PointSpec.level``), returned among the blend's points in the order of s.
    """
    n = s.orbit_rate
    start = next(p.spec for p in points if p.spec.s == 0.0)
    end = next(p.spec for p in points if p.spec.s == 1.0)
    added = rounds = 0
    while True:
        fit = _schedule(points, s, sched, None)
        pc = check_path(fit.gain, path, n, s.sector.sigma, s.sector.half_angle_deg, disk=False)
        bad = ~(pc.margin >= sched.refine_margin)          # NaN (a failed eigenvalue) fails
        if not bad.any() or added >= sched.refine_points:
            break
        nodes = sorted(points, key=lambda p: p.tea.theta[1])
        x = np.array([p.tea.theta[1] for p in nodes])
        where = np.clip(np.searchsorted(x, pc.theta2[bad]) - 1, 0, len(x) - 2)
        worst = {}
        for k, m in zip(where, pc.margin[bad]):
            worst[int(k)] = min(worst.get(int(k), np.inf), float(np.nan_to_num(m, nan=-np.inf)))
        split = [k for k in sorted(worst, key=lambda k: (worst[k], k))
                 if np.isfinite(nodes[k].spec.s) and np.isfinite(nodes[k + 1].spec.s)
                 and abs(nodes[k + 1].spec.s - nodes[k].spec.s) > 1e-9]
        split = split[:sched.refine_points - added]
        if not split:
            break
        specs = []
        for k in split:
            a, b = nodes[k], nodes[k + 1]
            sm = 0.5 * (a.spec.s + b.spec.s)
            specs.append(PointSpec(f"node_s{sm:.6f}", (1 - sm) * start.inertia + sm * end.inertia,
                                   (1 - sm) * start.bias + sm * end.bias, sm,
                                   0.5 * (a.tea.theta + b.tea.theta), level=False))
        for spec, point in zip(specs, map_points(partial(sch.design_one, s=s), specs)):
            points = points + [point]
            if progress is not None:
                progress(spec.name)
        added += len(specs)
        rounds += 1
    # the blend's points in the order of s (θ2* monotonic along it, as a table is read), the named
    # points after them
    blend = sorted((p for p in points if np.isfinite(p.spec.s)), key=lambda p: p.spec.s)
    points = blend + [p for p in points if not np.isfinite(p.spec.s)]
    return points, Refinement(added, rounds, sched.refine_points, sched.refine_margin, not bad.any())


def _schedule(points: list, s: DesignSettings, sched: ScheduleSettings | None, path):
    """The gain schedule of ``points`` (ch. 5.3): least squares (or the table look-up), then, for
    ``schedule.fit: shifted_lqr``, the converged quadratic on the path's models ``path``."""
    gains = np.array([p.gain.K for p in points])
    teas = np.array([p.tea.theta for p in points])
    if np.ptp(teas[:, 1]) < 1e-6:
        raise ConfigError(f"schedule: the {len(points)} design points all have the pitch TEA "
                          f"{np.degrees(teas[0, 1]):.4g} deg: a gain schedule in θ2* needs stations whose TEAs "
                          "differ (is schedule.to the same station as the config itself?)")
    fit = sch.fit_schedule(teas[:, 1], gains, sched.order if sched else 2,
                           sched.form if sched else "polynomial")
    if sched is None or sched.fit != "shifted_lqr" or fit.form != "polynomial" or path is None:
        return fit
    nx = path.A.shape[1]
    q0 = s.q0_weight(nx)
    return refit_shifted_lqr(fit, path, s.orbit_rate, np.zeros((nx, nx)) if q0 is None else q0,
                             s.R * np.eye(path.B.shape[2]))
