"""Gathering the results the report needs: reuse ``<root>/<name>/*.h5`` by hash, else run the stage.

The stages are those of Part II (TEA, design and stair-case simulation, ch. 4–6) and Part III
(the examples of ch. 13–14).  One stage's results file is reused when its hashes match, else the
stage is run (:func:`acmm.stages.design.design_for` for designs, the hashes of the simulation and of
the QPP stages otherwise); :func:`stage_tasks` runs them as a task graph.
"""
from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import h5py
import numpy as np
import yaml
from acmm_qpp.errors import EXIT_INPUT, AcmmError, OutputError, plain_failure
from acmm_qpp.outputs import file_identity
from acmm.io.config import load_config, parse_config
from qpp.io.config import load_config as load_qpp_config, parse_config as parse_qpp_config
from acmm.report.runner import Task
from acmm.report.constants import FAST_ORBITS, STAIRCASES
from acmm.simulate.warmup import warm_up
from acmm.report.figure_style import warm
from acmm import PACKAGED_CONFIGS
from acmm_qpp.configio import packaged_config_path
from acmm_qpp.provenance import config_hash
from acmm_qpp.results import read_h5
from acmm.stages.design import design_for, design_hash, run_design
from acmm.stages.simulate import run_simulate
from acmm.sweep.config import parse_sweep
from acmm.sweep.run import run_sweep
from qpp.io import stages as qst
# imported here so that the report's workers, forked after :func:`warm_workers`, find them loaded
import matplotlib.pyplot  # noqa: F401
import scipy.linalg  # noqa: F401
import acmm.stages.runners  # noqa: F401


@dataclass
class StageRun:
    """One results file the report used.

    Attributes
    ----------
    stage : str
        Stage name (``"acmm design"``, ``"qpp simulate"``, ...).
    config : str
        Config name.
    path : pathlib.Path
        The HDF5 file.
    config_hash : str
        Hash of the resolved config.
    design_hash : str
        Hash of the design-relevant config (acmm stages), else empty.
    reused : bool
        The file was reused, not recomputed.
    wall_time : float
        Time this report spent on the stage, s (0 when reused).
    created_utc : str
        The file's creation time.
    git_commit : str
        Commit the file was written by.
    """

    stage: str
    config: str
    path: Path
    config_hash: str
    design_hash: str = ""
    reused: bool = False
    wall_time: float = 0.0          #: seconds this report spent on the stage (0 when reused)
    created_utc: str = ""
    git_commit: str = ""


@dataclass
class Failed:
    """A stage or section part of the report that failed with a user-facing error: the report
    shows it in its section, the other sections complete, and ``acmm report`` exits non-zero.

    Attributes
    ----------
    name : str
        Task name (``"qpp design:qpp_siso"``, ``"qpp13/circle"``, ``"printed"``, ...).
    message : str
        The error on one line.
    exit_code : int
        The error's exit code (:mod:`acmm_qpp.errors`: 2 input, 3 numerical, 4 output).
    cause : str
        The task whose failure kept this one from running (its message is that task's); empty
        when this task itself failed.
    """

    name: str
    message: str
    exit_code: int
    cause: str = ""

    def text(self) -> str:
        """The failure as the report prints it.

        Returns
        -------
        str
            ``"<name> failed: <message>"``, or ``"<name> not computed: <cause> failed: <message>"``.
        """
        if self.cause:
            return f"{self.name} not computed: {self.cause} failed: {self.message}"
        return f"{self.name} failed: {self.message}"


