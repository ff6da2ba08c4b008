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
from acmm.design.schedule_refit import REFIT_DEFAULTS, refit_closed_loop
from acmm.design.settings import DesignSettings, ScheduleSettings
from acmm_qpp.errors import ConfigError


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
    """

    points: list            # list[acmm.design.schedule.PointDesign]
    fit: object             # acmm.design.schedule.ScheduleFit or None
    check: object           # acmm.design.schedule.ScheduleCheck or None
    path_check: object      # acmm.design.path_check.PathCheck or None


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
    fit = _schedule(points, s, sched, path)
    check = sch.check_schedule(fit, points, s)
    path_check = None
    if path is not None:
        path_check = check_path(fit.gain, path, s.orbit_rate, s.sector.sigma, s.sector.half_angle_deg)
    return DesignedSchedule(points, fit, check, path_check)


def _schedule(points: list, s: DesignSettings, sched: ScheduleSettings | None, path):
    """The gain schedule of ``points`` (ch. 5.3): least squares (or the table look-up), then the
    closed-loop refit on the path's models ``path`` when configured."""
    gains = np.array([p.gain.K for p in points])
    teas = np.array([p.tea.theta for p in points])
    if np.ptp(teas[:, 1]) < 1e-6:
        raise ConfigError(f"schedule: the {len(points)} design points all have the pitch TEA "
                          f"{np.degrees(teas[0, 1]):.4g} deg: a gain schedule in θ2* needs stations whose TEAs "
                          "differ (is schedule.to the same station as the config itself?)")
    fit = sch.fit_schedule(teas[:, 1], gains, sched.order if sched else 2,
                           sched.form if sched else "polynomial")
    if sched is not None and sched.fit == "closed_loop" and fit.form == "polynomial" and path is not None:
        fit = refit_closed_loop(fit, path, s.orbit_rate, half_angle_deg=s.sector.half_angle_deg,
                                **REFIT_DEFAULTS)
    return fit
