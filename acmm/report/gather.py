"""Gathering the results the report needs: reuse ``<root>/<name>/*.h5`` by hash, else run the stage.

The stages are those of Part II (TEA, design and stair-case simulation, ch. 4–6) and Part III
(the examples of ch. 13–14).
"""
from __future__ import annotations

import importlib
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from acmm_qpp.errors import AcmmError, OutputError
from acmm_qpp.outputs import file_identity
# the results files of one stage (reused by hash, else run)
from acmm.report.stage_results import (Failed, StageRun, stage_record, try_attrs, acmm_config, blocked, ensure_acmm_design, ensure_acmm_simulation, ensure_qpp, failed, qpp_config)
import yaml
from acmm.io.config import parse_config
from acmm.report.runner import Task, run_tasks
from acmm.report.constants import STAIRCASES
from acmm.simulate.warmup import warm_up
from acmm.report.figure_style import warm
from acmm import PACKAGED_CONFIGS
from acmm_qpp.configio import packaged_config_path
from acmm_qpp.results import read_h5
from acmm.sweep.config import parse_sweep
# imported here so that the report's workers, forked after :func:`warm_workers`, find them loaded
import h5py  # noqa: F401
import matplotlib.pyplot  # noqa: F401
import scipy.linalg  # noqa: F401
import acmm.stages.runners  # noqa: F401
import acmm.sweep.run  # noqa: F401
import qpp.io.stages  # noqa: F401


@dataclass
class Gathered:
    """Configs and results files of one report.

    Attributes
    ----------
    configs : dict
        Config name → acmm or qpp config.
    runs : dict
        ``"stage:name"`` → :class:`StageRun`.
    robustness : dict or None
        The robustness sweep (:func:`robustness_result`), or None.
    robustness_note : str
        Where it comes from, or why it is not available.
    robustness_wall : float
        Time spent on it, s.
    timings : dict
        Group of stages → wall time, s.
    produced_by : dict
        Run key (``"stage:name"``) → name of the :class:`acmm.report.runner.Task` that produced it
        (used by :func:`order_runs`).
    identities : dict
        Run key → :func:`acmm_qpp.outputs.file_identity` of its results file when the report
        took it; checked before the report writes its pages (:func:`changed_runs`).
    failed : dict
        Task name → :class:`Failed` of each stage that failed (or was not run because the
        stage it waits for failed); the sections reading it show the error.
    """

    configs: dict
    runs: dict                                   #: key "stage:name" → StageRun
    robustness: dict | None = None
    robustness_note: str = ""
    robustness_wall: float = 0.0
    timings: dict = field(default_factory=dict)   #: wall time (s) per stage
    produced_by: dict = field(default_factory=dict)   #: run key → name of the task that made it
    identities: dict = field(default_factory=dict)    #: run key → file_identity when taken
    failed: dict = field(default_factory=dict)        #: stage task name → Failed


def report_configs(root: Path | None = None, *, fast: bool = False) -> dict:
    """The six packaged configs of the report, the stair-case on the report's route and in the
    report's quadratic form, keyed by config name (``--fast``: short stair-case, and no quadratic:
    its refit is a minute of design).

    Parameters
    ----------
    root : pathlib.Path, optional
        Results root (default: each config's ``output.root``).
    fast : bool, optional
        The stair-case config with :data:`FAST_ORBITS` orbits (:func:`acmm_config`), without
        ``"staircase_quadratic"``.

    Returns
    -------
    dict
        ``"mb3"``, ``"mb3_decoupled"``, ``"ac"``, ``"staircase"`` → acmm config (Table 1, ch. 5–6);
        ``"staircase_lqr"`` → the stair-case on the report's route and ``"staircase_quadratic"``
        → in the report's converged quadratic form (:data:`REPORT_VARIANTS`; not with ``fast``);
        ``"qpp_siso"``, ``"qpp_manipulator"`` → qpp config (ch. 13–14).
    """
    cfgs = {name: acmm_config(name, root, fast=fast and name == "staircase")
            for name in ("mb3", "mb3_decoupled", "ac", "staircase")}
    for key, (suffix, patch) in REPORT_VARIANTS.items():
        if not (fast and key == "staircase_quadratic"):
            cfgs[key] = variant(cfgs["staircase"], suffix, patch)
    cfgs.update({name: qpp_config(name, root) for name in ("qpp_siso", "qpp_manipulator")})
    return cfgs


