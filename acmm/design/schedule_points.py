"""Design points of a gain schedule (CR-185644 ch. 5.3): the configurations a schedule is designed at.

A design point is a station configuration (inertia, bias) on the blend
I(s) = (1−s)·I_start + s·I_to (bias blended alike) or a named configuration.  The blend's points
are spaced evenly in s or in pitch TEA θ2* (eqs 4.1–4.3, tracked by Newton continuation).
:func:`point_specs` is where a config's inertias and biases become :class:`PointSpec` s; the rest
takes arrays and settings objects.
"""
from __future__ import annotations

from contextlib import contextmanager, suppress
from dataclasses import dataclass

import numpy as np

from acmm.model.tea import NoEquilibriumError, resolve_bias, solve_tea, solve_tea_near
from acmm_qpp.errors import ConvergenceError
from acmm.design.settings import schedule_settings

#: Values of s, evenly spaced, on which the TEA is continued along a blend (the TEA spacing, the path
#: check and the branch check track the same blend).
N_TRACK = 81


@dataclass(frozen=True)
class PointSpec:
    """A station configuration to design for: name, inertia (slug·ft²), bias (ft·lbf), blend s.

    Attributes
    ----------
    name : str
        Name of the configuration.
    inertia : (3, 3) array
        Inertia matrix, slug·ft².
    bias : (3,) array
        Bias torque, ft·lbf.
    s : float
        Blend parameter, dimensionless (NaN for a named point off the blend).
    theta_guess : (3,) array or None
        Starting guess for its TEA, rad; None: solve from scratch.
    expected : (3,) array or None
        The TEA its config asks for (``bias_from_tea``, rad): the ``expected`` of
        :func:`acmm.model.tea.solve_tea`; None: the continuation's.
    level : bool
        The configuration is a level of the stair-case (ch. 6); False for a table node that the
        schedule's refinement added between levels (``schedule.refine_points``).
    """

    name: str
    inertia: np.ndarray
    bias: np.ndarray
    s: float = float("nan")
    theta_guess: np.ndarray | None = None
    expected: np.ndarray | None = None
    level: bool = True


def _blend_points(start: PointSpec, end: PointSpec, s_pts, guesses=None) -> list[PointSpec]:
    """The configurations at the blend parameters ``s_pts`` (both ends included) on
    I(s) = (1−s)·I_start + s·I_end, bias blended alike; TEA guesses ``guesses`` (rad) or none; the
    ends keep their ``expected`` TEA."""
    last = len(s_pts) - 1
    return [PointSpec(start.name if k == 0 else end.name if k == last else f"blend_{s:.3f}",
                      (1 - s) * start.inertia + s * end.inertia, (1 - s) * start.bias + s * end.bias, float(s),
                      None if guesses is None else guesses[k],
                      start.expected if k == 0 else end.expected if k == last else None)
            for k, s in enumerate(s_pts)]


def tea_spaced_blend(start: PointSpec, end: PointSpec, n_points: int, n: float) -> list[PointSpec]:
    """``n_points`` blend configurations whose pitch TEAs are evenly spaced.

    The TEA is tracked along the blend by Newton continuation on :data:`N_TRACK` values of s (the
    physical branch, starting from the start configuration's TEA), then s is interpolated at
    evenly spaced θ2*.  Falls back to evenly spaced s when θ2*(s) is not monotonic.

    Parameters
    ----------
    start, end : PointSpec
        The configurations at s = 0 and s = 1.
    n_points : int
        Number of points including both ends.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    list of PointSpec
        The configurations, with their tracked TEA as ``theta_guess``.
    """
    s_grid = np.linspace(0.0, 1.0, N_TRACK)
    # (the design points and the path check of one design track the same blend: ~35 ms each, so it
    # is not remembered between them)
    thetas = np.array(list(_continue_blend(start, end, n, s_grid)))
    th2 = thetas[:, 1]
    d = np.diff(th2)
    if not (np.all(d > 0) or np.all(d < 0)):
        return _blend_points(start, end, np.linspace(0.0, 1.0, n_points))
    order = np.argsort(th2)
    targets = np.linspace(th2[0], th2[-1], n_points)
    s_pts = np.interp(targets, th2[order], s_grid[order])
    s_pts[0], s_pts[-1] = 0.0, 1.0
    return _blend_points(start, end, s_pts,
                         [np.array([np.interp(s, s_grid, thetas[:, i]) for i in range(3)]) for s in s_pts])


@contextmanager
def blend_context(end_name: str | None, s: float):
    """A missing equilibrium on the blend names where it is: the blend toward ``schedule.to``,
    at s, whose inertia and bias are (1 − s)·start + s·end (the bias in the message is that blend,
    not a bias the user wrote).

    Parameters
    ----------
    end_name : str or None
        Name of the blend's end station (None: not known where the error arises).
    s : float
        Blend parameter, dimensionless (0: the start, whose errors pass unchanged).

    Raises
    ------
    NoEquilibriumError
        The one raised inside, its message prefixed with the place on the blend.
    """
    try:
        yield
    except NoEquilibriumError as exc:
        if s > 0:
            raise NoEquilibriumError(f"on the blend toward schedule.to{f' ({end_name})' if end_name else ''} "
                                     f"at s = {s:.3g}, inertia and bias (1 − s)·start + s·end: {exc}",
                                     hint="reduce the bias of disturbance or of schedule.to (their blend must "
                                          "balance at every s), or give each as its bias_from_tea") from None
        raise