def failed(name: str, exc: BaseException) -> Failed | None:
    """``exc`` raised by task ``name`` as a :class:`Failed`, or None for a bug (to propagate).

    Parameters
    ----------
    name : str
        Task name.
    exc : BaseException
        What it raised.

    Returns
    -------
    Failed or None
        Its message on one line and exit code: an :class:`~acmm_qpp.errors.AcmmError`'s message
        (its class name when empty) and class's ``exit_code``, or a
        :func:`~acmm_qpp.errors.plain_failure`; None for a genuine bug, for what is not an
        ``Exception`` and for an :class:`acmm_qpp.errors.OutputError` (a report that cannot write
        stops at once, with one ``error:`` line).
    """
    if isinstance(exc, OutputError) or not isinstance(exc, Exception):   # the report cannot write: it stops
        return None
    if isinstance(exc, AcmmError):
        return Failed(name, " ".join(str(exc).split()) or type(exc).__name__,
                      int(getattr(exc, "exit_code", EXIT_INPUT)))
    plain = plain_failure(exc)
    return None if plain is None else Failed(name, " ".join(plain[0].split()), plain[1])


def blocked(name: str, done: dict, deps) -> Failed | None:
    """The :class:`Failed` of task ``name`` when one of its dependencies failed (it is not run).

    Parameters
    ----------
    name : str
        Task name.
    done : dict
        Task name → result (a :class:`Failed`, or an object with a ``failed`` attribute).
    deps : iterable of str
        Its dependencies.

    Returns
    -------
    Failed or None
        The first failed dependency's message, exit code and origin; None: none failed.
    """
    for d in deps:
        f = done.get(d)
        f = f if isinstance(f, Failed) else getattr(f, "failed", None)
        if isinstance(f, Failed):
            return Failed(name, f.message, f.exit_code, f.cause or f.name)
    return None


def _attrs(path: Path) -> dict:
    """The root attributes of a results file, bytes decoded."""
    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def _try_attrs(path: Path) -> dict | None:
    """The root attributes of a results file, or None when it is missing or unreadable."""
    try:
        return _attrs(path) if path.exists() else None
    except OSError:
        return None


def acmm_config(name: str, root: Path | None = None, *, fast: bool = False):
    """A packaged acmm config with its results root set to ``root`` (``--fast``: short stair-case).

    Parameters
    ----------
    name : str
        Packaged config name.
    root : pathlib.Path, optional
        Results root (default: the config's ``output.root``).
    fast : bool, optional
        For a config with a schedule: ``<name>_fast`` with :data:`FAST_ORBITS` orbits.

    Returns
    -------
    acmm.io.config.Config
        The config, figures off.
    """
    data = _packaged(load_config, name, root)
    if fast and data.get("schedule") is not None:
        data["name"] = f"{data['name']}_fast"
        data["simulation"]["orbits"] = FAST_ORBITS
        data["description"] = f"{data['description']} [--fast: {FAST_ORBITS:g} orbits]"
    return parse_config(data, source=f"packaged config {name}")


def qpp_config(name: str, root: Path | None = None):
    """A packaged qpp config with its results root set to ``root``.

    Parameters
    ----------
    name : str
        Packaged config name.
    root : pathlib.Path, optional
        Results root (default: the config's ``output.root``).

    Returns
    -------
    qpp.io.config.QppConfig
        The config, figures off.
    """
    return parse_qpp_config(_packaged(load_qpp_config, name, root), source=f"packaged config {name}")


def _packaged(load, name: str, root: Path | None) -> dict:
    """The packaged config ``name`` read by ``load`` (the file itself: a file or folder named like it
    in the working directory is not it), as data with its results root ``root`` and figures off."""
    data = load(packaged_config_path(f"{name}.yaml", PACKAGED_CONFIGS)).model_dump(mode="json")
    if root is not None:
        data["output"]["root"] = str(root)
    data["output"]["figures"] = False
    return data


def _stage_record(stage, cfg_name, path, chash, dhash, reused, wall):
    """The :class:`StageRun` of a results file the report computed or reused (``wall`` in s), with
    the file's creation time and git commit."""
    a = _attrs(path)
    return StageRun(stage, cfg_name, path, chash, dhash, reused, wall, str(a.get("created_utc", "")),
                    str(a.get("git_commit", "")))


