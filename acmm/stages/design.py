"""The design stage: TEA → design model (eqs 4.46–4.47) → sector LQR per design point
(ch. 5.2) → gain schedule (ch. 5.3), its ``design.h5`` and the reuse of a design already written.
"""
from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import h5py
import numpy as np

from acmm.io.config import Config
from acmm.stages.common import as_config, write_results
from acmm_qpp.outputs import stage
from acmm.stages.pool import pool_map, process_pool, stop_pool
from acmm_qpp.results import draw_figures, h5_text
from acmm.io.design_file import DesignTable, stored_table_digest, load_design_table
import json
import time
from acmm_qpp.provenance import config_hash
from acmm.design.design_core import design_schedule
from acmm.design.settings import design_settings, schedule_settings
from acmm.stages import design_output
from acmm.design.schedule_points import off_branch_point, point_specs


@dataclass
class DesignResult:
    """A config's design: point designs, the schedule and its checks, and the table.

    Attributes
    ----------
    config : acmm.io.config.Config
        The validated config.
    points : list of acmm.design.schedule.PointDesign
        Sector LQR design per point (ch. 5.2).
    fit : acmm.design.schedule.ScheduleFit or None
        The fitted gain schedule (ch. 5.3); None with a single point.
    check : acmm.design.schedule.ScheduleCheck or None
        The schedule checked at the design points and blend midpoints.
    table : DesignTable
        The arrays a simulation needs.
    wall_time : float
        Design wall time, s.
    path_check : acmm.design.path_check.PathCheck or None
        The schedule checked along the path (``schedule.n_check``).
    refinement : acmm.design.design_core.Refinement or None
        What the table's refinement did (``schedule.refine_points``; None: not asked for).
    """

    config: Config
    points: list
    fit: object
    check: object
    table: DesignTable
    wall_time: float
    path_check: object = None
    refinement: object = None

    def fastest_over_n(self) -> np.ndarray:
        """Per design point, the fastest closed-loop pole's decay rate max(−Re s) divided by n.

        Returns
        -------
        (P,) array
            max(−Re s) / n, dimensionless.
        """
        return np.array([np.max(-p.gain.poles.real) / self.config.orbit_rate for p in self.points])

    def off_branch(self):
        """The first blend point whose TEA is not on the branch of equilibria continued from the
        blend's start (:func:`acmm.design.schedule_points.off_branch_point`), else None.

        Returns
        -------
        acmm.design.schedule_points.BranchJump or None
            The point, its TEA and the branch's there, rad.
        """
        return off_branch_point([p.spec for p in self.points], [p.tea.theta for p in self.points],
                                self.config.orbit_rate)

    def unstable(self) -> str | None:
        """Where the scheduled closed loop is unstable, as one sentence (None: stable at every
        schedule check and every path TEA, or no schedule).

        Returns
        -------
        str or None
            E.g. ``the scheduled closed loop is UNSTABLE at mid_0.640 (midpoint; largest Re λ
            +0.020 n) and at 14 of 201 path TEAs, θ2* -30.10 ... -25.30 deg``.
        """
        parts = []
        c = self.check
        if c is not None and c.max_real.size and not np.all(c.max_real < 0):
            k = int(np.nanargmax(np.where(np.isnan(c.max_real), np.inf, c.max_real)))
            bad = int(np.sum(~(c.max_real < 0)))
            kind = f"{c.kind[k]}; " if c.kind else ""
            parts.append(f"at {c.names[k]} ({kind}largest Re λ {c.max_real[k]:+.3f} n"
                         + (f"; {bad} of {c.max_real.size} schedule checks unstable)" if bad > 1 else ")"))
        pc = self.path_check
        if pc is not None and pc.max_real.size and not np.all(pc.max_real < 0):
            bad = ~(pc.max_real < 0)                # NaN (a failed eigenvalue) counts as unstable
            th = np.degrees(pc.theta2[bad])
            parts.append(f"at {int(bad.sum())} of {bad.size} path TEAs, θ2* {th.min():+.2f} ... {th.max():+.2f} deg")
        return "the scheduled closed loop is UNSTABLE " + " and ".join(parts) if parts else None

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
    cfg : acmm.io.config.Config
        The config.

    Returns
    -------
    str
        :func:`acmm_qpp.provenance.config_hash` of those sections.
    """
    keys = {"inertia", "orbit_rate", "disturbance", "design", "schedule"}
    return config_hash(json.dumps(cfg.model_dump(mode="json", include=keys), sort_keys=True))


def _point_workers(pooled: bool, n_points: int) -> int:
    """Worker processes (1: in this process) designing ``n_points`` points: a ``pooled`` route's
    (:attr:`acmm.design.methods.PoleMethod.pooled`, the regional LMI's, seconds each) on a process pool
    of one worker per available CPU, at most one per point; the sector LQR's (about a second each),
    and any design inside a pool worker already (a sweep's, the report's) or in a process running
    other threads, in this process.  A point's result does not depend on where it is computed."""
    if not pooled or n_points < 2 or multiprocessing.parent_process() is not None:
        return 1
    if threading.active_count() > 1:        # (a terminal's progress bar, a notebook's kernel threads)
        return 1                            # forking beside other threads can deadlock the child
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(cpus, n_points))