def _continue_blend(start: PointSpec, end: PointSpec, n: float, grid):
    """Yield the TEA (3,), rad, at each s of ``grid`` along the blend start → end, Newton-continued
    from the start's equilibrium; where the branch folds, the error is raised naming the blend
    (:func:`blend_context`)."""
    t = solve_tea(start.inertia, n, start.bias, expected=start.expected).theta
    for s in grid:
        with blend_context(end.name, s):
            t = solve_tea_near((1 - s) * start.inertia + s * end.inertia, n, (1 - s) * start.bias + s * end.bias,
                               t).theta
        yield t


def point_specs(cfg) -> list[PointSpec]:
    """Design points of a config: the blend start → ``schedule.to`` plus ``schedule.points``.

    Without a ``schedule`` section, the config's own configuration is the only point.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        A validated configuration.

    Returns
    -------
    list of PointSpec
        The design points.
    """
    n = cfg.orbit_rate

    def spec(name, inertia, disturbance, s=float("nan")):
        matrix = inertia.matrix()
        return PointSpec(name, matrix, resolve_bias(disturbance, matrix, n), s, expected=disturbance.requested_tea())

    start = spec(cfg.name, cfg.inertia, cfg.disturbance, 0.0)
    sch = cfg.schedule
    if sch is None:
        return [start]
    end = None if sch.to is None else spec(sch.to.name, sch.to.inertia, sch.to.disturbance, 1.0)
    extras = [spec(p.name, p.inertia, p.disturbance) for p in sch.points]
    return schedule_specs(start, end, extras, schedule_settings(cfg), n)


def schedule_specs(start: PointSpec, end: PointSpec | None, extras: list[PointSpec], sched, n: float
                   ) -> list[PointSpec]:
    """The design points: ``start`` alone, else the blend ``start`` → ``end`` (``sched.n_points``
    points spaced by ``sched.spacing``) followed by the named ``extras``.

    Parameters
    ----------
    start : PointSpec
        The config's own configuration (s = 0).
    end : PointSpec or None
        The end of the blend (s = 1), or None.
    extras : list of PointSpec
        Named extra points.
    sched : ScheduleSettings
        Schedule settings.
    n : float
        Orbital rate, rad/s.

    Returns
    -------
    list of PointSpec
        The design points.
    """
    specs = [start]
    if end is not None:
        if sched.spacing == "tea":
            specs = tea_spaced_blend(start, end, sched.n_points, n)
        else:
            specs = _blend_points(start, end, np.linspace(0.0, 1.0, sched.n_points))
    return specs + list(extras)


@dataclass(frozen=True)
class BranchJump:
    """A blend design point whose TEA is not on the branch of equilibria continued from the
    blend's start (:func:`off_branch_point`).

    Attributes
    ----------
    name : str
        The design point.
    s : float
        Its blend parameter, dimensionless.
    theta : (3,) array
        Its TEA, rad.
    branch : (3,) array or None
        Where the branch continued from the start is at that s, rad; None where that branch
        ends (folds) before reaching it.
    asked : bool
        Whether the point's TEA is the one its config asks for (``bias_from_tea``).
    """

    name: str
    s: float
    theta: np.ndarray
    branch: np.ndarray | None
    asked: bool


def off_branch_point(specs: list[PointSpec], thetas, n: float, tol: float = 1e-6) -> BranchJump | None:
    """The first blend point whose TEA lies off the branch continued from the blend's start.

    The points of a gain schedule (ch. 5.3) should lie on one branch of equilibria
    (eqs 4.1–4.3): the station moves along it as it is assembled.  A point solved on its own
    (blend spacing: each from LVLH; an end that asks for its TEA) can land on another branch
    where the blend crosses a fold; the points then jump and the schedule is fitted across the
    jump.  Here the branch is continued from the start over the :data:`N_TRACK` values of s of
    the TEA spacing and Newton-solved at each point's s.

    Parameters
    ----------
    specs : list of PointSpec
        The design points; those with a finite ``s`` form the blend.
    thetas : sequence of (3,) arrays
        Their TEAs, rad, in the order of ``specs``.
    n : float
        Orbital rate, rad/s.
    tol : float, optional
        Largest angle (rad) by which a point may differ from the branch.

    Returns
    -------
    BranchJump or None
        The first point off the branch, None when all are on it (or without a blend).
    """
    blend = [(sp, np.asarray(th, float)) for sp, th in zip(specs, thetas) if np.isfinite(sp.s)]
    if len(blend) < 2:
        return None
    grid = np.linspace(0.0, 1.0, N_TRACK)
    track = []
    with suppress(NoEquilibriumError, ConvergenceError):     # where the branch folds, the points before it are checked
        for t in _continue_blend(blend[0][0], blend[-1][0], n, grid):
            track.append(t)
    track = np.array(track).reshape(-1, 3)
    reach = grid[len(track) - 1] if len(track) else -1.0       # the last s the branch reaches
    for sp, th in blend:
        branch = None
        if sp.s <= reach + 1e-12:
            guess = np.array([np.interp(sp.s, grid[:len(track)], track[:, i]) for i in range(3)])
            with suppress(NoEquilibriumError, ConvergenceError):
                branch = solve_tea_near(sp.inertia, n, sp.bias, guess).theta
        if branch is None or np.max(np.abs((th - branch + np.pi) % (2 * np.pi) - np.pi)) > tol:
            return BranchJump(sp.name, float(sp.s), th, branch, sp.expected is not None)
    return None
