"""Gathering the results the report needs: reuse ``<root>/<name>/*.h5`` by hash, else run the stage.

The stages are those of Part II (TEA, design and stair-case simulation, ch. 4–6) and Part III
(the examples of ch. 13–14).
"""
from __future__ import annotations

import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from common.errors import AcmmError
from report.constants import FAST_ORBITS


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


def _attrs(path: Path) -> dict:
    import h5py

    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def _try_attrs(path: Path) -> dict | None:
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
    acmm.config.Config
        The config, figures off.
    """
    from acmm.config import load_config, parse_config

    data = load_config(name).model_dump(mode="json")
    if root is not None:
        data["output"]["root"] = str(root)
    data["output"]["figures"] = False
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
    qpp.config.QppConfig
        The config, figures off.
    """
    from qpp.config import load_config, parse_config

    data = load_config(name).model_dump(mode="json")
    if root is not None:
        data["output"]["root"] = str(root)
    data["output"]["figures"] = False
    return parse_config(data, source=f"packaged config {name}")


def _record(stage, cfg_name, path, chash, dhash, reused, wall):
    a = _attrs(path)
    return StageRun(stage, cfg_name, path, chash, dhash, reused, wall, str(a.get("created_utc", "")),
                    str(a.get("git_commit", "")))


def ensure_acmm_design(cfg, *, rerun: bool = False, donor_roots=()) -> StageRun:
    """``design.h5`` of an acmm config through :func:`acmm.stages.design_for` (the stages' own
    reuse by ``design_hash``), or designed again (``rerun``).

    ``donor_roots``: other run directories whose ``design.h5`` may be copied when its design hash
    matches (the ``--fast`` stair-case reuses the full stair-case's design).

    Parameters
    ----------
    cfg : acmm.config.Config
        The config.
    rerun : bool, optional
        Design again even when a matching file exists.
    donor_roots : iterable of path-like, optional
        Run directories whose ``design.h5`` may be copied.

    Returns
    -------
    StageRun
        The design file used.
    """
    from common.results import config_hash
    from acmm.stages import design_for, design_hash, run_design

    want = design_hash(cfg)
    path = cfg.run_dir() / "design.h5"
    chash = config_hash(cfg.to_yaml())
    t0 = time.perf_counter()
    if rerun:
        _, path = run_design(cfg, figures=False)
        return _record("acmm design", cfg.name, path, chash, want, False, time.perf_counter() - t0)
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
    return _record("acmm design", cfg.name, path, chash, want, reused,
                   0.0 if reused else time.perf_counter() - t0)


def ensure_acmm_simulation(cfg, *, rerun: bool = False) -> StageRun:
    """``sim.h5`` of an acmm config: reused when config and design hashes match, else simulated.

    Parameters
    ----------
    cfg : acmm.config.Config
        The config.
    rerun : bool, optional
        Simulate again even when a matching file exists.

    Returns
    -------
    StageRun
        The simulation file used.
    """
    from common.results import config_hash
    from acmm.stages import design_hash, run_simulate

    chash, dhash = config_hash(cfg.to_yaml()), design_hash(cfg)
    path = cfg.run_dir() / "sim.h5"
    a = None if rerun else _try_attrs(path)
    if a is not None and a.get("config_hash") == chash and a.get("design_hash") == dhash:
        return _record("acmm simulate", cfg.name, path, chash, dhash, True, 0.0)
    t0 = time.perf_counter()
    _, path = run_simulate(cfg, figures=False)
    return _record("acmm simulate", cfg.name, path, chash, dhash, False, time.perf_counter() - t0)


def ensure_qpp(cfg, stage: str, *, rerun: bool = False) -> StageRun:
    """``qpp_design.h5`` (``stage="design"``) or ``qpp_sim.h5`` (``"simulate"``), reused by config hash.

    Parameters
    ----------
    cfg : qpp.config.QppConfig
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
    from common.results import config_hash
    from qpp import stages as qst

    chash = config_hash(cfg.to_yaml())
    path = cfg.run_dir() / ("qpp_design.h5" if stage == "design" else "qpp_sim.h5")
    a = None if rerun else _try_attrs(path)
    if a is not None and a.get("config_hash") == chash:
        return _record(f"qpp {stage}", cfg.name, path, chash, "", True, 0.0)
    t0 = time.perf_counter()
    if stage == "design":
        path = qst.run_design(cfg, figures=False)[2]
    else:
        path = qst.run_simulate(cfg, figures=False)[3]
    return _record(f"qpp {stage}", cfg.name, path, chash, "", False, time.perf_counter() - t0)


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
    """

    configs: dict
    runs: dict                                   #: key "stage:name" → StageRun
    robustness: dict | None = None
    robustness_note: str = ""
    robustness_wall: float = 0.0
    timings: dict = field(default_factory=dict)   #: wall time (s) per group of stages