def ensure_acmm_design(cfg, rerun: bool = False, donor_roots=()) -> StageRun:
    """``design.h5`` of an acmm config through :func:`acmm.stages.runners.design_for` (the stages' own
    reuse by ``design_hash``), or designed again (``rerun``).

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The config.
    rerun : bool, optional
        Design again even when a matching file exists.
    donor_roots : iterable of path-like, optional
        Run directories whose ``design.h5`` may be copied when its design hash matches (the
        ``--fast`` stair-case reuses the full stair-case's design).

    Returns
    -------
    StageRun
        The design file used.
    """
    want = design_hash(cfg)
    path = cfg.run_dir() / "design.h5"
    chash = config_hash(cfg.to_yaml())
    t0 = time.perf_counter()
    if rerun:
        _, path = run_design(cfg, figures=False)
        return _stage_record("acmm design", cfg.name, path, chash, want, False, time.perf_counter() - t0)
    a = _try_attrs(path)
    if a is None or a.get("design_hash") != want:
        for donor in donor_roots:
            a = _try_attrs(Path(donor) / "design.h5")
            if a is not None and a.get("design_hash") == want:
                path.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(Path(donor) / "design.h5", path)
                break
    _, note = design_for(cfg, figures=False)
    reused = note.startswith("reused")
    return _stage_record("acmm design", cfg.name, path, chash, want, reused,
                         0.0 if reused else time.perf_counter() - t0)


def ensure_acmm_simulation(cfg, rerun: bool = False) -> StageRun:
    """``sim.h5`` of an acmm config: reused when config and design hashes match, else simulated.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The config.
    rerun : bool, optional
        Simulate again even when a matching file exists.

    Returns
    -------
    StageRun
        The simulation file used.
    """
    return _reused_or_run("acmm simulate", cfg, cfg.run_dir() / "sim.h5", design_hash(cfg), rerun,
                          lambda: run_simulate(cfg, figures=False)[1])


def ensure_qpp(cfg, stage: str, rerun: bool = False) -> StageRun:
    """``qpp_design.h5`` (``stage="design"``) or ``qpp_sim.h5`` (``"simulate"``), reused by config hash.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The config.
    stage : {"design", "simulate"}
        Which stage.
    rerun : bool, optional
        Run again even when a matching file exists.

    Returns
    -------
    StageRun
        The file used.
    """
    file, run, at = ("qpp_design.h5", qst.run_design, 2) if stage == "design" else ("qpp_sim.h5", qst.run_simulate, 3)
    return _reused_or_run(f"qpp {stage}", cfg, cfg.run_dir() / file, "", rerun, lambda: run(cfg, figures=False)[at])


def _reused_or_run(stage: str, cfg, path: Path, dhash: str, rerun: bool, run) -> StageRun:
    """The :class:`StageRun` of ``path`` when its stored config hash (and design hash ``dhash``,
    when not empty) match ``cfg``'s and not ``rerun``, else of the file ``run()`` writes."""
    chash = config_hash(cfg.to_yaml())
    a = None if rerun else _try_attrs(path)
    if a is not None and a.get("config_hash") == chash and (not dhash or a.get("design_hash") == dhash):
        return _stage_record(stage, cfg.name, path, chash, dhash, True, 0.0)
    t0 = time.perf_counter()
    path = run()
    return _stage_record(stage, cfg.name, path, chash, dhash, False, time.perf_counter() - t0)