#: the report's stair-case variants beside the packaged one (config key → name suffix and the
#: config sections it changes): the report's route, sector LQR points (its gains are chosen
#: discretely, so bisection of the table does not converge), and the report's quadratic form
#: (ch. 5.3), converged on the path (``fit`` null: the polynomial's default, ``shifted_lqr``)
REPORT_VARIANTS = {
    "staircase_lqr": ("lqr", {"design": {"pole_method": "shift"}, "schedule": {"refine_points": 0}}),
    "staircase_quadratic": ("quadratic", {"schedule": {"form": "polynomial", "fit": None}}),
}


def variant(cfg, suffix: str, patch: dict):
    """``cfg`` named ``<name>_<suffix>`` with its sections updated by ``patch``.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The config (:func:`acmm.report.stage_results.acmm_config`).
    suffix : str
        Appended to its name.
    patch : dict
        ``{section: {key: value}}`` merged into its sections.

    Returns
    -------
    acmm.io.config.Config
        The variant, validated.
    """
    data = cfg.model_dump(mode="json")
    data["name"] = f"{data['name']}_{suffix}"
    for section, values in patch.items():
        data[section].update(values)
    return parse_config(data, source=f"{cfg.name} ({suffix})")


def _design_task(cfg, rerun, donors):
    return ensure_acmm_design(cfg, rerun=rerun, donor_roots=donors)


def _simulate_task(cfg, rerun):
    return ensure_acmm_simulation(cfg, rerun=rerun)


def _qpp_task(cfg, stage, rerun):
    return ensure_qpp(cfg, stage, rerun=rerun)


def _guarded(name, fn, not_run, *args):
    """``fn(*args)`` of stage task ``name``, or its :class:`Failed` (``not_run``: a stage it waits
    for failed; a user-facing error it raises); a bug propagates."""
    if not_run is not None:
        return not_run
    try:
        return fn(*args)
    except Exception as exc:  # noqa: BLE001 (re-raised unless a user-facing failure)
        f = failed(name, exc)
        if f is None:
            raise
        return f


def _stage(name, fn, deps, args, cost):
    """The stage ``name`` as a task of :func:`_guarded`."""
    return Task(name, _guarded, deps, lambda done: (name, fn, blocked(name, done, deps), *args), cost)


def _sweep_task(root, fast, rerun, workers):
    t0 = time.perf_counter()
    res, note = robustness_result(root, fast=fast, rerun=rerun, workers=workers)
    return res, note, time.perf_counter() - t0


#: rough relative run times of the stages on one idle core, only to order the parallel tasks (the
#: stair-case's regional LMI points, in a report worker designed one after another, dominate)
_COST = {"design:staircase": 25.0, "simulate:staircase": 0.4, "design:staircase_lqr": 1.2,
         "simulate:staircase_lqr": 0.4, "design:staircase_quadratic": 25.0, "simulate:staircase_quadratic": 0.4, "qpp design:qpp_siso": 2.0,
         "qpp simulate:qpp_siso": 1.0, "qpp design:qpp_manipulator": 1.8, "qpp simulate:qpp_manipulator": 1.0,
         "sweep": 2.7}


def stage_tasks(cfgs: dict, root: Path | None = None, *, fast: bool = False, rerun: bool = False,
                robustness: bool = True, jobs: int = 1) -> list:
    """The stages of the report as :class:`acmm.report.runner.Task` s, in the serial order.

    A simulation waits for the design of its config (it reuses ``design.h5``); a qpp simulation
    waits for the qpp design of its config (one run at a time holds a run directory's lock).
    The robustness sweep runs on one process when the report itself runs ``jobs`` > 1 processes.

    Parameters
    ----------
    cfgs : dict
        Config name → config, as :func:`report_configs` returns.
    root : pathlib.Path, optional
        Results root (default: each config's ``output.root``).
    fast : bool, optional
        Short stair-case and reduced robustness sweep (:func:`robustness_result`).
    rerun : bool, optional
        Recompute every stage instead of reusing matching results.
    robustness : bool, optional
        Include the robustness sweep (task ``"sweep"``).
    jobs : int, optional
        Processes the report runs on (> 1: the sweep itself uses one worker).

    Returns
    -------
    list of acmm.report.runner.Task
        Named ``"design:<name>"``, ``"simulate:<name>"``, ``"qpp design:<name>"``,
        ``"qpp simulate:<name>"`` and ``"sweep"``; each returns a :class:`StageRun` (the sweep:
        ``(result, note, wall s)``), or a :class:`Failed` when it raised a user-facing error or
        the stage it waits for failed (a bug propagates).
    """
    # a --fast stair-case takes the design of the full one when it has the same design hash
    full = report_configs(root) if fast else cfgs
    tasks = []
    stairs = [name for name in STAIRCASES if name in cfgs]
    for name in ("mb3", "mb3_decoupled", "ac", *stairs):
        donors = [full[name].run_dir()] if cfgs[name].name != full[name].name else []
        tasks.append(_stage(f"design:{name}", _design_task, (), (cfgs[name], rerun, donors),
                            _COST.get(f"design:{name}", 0.1)))
    for name in ("mb3", "mb3_decoupled", *stairs):
        tasks.append(_stage(f"simulate:{name}", _simulate_task, (f"design:{name}",), (cfgs[name], rerun),
                            _COST.get(f"simulate:{name}", 0.1) if not fast else 0.1))
    for name in ("qpp_siso", "qpp_manipulator"):
        for stage, deps in (("design", ()), ("simulate", (f"qpp design:{name}",))):
            tasks.append(_stage(f"qpp {stage}:{name}", _qpp_task, deps, (cfgs[name], stage, rerun),
                                _COST[f"qpp {stage}:{name}"]))
    if robustness:
        tasks.append(_stage("sweep", _sweep_task, (), (root, fast, rerun, 1 if jobs > 1 else None),
                            0.5 if fast else _COST["sweep"]))
    return tasks