def compute_design(config, progress=None) -> DesignResult:
    """Design every point of a config and fit the schedule (when there are ≥ 2 points).

    The config is read here once (:func:`acmm.design.settings.design_settings`,
    :func:`acmm.design.schedule.point_specs`); the core :func:`acmm.design.design_core.design_schedule` gets
    only explicit arguments.

    Parameters
    ----------
    config : acmm.io.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    progress : callable, optional
        ``progress(name)``, called after each design point.

    Returns
    -------
    DesignResult
        The design.

    Raises
    ------
    OutputError
        A worker process of the design pool died (killed, or out of memory; :func:`acmm.stages.pool.pool_map`).
    """

    cfg = as_config(config)
    t0 = time.perf_counter()
    specs, s = point_specs(cfg), design_settings(cfg)
    workers = _point_workers(s.method.pooled, len(specs))
    if workers <= 1:
        ds = design_schedule(specs, s, schedule_settings(cfg), progress)
    else:
        pool = process_pool(workers)
        try:
            ds = design_schedule(specs, s, schedule_settings(cfg), progress, map_points=partial(pool_map, pool))
        except BaseException:
            stop_pool(pool, abort=True)
            raise
        stop_pool(pool)
    return DesignResult(cfg, ds.points, ds.fit, ds.check, design_table(ds.points, ds.fit, design_hash(cfg)),
                        time.perf_counter() - t0, ds.path_check, ds.refinement)


def design_table(points, fit, design_hash: str) -> DesignTable:
    """The :class:`DesignTable` of point designs and their schedule fit (None: one point).

    Parameters
    ----------
    points : list of acmm.design.schedule.PointDesign
        Point designs.
    fit : acmm.design.schedule.ScheduleFit or None
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
                       np.array([p.gain.K for p in points]),
                       None if fit is None else fit.coef, design_hash,
                       "polynomial" if fit is None else fit.form,
                       np.array([p.spec.level for p in points], dtype=bool))


@stage(("design.h5", "design_*.png"), as_config)
def run_design(config, progress=None, figures: bool | None = None, warn=None, *,
               out: Path) -> tuple[DesignResult, Path]:
    """Design and write ``runs/<name>/design.h5`` plus the gain-schedule and pole-map figures
    (:mod:`acmm.stages.design_output` builds both).

    Parameters
    ----------
    config : acmm.io.config.Config or path-like or str
        The config, or a config file / packaged name to load.
    progress : callable, optional
        ``progress(name)``, called after each design point.
    figures : bool, optional
        Write the figures (default: ``output.figures``).
    warn : callable, optional
        ``warn(message)``, called before ``design.h5`` is written when the scheduled closed loop
        is unstable somewhere (:meth:`DesignResult.unstable`).
    out : pathlib.Path
        The folder its files are written in (the staging folder :func:`acmm_qpp.outputs.stage` gives).

    Returns
    -------
    tuple
        (:class:`DesignResult`, pathlib.Path of ``design.h5``).
    """
    cfg = as_config(config)
    want_figures = cfg.output.figures if figures is None else figures
    r = compute_design(cfg, progress)
    if warn is not None and r.unstable() is not None:
        warn(f"{cfg.name}: {r.unstable()}; writing it to {cfg.run_dir() / 'design.h5'} all the same")
    items = design_output.design_items(r, cfg)
    write_results(out / "design.h5", items, cfg,
                  {"stage": "design", "design_hash": r.table.design_hash, "n_points": len(r.points),
                   "schedule_form": r.table.form, "table_sha256": stored_table_digest(items, cfg.output.units)})
    if want_figures:
        draw_figures(design_output.design_figures_from_file(out / "design.h5", out))
    return r, cfg.run_dir() / "design.h5"


def design_for(cfg: Config, progress=None, figures: bool | None = None, warn=None) -> tuple[DesignTable, str]:
    """The design of a config: reused from ``design.h5`` when its hash matches, else computed.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The config.
    progress : callable, optional
        ``progress(name)``, called after each design point when designing.
    figures : bool, optional
        Write the design figures when designing (default: ``output.figures``).
    warn : callable, optional
        Passed to :func:`run_design` when designing (an unstable schedule is named before it is written).

    Returns
    -------
    tuple
        (:class:`DesignTable`, a note saying whether it was reused or designed).
    """
    path = cfg.run_dir() / "design.h5"
    want = design_hash(cfg)
    if path.is_file():          # a regular file (a FIFO or a device there would block or never end)
        with contextlib.suppress(OSError, KeyError, ValueError):
            table = load_design_table(path)
            if table.design_hash == want:
                with h5py.File(path, "r") as f:    # one unit system per run folder (before issue 14: imperial)
                    if h5_text(f.attrs.get("unit_system", "imperial")) == cfg.output.units:
                        return table, f"reused {path}"
    r, path = run_design(cfg, progress, figures, warn)
    # in SI the table as a later run reuses it: converted to SI and back, so that a simulation is
    # the same bit for bit whether its design was just made or read from design.h5
    return r.table if cfg.output.units == "imperial" else load_design_table(path), f"designed, wrote {path}"