def qpp_scenarios(path: Path) -> dict:
    """The scenarios of a ``qpp_sim.h5``: their errors and sphere verdicts (dataset attributes,
    which :func:`acmm_qpp.results.read_h5` does not return).

    Parameters
    ----------
    path : pathlib.Path
        The ``qpp_sim.h5`` file.

    Returns
    -------
    dict
        Scenario name (file order) → ``{"error_inf": float, "per_output": array, "passed": bool,
        "beta_o": float, "gamma": float}`` (errors in the outputs' units; ``gamma`` NaN for a
        scenario that sets an expression's parameters instead).
    """
    out = {}
    with h5py.File(path, "r") as f:
        for k in f:
            if isinstance(f[k], h5py.Group) and "error_inf" in f[k]:
                e = f[k]["error_inf"]
                out[k] = {"error_inf": float(e[()]), "per_output": np.atleast_1d(f[k]["error_per_output"][()]),
                          "passed": bool(e.attrs["passed"]), "beta_o": float(e.attrs["beta_o"]),
                          "gamma": float(e.attrs.get("gamma", np.nan))}
    return out


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
        took it; checked before the report writes its pages.
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
        if not (fast and key == "staircase_quadratic"):         # the stair-case renamed and patched
            data = cfgs["staircase"].model_dump(mode="json")
            data["name"] = f"{data['name']}_{suffix}"
            for section, values in patch.items():
                data[section].update(values)
            cfgs[key] = parse_config(data, source=f"{cfgs['staircase'].name} ({suffix})")
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
        tasks.append(_stage(f"design:{name}", ensure_acmm_design, (), (cfgs[name], rerun, donors),
                            _COST.get(f"design:{name}", 0.1)))
    for name in ("mb3", "mb3_decoupled", *stairs):
        tasks.append(_stage(f"simulate:{name}", ensure_acmm_simulation, (f"design:{name}",), (cfgs[name], rerun),
                            _COST.get(f"simulate:{name}", 0.1) if not fast else 0.1))
    for name in ("qpp_siso", "qpp_manipulator"):
        for stage, deps in (("design", ()), ("simulate", (f"qpp design:{name}",))):
            tasks.append(_stage(f"qpp {stage}:{name}", ensure_qpp, deps, (cfgs[name], stage, rerun),
                                _COST[f"qpp {stage}:{name}"]))
    if robustness:
        tasks.append(_stage("sweep", _sweep_task, (), (root, fast, rerun, 1 if jobs > 1 else None),
                            0.5 if fast else _COST["sweep"]))
    return tasks


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
        say(f"  robustness     {'available' if g.robustness else 'not available'} "
            f"({g.robustness_wall:.1f} s) {g.robustness_note}")
        if g.robustness is None:
            return
        r: StageRun = g.robustness["run"]
    else:
        r = result
        g.timings[f"{r.stage} {r.config}"] = r.wall_time
        say(f"  {r.stage:<14} {r.config:<16} {'reused' if r.reused else f'{r.wall_time:6.1f} s'}  {r.path}")
    key = f"{r.stage}:{r.config}"
    g.runs[key], g.produced_by[key], g.identities[key] = r, name, file_identity(r.path)


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


def warm_workers() -> None:
    """Imports (and the compiled simulator, a first figure's fonts and caches) every worker needs,
    done once before forking them (the modules they import are imported at the top of this one)."""
    warm_up()
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
        "design", "tea_estimate", "seed"}`` and a note.  A sweep that fails with an :class:`AcmmError` or an
        ``OSError``, makes the section "not available"; programming errors propagate.
    """
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
        data["sweep"].update(n_runs=FAST_SWEEP_RUNS, orbits=FAST_SWEEP_ORBITS)
        data["sweep"].pop("margin", None)
    sweep = parse_sweep(data, source=str(p), directory=p.parent)
    path = sweep.run_dir() / "sweep.h5"
    a = None if rerun else _try_attrs(path)
    reused = bool(a is not None and a.get("results_key") == sweep.results_key() and bool(a.get("complete")))
    t0 = time.perf_counter()
    if not reused:
        path = run_sweep(sweep, workers=workers or max(1, min(2, os.cpu_count() or 1)), figures=False).path
    wall = 0.0 if reused else time.perf_counter() - t0
    d, spec = read_h5(path), sweep.spec
    run = _stage_record("acmm sweep", sweep.name, path, str(d["attrs"].get("config_hash", "")), "", reused, wall)
    return {"data": d, "run": run, "fast": fast, "n_runs": spec.n_runs, "orbits": spec.orbits,
            "design": spec.design, "tea_estimate": spec.tea_estimate, "seed": spec.seed}, f"{sweep.name}: {path}"
