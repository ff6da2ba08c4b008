"""The design pipeline on explicit arguments: design points → sector LQR each → schedule → checks.

:func:`design_schedule` is what :func:`acmm.stages.compute_design` runs for a config and what the
sweep's redesign runs for a perturbed plant: it takes :class:`acmm.schedule.PointSpec` s and the
settings objects of :mod:`acmm.settings`, never a Config.

Each point: TEA (eqs 4.1–4.3), design model (eq 4.46) and sector LQR (report ch. 5.2, Fig 5.2,
eqs 5.2–5.4); then the gain schedule and its checks (ch. 5.3).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm import schedule as sch
from acmm.path_check import check_path, path_models, path_models_from_specs
from acmm.schedule_refit import REFIT_DEFAULTS, refit_closed_loop
from acmm.settings import DesignSettings, ScheduleSettings
from common.forked import ForkedCall


@dataclass
class DesignedSchedule:
    """Point designs, the fitted schedule and its checks (None with a single point).

    Attributes
    ----------
    points : list of acmm.schedule.PointDesign
        The design of every point.
    fit : acmm.schedule.ScheduleFit or None
        The fitted schedule.
    check : acmm.schedule.ScheduleCheck or None
        The schedule at the design points and blend midpoints.
    path_check : acmm.path_check.PathCheck or None
        The schedule along the path (``schedule.n_check``).
    """

    points: list            # list[acmm.schedule.PointDesign]
    fit: object             # acmm.schedule.ScheduleFit or None
    check: object           # acmm.schedule.ScheduleCheck or None
    path_check: object      # acmm.path_check.PathCheck or None


def design_schedule(specs: list, s: DesignSettings, sched: ScheduleSettings | None,
                    progress=None, on_points=None, on_fit=None, fork: bool = False) -> DesignedSchedule:
    """Design every point of ``specs`` with settings ``s`` and fit the schedule ``sched``
    (when there are ≥ 2 points); ``progress(name)`` is called after each point,
    ``on_points(points)`` once they are all designed and ``on_fit(points, fit)`` once the
    schedule is final (the stage hands figures to its figure worker meanwhile).

    Parameters
    ----------
    specs : list of acmm.schedule.PointSpec
        The design points.
    s : DesignSettings
        The design settings.
    sched : ScheduleSettings or None
        The schedule settings (None: order 2 polynomial, no path check).
    progress : callable or None
        Called with each point's name after its design.
    on_points : callable or None
        Called with the list of point designs once all are designed.
    on_fit : callable or None
        Called with the point designs and the final :class:`acmm.schedule.ScheduleFit`
        (before its checks; not called with fewer than 2 points).
    fork : bool, optional
        Solve the path's models in a forked child while the points are designed
        (:class:`common.forked.ForkedCall`; the same numbers).  For a command run on its own,
        not for a process pool's worker.

    Returns
    -------
    DesignedSchedule
        The point designs, the schedule and its checks.
    """
    models = None
    if fork and sched is not None and len(specs) >= 2:
        models = ForkedCall(path_models_from_specs, list(specs), s, sched.n_check)
    try:
        points = _design_points(specs, s, progress, on_points)
        fit = check = path_check = None
        if len(points) >= 2:
            fit, path = _schedule(points, s, sched, models, on_fit)
            check = sch.check_schedule(fit, points, s)
            if path is not None:
                path_check = check_path(fit.gain, path, s.orbit_rate, s.sector.sigma,
                                        s.sector.half_angle_deg)
    finally:
        if models is not None:
            models.cancel()
    return DesignedSchedule(points, fit, check, path_check)


def _design_points(specs: list, s: DesignSettings, progress, on_points) -> list:
    """The sector LQR of every point (ch. 5.2), with the callbacks of :func:`design_schedule`."""
    points = []
    for spec in specs:
        points.append(sch.design_one(spec, s))
        if progress is not None:
            progress(spec.name)
    if on_points is not None:
        on_points(points)
    return points


def _schedule(points: list, s: DesignSettings, sched: ScheduleSettings | None, models, on_fit):
    """The schedule of ``points`` (least squares, then the closed-loop refit when configured)
    and the path's models (from the child ``models`` when one was forked, else solved here: the
    refit's first, the others after ``on_fit``).  Returns (fit, path models or None)."""
    gains = np.array([p.lqr.K for p in points])
    teas = np.array([p.tea.theta for p in points])
    if np.ptp(teas[:, 1]) < 1e-6:
        from common.errors import ConfigError

        raise ConfigError(f"schedule: the {len(points)} design points all have the pitch TEA "
                          f"{np.degrees(teas[0, 1]):.4g} deg: a gain schedule in θ2* needs stations whose TEAs "
                          "differ (is schedule.to the same station as the config itself?)")
    fit = sch.fit_schedule(teas[:, 1], gains, sched.order if sched else 2,
                           sched.form if sched else "polynomial")
    path = models.result() if models is not None and models.forked else None
    if sched is not None and sched.fit == "closed_loop" and fit.form == "polynomial":
        if path is not None:
            fit = refit_closed_loop(fit, path, s.orbit_rate, half_angle_deg=s.sector.half_angle_deg,
                                    **REFIT_DEFAULTS)
        else:
            fit = _refit(fit, points, s, sched.n_check)
    if on_fit is not None:
        on_fit(points, fit)
    if path is None and sched is not None:
        path = path_models(points, s, sched.n_check)
    return fit, path


def _refit(fit, points: list, s: DesignSettings, n_check: int):
    """:func:`acmm.schedule_refit.refit_closed_loop` with :data:`REFIT_DEFAULTS` on the path's
    every ``REFIT_DEFAULTS["every"]``-th model (the ends included), solved before the others:
    the schedule (and its figure) is final ~0.1 s sooner, and the result is the same bit for bit
    as refitting on the whole path with that ``every``."""
    every = REFIT_DEFAULTS["every"]
    idx = sorted(set(range(0, n_check, max(1, every))) | {n_check - 1})
    sub = path_models(points, s, n_check, indices=idx)
    if sub is None:
        return fit
    return refit_closed_loop(fit, sub, s.orbit_rate, half_angle_deg=s.sector.half_angle_deg,
                             **{**REFIT_DEFAULTS, "every": 1})