def gather(root: Path | None = None, *, fast: bool = False, rerun: bool = False,
           progress: Callable[[str], None] | None = None, robustness: bool = True) -> Gathered:
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

    Returns
    -------
    Gathered
        The configs and the results files.
    """
    say = progress or (lambda msg: None)
    cfgs = {name: acmm_config(name, root, fast=fast and name == "staircase")
            for name in ("mb3", "mb3_decoupled", "ac", "staircase")}
    cfgs.update({name: qpp_config(name, root) for name in ("qpp_siso", "qpp_manipulator")})
    runs: dict[str, StageRun] = {}

    def keep(r: StageRun):
        runs[f"{r.stage}:{r.config}"] = r
        say(f"  {r.stage:<14} {r.config:<16} {'reused' if r.reused else f'{r.wall_time:6.1f} s'}  {r.path}")

    full = acmm_config("staircase", root)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    for name in ("mb3", "mb3_decoupled", "ac", "staircase"):
        donors = [full.run_dir()] if cfgs[name].name != full.name else []
        keep(ensure_acmm_design(cfgs[name], rerun=rerun, donor_roots=donors))
    for name in ("mb3", "mb3_decoupled", "staircase"):
        keep(ensure_acmm_simulation(cfgs[name], rerun=rerun))
    timings["acmm stages"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    for name in ("qpp_siso", "qpp_manipulator"):
        keep(ensure_qpp(cfgs[name], "design", rerun=rerun))
        keep(ensure_qpp(cfgs[name], "simulate", rerun=rerun))
    timings["qpp stages"] = time.perf_counter() - t0
    g = Gathered(cfgs, runs, timings=timings)
    if robustness:
        t0 = time.perf_counter()
        g.robustness, g.robustness_note = robustness_result(root, fast=fast, rerun=rerun)
        g.robustness_wall = time.perf_counter() - t0
        g.timings["robustness sweep"] = g.robustness_wall
        if g.robustness is not None:
            r = g.robustness["run"]
            runs[f"{r.stage}:{r.config}"] = r
        say(f"  robustness     {'available' if g.robustness else 'not available'} "
            f"({g.robustness_wall:.1f} s) {g.robustness_note}")
    return g


def robustness_result(root: Path | None = None, *, fast: bool = False, rerun: bool = False):
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

    Returns
    -------
    (dict or None, str)
        ``{"data": sweep.h5 as read by read_h5, "run": StageRun, "fast", "n_runs", "orbits",
        "design", "tea_estimate", "seed", "bases"}`` and a note.  A missing sweep package, or a sweep that fails with an :class:`AcmmError` or an
        ``OSError``, makes the section "not available"; programming errors propagate.
    """
    import importlib

    try:
        importlib.import_module("acmm.sweep")
    except ImportError as exc:
        return None, f"acmm.sweep is not installed in this tree ({exc.name or exc})"
    try:
        return _robustness_from_sweep(root, fast=fast, rerun=rerun)
    except (AcmmError, OSError) as exc:        # a sweep that refuses its input or cannot write;
        return None, f"the sweep failed: {type(exc).__name__}: {exc}"   # a bug (TypeError, …) propagates


#: the reduced sweep of ``--fast``: runs per base and orbits per run (no margin search)
FAST_SWEEP_RUNS = 6
FAST_SWEEP_ORBITS = 2.0
SWEEP_CONFIG = "sweep_inertia30.yaml"


def _robustness_from_sweep(root, *, fast, rerun):
    """Run (or reuse, by ``results_key``) ``configs/sweep_inertia30.yaml`` through
    :func:`acmm.sweep.run_sweep` and read ``sweep.h5`` back."""
    import yaml

    import importlib

    from acmm.config import packaged_config_path
    from common.results import read_h5
    from acmm.sweep.config import parse_sweep

    p = packaged_config_path(SWEEP_CONFIG)
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
    a = None if rerun else _try_attrs(path)
    reused = bool(a is not None and a.get("results_key") == sweep.results_key() and bool(a.get("complete")))
    t0 = time.perf_counter()
    if not reused:
        run_sweep = importlib.import_module("acmm.sweep").run_sweep
        path = run_sweep(sweep, workers=max(1, min(2, os.cpu_count() or 1)), figures=False).path
    wall = 0.0 if reused else time.perf_counter() - t0
    d = read_h5(path)
    chash = str(d["attrs"].get("config_hash", ""))
    run = _record("acmm sweep", sweep.name, path, chash, "", reused, wall)
    spec = sweep.spec
    return {"data": d, "run": run, "fast": fast, "n_runs": spec.n_runs, "orbits": spec.orbits,
            "design": spec.design, "tea_estimate": spec.tea_estimate, "seed": spec.seed,
            "bases": [b.label for b in sweep.bases]}, f"{sweep.name}: {path}"


# =============================================================================================