def changed_runs(g: "Gathered") -> list[str]:
    """Run keys whose results file is no longer the one the report took (another run of that
    name wrote it meanwhile: the report's sections may have read either).

    Parameters
    ----------
    g : Gathered
        The gathered results.

    Returns
    -------
    list of str
        The changed run keys.
    """
    return [k for k, ident in g.identities.items() if file_identity(g.runs[k].path) != ident]


def keep_stage(g: "Gathered", name: str, result, say: Callable[[str], None]) -> None:
    """Record the result of stage task ``name`` in ``g`` (and print one line).

    Parameters
    ----------
    g : Gathered
        Filled in place: ``runs``, ``produced_by``, ``timings`` and, for the sweep, the
        ``robustness`` fields.
    name : str
        Task name (:func:`stage_tasks`).
    result : StageRun, tuple or Failed
        The task's result; for ``"sweep"`` ``(robustness dict or None, note, wall s)``; a
        :class:`Failed` goes into ``g.failed``.
    say : callable
        Called with one line of progress text.
    """
    if isinstance(result, Failed):
        g.failed[name] = result
        if name == "sweep":
            g.robustness_note = f"the sweep failed: {result.message}"
        say(f"  {result.text()}")
        return
    if name == "sweep":
        g.robustness, g.robustness_note, g.robustness_wall = result
        g.timings["robustness sweep"] = g.robustness_wall
        if g.robustness is not None:
            r = g.robustness["run"]
            g.runs[f"{r.stage}:{r.config}"] = r
            g.produced_by[f"{r.stage}:{r.config}"] = name
            g.identities[f"{r.stage}:{r.config}"] = file_identity(r.path)
        say(f"  robustness     {'available' if g.robustness else 'not available'} "
            f"({g.robustness_wall:.1f} s) {g.robustness_note}")
        return
    r: StageRun = result
    g.runs[f"{r.stage}:{r.config}"] = r
    g.produced_by[f"{r.stage}:{r.config}"] = name
    g.identities[f"{r.stage}:{r.config}"] = file_identity(r.path)
    g.timings[f"{r.stage} {r.config}"] = r.wall_time
    say(f"  {r.stage:<14} {r.config:<16} {'reused' if r.reused else f'{r.wall_time:6.1f} s'}  {r.path}")


def order_runs(g: "Gathered", tasks: list) -> None:
    """``g.runs`` in the serial order of ``tasks`` (the manifest and provenance list them so).

    Parameters
    ----------
    g : Gathered
        Its ``runs`` are re-ordered in place (by ``produced_by``).
    tasks : list of acmm.report.runner.Task
        The stage tasks in their serial order (:func:`stage_tasks`).
    """
    index = {t.name: i for i, t in enumerate(tasks)}
    rank = {key: index.get(name, len(index)) for key, name in g.produced_by.items()}
    g.runs = dict(sorted(g.runs.items(), key=lambda kv: rank.get(kv[0], len(index))))


def gather(root: Path | None = None, *, fast: bool = False, rerun: bool = False,
           progress: Callable[[str], None] | None = None, robustness: bool = True, jobs: int = 1) -> Gathered:
    """Run (or reuse) every stage the report needs.

    Parameters
    ----------
    root : Path or None
        Results root (``<root>/<name>/``); None keeps each config's ``output.root`` (``runs``).
    fast : bool
        Short stair-case (:data:`FAST_ORBITS` orbits) and a reduced robustness sweep.
    rerun : bool
        Ignore existing results and recompute every stage.
    progress : callable or None
        Called with one line of text per stage.
    robustness : bool
        Also run (or reuse) the robustness sweep.
    jobs : int
        Worker processes (:mod:`acmm.report.runner`); 1 runs the stages one after the other here.

    Returns
    -------
    Gathered
        The configs and the results files.
    """
    say = progress or (lambda msg: None)
    g = Gathered(report_configs(root, fast=fast), {})
    tasks = stage_tasks(g.configs, root, fast=fast, rerun=rerun, robustness=robustness, jobs=jobs)
    run_tasks(tasks, jobs, lambda name, res: keep_stage(g, name, res, say), warm=warm_workers)
    order_runs(g, tasks)
    return g


