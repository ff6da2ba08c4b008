"""The results file of one stage the report reads: reused when its hashes match, else the stage
is run (:func:`acmm.stages.runners.design_for` for designs, the hashes of the simulation and of the QPP
stages otherwise).

The stages are those of Part II (design and stair-case simulation, ch. 5–6) and Part III (the
examples of ch. 13–14).  Split from :mod:`acmm.report.gather` and runs
them as a task graph.
"""
from __future__ import annotations

import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from acmm.report.constants import FAST_ORBITS
import h5py
import numpy as np
from acmm_qpp.errors import EXIT_INPUT, AcmmError, OutputError, plain_failure
from acmm.io.config import load_config, parse_config
from qpp.io.config import load_config as load_qpp_config, parse_config as parse_qpp_config
from acmm import PACKAGED_CONFIGS
from acmm_qpp.configio import packaged_config_path
from acmm_qpp.provenance import config_hash
from acmm.stages.design import design_for, design_hash, run_design
from acmm.stages.simulate import run_simulate
from qpp.io import stages as qst


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


def failure_line(exc: BaseException):
    """(one-line message, exit code) of any user-facing failure: an
    :class:`~acmm_qpp.errors.AcmmError` (its message and class's ``exit_code``) or a
    :func:`~acmm_qpp.errors.plain_failure`; None for a genuine bug.

    Parameters
    ----------
    exc : BaseException
        The exception caught.

    Returns
    -------
    tuple of (str, int) or None
        The message on one line and the exit code, or None.
    """
    if isinstance(exc, AcmmError):
        return " ".join(str(exc).split()) or type(exc).__name__, int(getattr(exc, "exit_code", EXIT_INPUT))
    plain = plain_failure(exc)
    return None if plain is None else (" ".join(plain[0].split()), plain[1])


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
        Its one-line message and exit code (:func:`failure_line`), or None (also
        for an :class:`acmm_qpp.errors.OutputError`: a report that cannot write stops at once,
        with one ``error:`` line).
    """
    if isinstance(exc, OutputError):    # the report's folder cannot be written (a full disk…): it stops
        return None
    line = failure_line(exc) if isinstance(exc, Exception) else None
    return None if line is None else Failed(name, *line)


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
    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def try_attrs(path: Path) -> dict | None:
    """The root attributes of a results file, or None when it is missing or unreadable.

    Parameters
    ----------
    path : pathlib.Path
        The results file.

    Returns
    -------
    dict or None
        Its root attributes.
    """
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
    # the packaged file itself: a file or folder named like it in the working directory is not it
    data = load_config(packaged_config_path(f"{name}.yaml", PACKAGED_CONFIGS)).model_dump(mode="json")
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
    qpp.io.config.QppConfig
        The config, figures off.
    """
    data = load_qpp_config(packaged_config_path(f"{name}.yaml", PACKAGED_CONFIGS)).model_dump(mode="json")
    if root is not None:
        data["output"]["root"] = str(root)
    data["output"]["figures"] = False
    return parse_qpp_config(data, source=f"packaged config {name}")


def stage_record(stage, cfg_name, path, chash, dhash, reused, wall):
    """The :class:`StageRun` of a results file the report computed or reused.

    Parameters
    ----------
    stage : str
        The stage (``tea``, ``design``…).
    cfg_name : str
        The config's name.
    path : pathlib.Path
        The results file.
    chash, dhash : str
        Its config and data hashes.
    reused : bool
        Whether it was reused (not computed in this report).
    wall : float
        Wall time of the stage, s.

    Returns
    -------
    StageRun
        The record, with the file's creation time and git commit.
    """
    a = _attrs(path)
    return StageRun(stage, cfg_name, path, chash, dhash, reused, wall, str(a.get("created_utc", "")),
                    str(a.get("git_commit", "")))


def ensure_acmm_design(cfg, *, rerun: bool = False, donor_roots=()) -> StageRun:
    """``design.h5`` of an acmm config through :func:`acmm.stages.runners.design_for` (the stages' own
    reuse by ``design_hash``), or designed again (``rerun``).

    ``donor_roots``: other run directories whose ``design.h5`` may be copied when its design hash
    matches (the ``--fast`` stair-case reuses the full stair-case's design).

    Parameters
    ----------
    cfg : acmm.io.config.Config
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
    want = design_hash(cfg)
    path = cfg.run_dir() / "design.h5"
    chash = config_hash(cfg.to_yaml())
    t0 = time.perf_counter()
    if rerun:
        _, path = run_design(cfg, figures=False)
        return stage_record("acmm design", cfg.name, path, chash, want, False, time.perf_counter() - t0)
    a = try_attrs(path)
    if a is None or a.get("design_hash") != want:
        for donor in donor_roots:
            a = try_attrs(Path(donor) / "design.h5")
            if a is not None and a.get("design_hash") == want:
                path.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(Path(donor) / "design.h5", path)
                break
    _, note = design_for(cfg, figures=False)
    reused = note.startswith("reused")
    return stage_record("acmm design", cfg.name, path, chash, want, reused,
                   0.0 if reused else time.perf_counter() - t0)


def ensure_acmm_simulation(cfg, *, rerun: bool = False) -> StageRun:
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
    chash, dhash = config_hash(cfg.to_yaml()), design_hash(cfg)
    path = cfg.run_dir() / "sim.h5"
    a = None if rerun else try_attrs(path)
    if a is not None and a.get("config_hash") == chash and a.get("design_hash") == dhash:
        return stage_record("acmm simulate", cfg.name, path, chash, dhash, True, 0.0)
    t0 = time.perf_counter()
    _, path = run_simulate(cfg, figures=False)
    return stage_record("acmm simulate", cfg.name, path, chash, dhash, False, time.perf_counter() - t0)


def ensure_qpp(cfg, stage: str, *, rerun: bool = False) -> StageRun:
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
    chash = config_hash(cfg.to_yaml())
    path = cfg.run_dir() / ("qpp_design.h5" if stage == "design" else "qpp_sim.h5")
    a = None if rerun else try_attrs(path)
    if a is not None and a.get("config_hash") == chash:
        return stage_record(f"qpp {stage}", cfg.name, path, chash, "", True, 0.0)
    t0 = time.perf_counter()
    if stage == "design":
        path = qst.run_design(cfg, figures=False)[2]
    else:
        path = qst.run_simulate(cfg, figures=False)[3]
    return stage_record(f"qpp {stage}", cfg.name, path, chash, "", False, time.perf_counter() - t0)


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
