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
from acmm.design.path_check import check_path, path_models, path_models_from_specs
from acmm.design.schedule_refit import REFIT_DEFAULTS, refit_closed_loop
from acmm.design.settings import DesignSettings, ScheduleSettings
from acmm_qpp.forked import ForkedCall


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
                    progress=None, on_points=None, on_fit=None, fork: bool = False) -> DesignedSchedule:
    """Design every point of ``specs`` with settings ``s`` and fit the schedule ``sched``
    (when there are ≥ 2 points); ``progress(name)`` is called after each point,
    ``on_points(points)`` once they are all designed and ``on_fit(points, fit)`` once the
    schedule is final (the stage hands figures to its figure worker meanwhile).

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
    on_points : callable or None
        Called with the list of point designs once all are designed.
    on_fit : callable or None
        Called with the point designs and the final :class:`acmm.design.schedule.ScheduleFit`
        (before its checks; not called with fewer than 2 points).
    fork : bool, optional
        Design the second half of the points, then solve the path's models, in a forked child
        while this process designs the first half (:class:`acmm_qpp.forked.ForkedCall`; the same
        numbers bit for bit).  For a command run on its own, not for a process pool's worker.

    Returns
    -------
    DesignedSchedule
        The point designs, the schedule and its checks.
    """
    helper, first = (_fork_helper(specs, s, sched, progress) if fork else (None, len(specs)))
    try:
        points, path = _design_points(specs, first, helper, s, sched, progress, on_points)
        fit = check = path_check = None
        if len(points) >= 2:
            fit, path = _schedule(points, s, sched, path, on_fit)
            check = sch.check_schedule(fit, points, s)
            if path is not None:
                path_check = check_path(fit.gain, path, s.orbit_rate, s.sector.sigma,
                                        s.sector.half_angle_deg)
    finally:
        if helper is not None:
            helper.cancel()
    return DesignedSchedule(points, fit, check, path_check)


def _helper_part(specs: list, first: int, s: DesignSettings, n_check: int | None, progress=None):
    """What the forked helper computes: the designs of ``specs[first:]`` (the same code as in
    place, so the same numbers bit for bit) and the path's models (None without ``n_check``, or
    when solving them fails: they are then solved again in place, where the error is raised at
    the same step as without the helper).  Run in place (the helper failed), ``progress`` is
    called after each point."""
    points = []
    for spec in specs[first:]:
        points.append(sch.design_one(spec, s))
        if progress is not None:
            progress(spec.name)
    try:
        path = path_models_from_specs(specs, s, n_check) if n_check is not None else None
    except Exception:  # noqa: BLE001
        path = None
    return points, path


def _fork_helper(specs: list, s: DesignSettings, sched: ScheduleSettings | None, progress):
    """Fork the helper of :func:`design_schedule` (``fork=True``): it designs the second half of
    the points and then solves the path's models while this process designs the first half (if
    it fails, that half is designed here, with ``progress``).  Returns (the
    :class:`acmm_qpp.forked.ForkedCall` or None, index of the first point it designs)."""
    if len(specs) < 2:
        return None, len(specs)
    first = (len(specs) + 1) // 2
    helper = ForkedCall(_helper_part, list(specs), first, s, sched.n_check if sched is not None else None,
                        in_place=partial(_helper_part, progress=progress))
    return (helper, first) if helper.forked else (None, len(specs))


def _design_points(specs: list, first: int, helper, s: DesignSettings, sched: ScheduleSettings | None,
                   progress, on_points) -> tuple[list, object]:
    """The sector LQR of every point (ch. 5.2): ``specs[:first]`` here, the others by ``helper``
    (None: all here); with the callbacks of :func:`design_schedule`.  Returns (the point designs
    in the order of ``specs``, the path's models when the helper solved them, else None)."""
    points, path = [], None
    for spec in specs[:first]:
        points.append(sch.design_one(spec, s))
        if progress is not None:
            progress(spec.name)
    if helper is not None:
        if sched is not None and sched.fit == "closed_loop" and sched.form == "polynomial":
            import scipy.optimize  # noqa: F401  (the refit's SLSQP: imported while the helper finishes)
        rest, path = helper.result()
        points += rest
        if progress is not None and helper.from_child:        # (in place: called meanwhile)
            for p in rest:
                progress(p.spec.name)
    if on_points is not None:
        on_points(points)
    return points, path


def _schedule(points: list, s: DesignSettings, sched: ScheduleSettings | None, path, on_fit):
    """The schedule of ``points`` (least squares, then the closed-loop refit when configured)
    and the path's models (``path`` when the forked helper solved them, else solved here: the
    refit's first, the others after ``on_fit``).  Returns (fit, path models or None)."""
    gains = np.array([p.lqr.K for p in points])
    teas = np.array([p.tea.theta for p in points])
    if np.ptp(teas[:, 1]) < 1e-6:
        from acmm_qpp.errors import ConfigError

        raise ConfigError(f"schedule: the {len(points)} design points all have the pitch TEA "
                          f"{np.degrees(teas[0, 1]):.4g} deg: a gain schedule in θ2* needs stations whose TEAs "
                          "differ (is schedule.to the same station as the config itself?)")
    fit = sch.fit_schedule(teas[:, 1], gains, sched.order if sched else 2,
                           sched.form if sched else "polynomial")
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
    """:func:`acmm.design.schedule_refit.refit_closed_loop` with :data:`REFIT_DEFAULTS` on the path's
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
