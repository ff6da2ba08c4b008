"""The design stage: TEA → design model (eqs 4.46–4.47) → sector LQR per design point
(ch. 5.2) → gain schedule (ch. 5.3), its ``design.h5`` and the reuse of a design already written.

Split from :mod:`acmm.stages` (issue 12), which re-exports these names.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acmm.config import Config
from acmm.stage_common import _as_config, _define_units, _in_system
from common.outputs import owns_outputs
from common.results import write_h5
from common.runlock import locked_stage
from acmm.design_file import _stored_digest, _unit_system, load_design_table, table_sha256  # noqa: F401

AXES = ["roll", "pitch", "yaw"]


# ---------------------------------------------------------------------------------------------
# design: TEA → linearize → sector LQR per point → schedule
# ---------------------------------------------------------------------------------------------
@dataclass
class DesignTable:
    """What a simulation needs from a design, as arrays (one row per design point).

    Attributes
    ----------
    names : list of str
        Design point names.
    inertia : (P, 3, 3) array
        Inertia per point, slug·ft².
    bias : (P, 3) array
        Bias torque per point, ft·lbf.
    tea : (P, 3) array
        TEA per point, rad.
    gain : (P, 3, 24) array
        LQR gain K per point (u = −K x), ft·lbf per state unit.
    coef : (order+1, 3, 24) array or None
        Schedule coefficients, lowest power first (units of K per rad^k), or None without a
        schedule.
    design_hash : str
        :func:`design_hash` of the config it was designed from.
    form : str
        Schedule form (:func:`acmm.schedule.schedule_gain`), ``"polynomial"`` by default.
    """

    names: list
    inertia: np.ndarray      # (P, 3, 3) slug·ft²
    bias: np.ndarray         # (P, 3) ft·lbf
    tea: np.ndarray          # (P, 3) rad
    gain: np.ndarray         # (P, 3, 24) LQR gains
    coef: np.ndarray | None  # (order+1, 3, 24) schedule coefficients, or None
    design_hash: str
    form: str = "polynomial"

    def scheduled_gain(self, k: int) -> np.ndarray:
        """Gain in use at point k: the schedule evaluated at its TEA when there is one, else
        the point's LQR gain.

        Parameters
        ----------
        k : int
            Design point index.

        Returns
        -------
        (3, 24) array
            Gain, ft·lbf per state unit.
        """
        return self.gain_at(self.tea[k, 1], k)

    def gain_at(self, theta2: float, k: int) -> np.ndarray:
        """The schedule at pitch TEA ``theta2`` (rad); without a schedule, point k's LQR gain.

        Parameters
        ----------
        theta2 : float
            Pitch TEA θ2*, rad.
        k : int
            Design point whose LQR gain is used when there is no schedule.

        Returns
        -------
        (3, 24) array
            Gain K(θ2*) of the schedule of ch. 5.3, ft·lbf per state unit.
        """
        from acmm.schedule import schedule_gain

        if self.coef is None:
            return self.gain[k]
        return schedule_gain(self.form, self.coef, self.tea[:, 1], self.gain, theta2)


@dataclass
class DesignResult:
    """A config's design: point designs, the schedule and its checks, and the table.

    Attributes
    ----------
    config : acmm.config.Config
        The validated config.
    points : list of acmm.schedule.PointDesign
        Sector LQR design per point (ch. 5.2).
    fit : acmm.schedule.ScheduleFit or None
        The fitted gain schedule (ch. 5.3); None with a single point.
    check : acmm.schedule.ScheduleCheck or None
        The schedule checked at the design points and blend midpoints.
    table : DesignTable
        The arrays a simulation needs.
    wall_time : float
        Design wall time, s.
    path_check : acmm.path_check.PathCheck or None
        The schedule checked along the path (``schedule.n_check``).
    """

    config: Config
    points: list
    fit: object
    check: object
    table: DesignTable
    wall_time: float
    path_check: object = None

    def fastest_over_n(self) -> np.ndarray:
        """Per design point, the fastest closed-loop pole's decay rate max(−Re s) divided by n.

        Returns
        -------
        (P,) array
            max(−Re s) / n, dimensionless.
        """
        return np.array([np.max(-p.lqr.poles.real) / self.config.orbit_rate for p in self.points])

    def off_branch(self):
        """The first blend point whose TEA is not on the branch of equilibria continued from the
        blend's start (:func:`acmm.schedule_points.off_branch_point`), else None.

        Returns
        -------
        acmm.schedule_points.BranchJump or None
            The point, its TEA and the branch's there, rad.
        """
        from acmm.schedule_points import off_branch_point

        return off_branch_point([p.spec for p in self.points], [p.tea.theta for p in self.points],
                                self.config.orbit_rate)

    def worst_check_index(self) -> int | None:
        """Index of the schedule check with the smallest sector margin (None without a schedule).

        Returns
        -------
        int or None
            Index into ``check.margin``.
        """
        return None if self.check is None else int(np.argmin(self.check.margin))


def design_hash(cfg: Config) -> str:
    """Hash of the design-relevant part of a config (inertia, n, disturbance, design, schedule).

    Parameters
    ----------
    cfg : acmm.config.Config
        The config.

    Returns
    -------
    str
        :func:`common.results.config_hash` of those sections.
    """
    import json

    from common.results import config_hash

    d = cfg.model_dump(mode="json")
    keys = ("inertia", "orbit_rate", "disturbance", "design", "schedule")
    return config_hash(json.dumps({k: d[k] for k in keys}, sort_keys=True))


def compute_design(config, progress=None, on_points=None, on_fit=None, fork: bool = False) -> DesignResult:
    """Design every point of a config and fit the schedule (when there are ≥ 2 points);
    ``on_points``/``on_fit``: see :func:`acmm.design_core.design_schedule`.

    The config is read here once (:func:`acmm.settings.design_settings`,
    :func:`acmm.schedule.point_specs`); the core :func:`acmm.design_core.design_schedule` gets
    only explicit arguments.

    Parameters
    ----------
    config : acmm.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    progress : callable, optional
        ``progress(name)``, called after each design point.
    on_points : callable, optional
        ``on_points(points)``, called with the list of :class:`acmm.schedule.PointDesign` once
        every point's sector LQR (ch. 5.2) is designed.
    on_fit : callable, optional
        ``on_fit(points, fit)``, called with the point designs and the final
        :class:`acmm.schedule.ScheduleFit` (ch. 5.3) before its checks; not called with fewer
        than 2 points.
    fork : bool, optional
        Design half the points and solve the path's models in a forked child meanwhile
        (``fork`` of :func:`acmm.design_core.design_schedule`; the same numbers).

    Returns
    -------
    DesignResult
        The design.
    """
    import time

    from acmm import schedule as sch
    from acmm.design_core import design_schedule
    from acmm.settings import design_settings, schedule_settings

    cfg = _as_config(config)
    t0 = time.perf_counter()
    ds = design_schedule(sch.point_specs(cfg), design_settings(cfg), schedule_settings(cfg), progress,
                         on_points, on_fit, fork=fork)
    table = design_table(ds.points, ds.fit, design_hash(cfg))
    return DesignResult(cfg, ds.points, ds.fit, ds.check, table, time.perf_counter() - t0, ds.path_check)


def design_table(points, fit, design_hash: str) -> DesignTable:
    """The :class:`DesignTable` of point designs and their schedule fit (None: one point).

    Parameters
    ----------
    points : list of acmm.schedule.PointDesign
        Point designs.
    fit : acmm.schedule.ScheduleFit or None
        Their schedule.
    design_hash : str
        Hash of the config they come from (:func:`design_hash`).

    Returns
    -------
    DesignTable
        The arrays (report units).
    """
    return DesignTable([p.spec.name for p in points], np.array([p.spec.inertia for p in points]),
                       np.array([p.spec.bias for p in points]), np.array([p.tea.theta for p in points]),
                       np.array([p.lqr.K for p in points]),
                       None if fit is None else fit.coef, design_hash,
                       "polynomial" if fit is None else fit.form)


@locked_stage(_as_config)
@owns_outputs("design", lambda c: _as_config(c))
def run_design(config, progress=None, figures: bool | None = None) -> tuple[DesignResult, Path]:
    """Design and write ``runs/<name>/design.h5`` plus the gain-schedule and pole-map figures
    (:mod:`acmm.design_output` builds both).

    Parameters
    ----------
    config : acmm.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    progress : callable, optional
        ``progress(name)``, called after each design point.
    figures : bool, optional
        Write the figures (default: ``output.figures``).

    Returns
    -------
    tuple
        (:class:`DesignResult`, pathlib.Path of ``design.h5``).
    """
    from acmm import design_output as out
    from acmm.stage_common import FIGURE_WARM
    from common import figure_worker
    from acmm.settings import design_settings

    cfg = _as_config(config)
    want_figures = cfg.output.figures if figures is None else figures
    s, run_dir = design_settings(cfg), cfg.run_dir()
    with figure_worker.session(want_figures, FIGURE_WARM):
        if want_figures:       # figures handed to the worker as their data is ready
            out.prepare_design_figures(s, cfg.output.units)
            r = compute_design(cfg, progress, lambda pts: out.pole_map_figure(pts, s, run_dir),
                               lambda pts, fit: out.gain_figure(pts, fit, s, run_dir, cfg.output.units),
                               fork=True)
            out.path_figures(r.path_check, s, run_dir)
        else:
            r = compute_design(cfg, progress, fork=True)
        pts = out.point_items(r.points)
        items = out.table_items(r, pts)
        if r.fit is not None:
            items["schedule"] = out.schedule_items(r)
        items = _define_units(_in_system(items, cfg, out.unit_roles(pts, r.fit is not None)), cfg.orbit_rate)
        path = write_h5(cfg.run_dir() / "design.h5", items, cfg.to_yaml(),
                        {"stage": "design", "design_hash": r.table.design_hash, "n_points": len(r.points),
                         "schedule_form": r.table.form, "table_sha256": _stored_digest(items, cfg.output.units)})
    return r, path


def design_for(cfg: Config, progress=None, figures: bool | None = None) -> tuple[DesignTable, str]:
    """The design of a config: reused from ``design.h5`` when its hash matches, else computed.

    Parameters
    ----------
    cfg : acmm.config.Config
        The config.
    progress : callable, optional
        ``progress(name)``, called after each design point when designing.
    figures : bool, optional
        Write the design figures when designing (default: ``output.figures``).

    Returns
    -------
    tuple
        (:class:`DesignTable`, a note saying whether it was reused or designed).
    """
    path = cfg.run_dir() / "design.h5"
    want = design_hash(cfg)
    if path.is_file():          # a regular file (a FIFO or a device there would block or never end)
        try:
            table = load_design_table(path)
            if table.design_hash == want and _unit_system(path) == cfg.output.units:   # one system per run folder
                return table, f"reused {path}"
        except (OSError, KeyError, ValueError):
            pass
    r, path = run_design(cfg, progress, figures)
    if cfg.output.units != "imperial":
        # the table as a later run reuses it: converted to SI and back, so that a simulation is
        # the same bit for bit whether its design was just made or read from design.h5
        return load_design_table(path), f"designed, wrote {path}"
    return r.table, f"designed, wrote {path}"