def warm_workers() -> None:
    """Imports (and the compiled simulator, a first figure's fonts and caches) every worker needs,
    done once before forking them (the modules they import are imported at the top of this one)."""
    warm_up(lambda *a: None)
    warm()


def robustness_result(root: Path | None = None, *, fast: bool = False, rerun: bool = False,
                      workers: int | None = None):
    """The ±30 % inertia sweep (issue 7, :mod:`acmm.sweep`), or (None, why not).

    Parameters
    ----------
    root : pathlib.Path, optional
        Results root (default: the sweep config's ``output.root``).
    fast : bool, optional
        A reduced sweep (:data:`FAST_SWEEP_RUNS` runs of :data:`FAST_SWEEP_ORBITS` orbits, no
        margin search).
    rerun : bool, optional
        Run the sweep even when a complete matching ``sweep.h5`` exists.
    workers : int, optional
        Worker processes of the sweep (default: min(2, CPUs)).

    Returns
    -------
    (dict or None, str)
        ``{"data": sweep.h5 as read by read_h5, "run": StageRun, "fast", "n_runs", "orbits",
        "design", "tea_estimate", "seed", "bases"}`` and a note.  A missing sweep package, or a sweep that fails with an :class:`AcmmError` or an
        ``OSError``, makes the section "not available"; programming errors propagate.
    """
    try:
        importlib.import_module("acmm.sweep.run")
    except ImportError as exc:
        return None, f"acmm.sweep is not installed in this tree ({exc.name or exc})"
    try:
        return _robustness_from_sweep(root, fast=fast, rerun=rerun, workers=workers)
    except OutputError:                         # the report's folder cannot be written: it stops
        raise
    except (AcmmError, OSError) as exc:        # a sweep that refuses its input or cannot read;
        return None, f"the sweep failed: {type(exc).__name__}: {exc}"   # a bug (TypeError, …) propagates


#: the reduced sweep of ``--fast``: runs per base and orbits per run (no margin search)
FAST_SWEEP_RUNS = 6
FAST_SWEEP_ORBITS = 2.0
SWEEP_CONFIG = "sweep_inertia30.yaml"


def _robustness_from_sweep(root, *, fast, rerun, workers=None):
    """Run (or reuse, by ``results_key``) ``configs/sweep_inertia30.yaml`` through
    :func:`acmm.sweep.run_sweep` and read ``sweep.h5`` back."""

    p = packaged_config_path(SWEEP_CONFIG, PACKAGED_CONFIGS)
    if not p.exists():
        return None, f"configs/{SWEEP_CONFIG} is not present"
    data = yaml.safe_load(p.read_text())
    data.setdefault("output", {})
    if root is not None:
        data["output"]["root"] = str(root)
    data["output"]["figures"] = False
    if fast:
        data["name"] = f"{data['name']}_fast"
        data["sweep"]["n_runs"] = FAST_SWEEP_RUNS
        data["sweep"]["orbits"] = FAST_SWEEP_ORBITS
        data["sweep"].pop("margin", None)
    sweep = parse_sweep(data, source=str(p), directory=p.parent)
    path = sweep.run_dir() / "sweep.h5"
    a = None if rerun else try_attrs(path)
    reused = bool(a is not None and a.get("results_key") == sweep.results_key() and bool(a.get("complete")))
    t0 = time.perf_counter()
    if not reused:
        run_sweep = importlib.import_module("acmm.sweep.run").run_sweep
        path = run_sweep(sweep, workers=workers or max(1, min(2, os.cpu_count() or 1)), figures=False).path
    wall = 0.0 if reused else time.perf_counter() - t0
    d = read_h5(path)
    chash = str(d["attrs"].get("config_hash", ""))
    run = stage_record("acmm sweep", sweep.name, path, chash, "", reused, wall)
    spec = sweep.spec
    return {"data": d, "run": run, "fast": fast, "n_runs": spec.n_runs, "orbits": spec.orbits,
            "design": spec.design, "tea_estimate": spec.tea_estimate, "seed": spec.seed,
            "bases": [b.label for b in sweep.bases]}, f"{sweep.name}: {path}"


# =============================================================================================
