"""``acmm report``: every table and figure of CR-185644 regenerated and compared, in one page.

:func:`build_report` gathers the results it needs (reusing ``<root>/<name>/*.h5`` whose
``design_hash`` / ``config_hash`` match the packaged configs, else running the stage), computes
the cheap evidence for every erratum of ``NOTES.md`` directly, draws the figures
(:mod:`acmm.report_style`: vector PDF + PNG) and writes

* ``<out>/index.html`` — self-contained (PNG figures embedded as base64; no server needed),
* ``<out>/report.md`` — the same content in Markdown (figures as relative files),
* ``<out>/figures/*.pdf|png`` — every figure,
* ``<out>/manifest.json`` — SHA-256 of every HDF5 dataset used (timing datasets excluded),
  compared with the previous report's manifest when one exists (determinism).

Sections: Table 1; gain schedules and pole maps (Figs 5.3–5.26); claim 1 (Figs 6.2–6.13); the
130-orbit stair-case (Figs 6.14–6.30); ±30 % robustness; QPP ch. 13 and 14; errata; printed
numbers; determinism; provenance.  Every printed number the project reproduces is marked
"matched to printed precision" (|computed − printed| ≤ half a unit of the last printed digit),
"consistent with the printed bound", or carries its explanation.
"""
from __future__ import annotations

import base64
import hashlib
import html
import json
import os
import platform
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

import numpy as np

from common.errors import AcmmError
from common.results import write_text

#: stair-case length of ``--fast`` (orbits): one dwell per design point of the 12-point schedule
FAST_ORBITS = 13.0
#: datasets that hold timings, excluded from determinism hashes ("timestamps aside")
TIMING_DATASETS = ("wall_time",)

SECTIONS = [
    ("table1", "Table 1: configurations and torque-equilibrium attitudes"),
    ("schedule", "Gain schedules and pole maps (Figs 5.3–5.26)"),
    ("claim1", "Claim 1: MB3 coupled vs cross-inertia-free design (Figs 6.2–6.13)"),
    ("staircase", "Claim 2: the MB3 → AC stair-case (Figs 6.14–6.30)"),
    ("robustness", "±30 % inertia robustness"),
    ("qpp13", "QPP chapter 13: SISO Lure example"),
    ("qpp14", "QPP chapter 14: two-DOF manipulator"),
    ("errata", "Errata: misprints, corrections and evidence"),
    ("printed", "Printed numbers: reproduced or explained"),
    ("determinism", "Determinism"),
    ("provenance", "Provenance"),
]

STATUS_MATCHED = "matched to printed precision"
STATUS_BOUND = "consistent with the printed bound"
STATUS_EXPLAINED = "explained"
STATUS_UNEXPLAINED = "NOT EXPLAINED"


# =============================================================================================
# printed numbers
# =============================================================================================
@dataclass
class PrintedNumber:
    """One number printed in CR-185644 and what this run computed for it."""

    section: str
    quantity: str
    printed: str
    computed: float | None
    unit: str = ""
    status: str = STATUS_UNEXPLAINED
    note: str = ""


def printed_decimals(printed: str) -> int:
    """Number of decimals of a printed number (``"-44.7"`` → 1, ``"1020"`` → 0)."""
    s = printed.strip().lower().split("e")[0]
    return len(s.split(".")[1]) if "." in s else 0


def matches_printed(printed: str, computed: float) -> bool:
    """|computed − printed| ≤ half a unit of the printed number's last digit."""
    half = 0.5 * 10.0 ** (-printed_decimals(printed))
    return bool(abs(float(computed) - float(printed)) <= half * (1 + 1e-9) + 1e-15)


def check_printed(section: str, quantity: str, printed: str, computed, unit: str = "", *,
                  explanation: str = "", bound: str | None = None) -> PrintedNumber:
    """Classify one printed number.

    Parameters
    ----------
    printed : str
        The number exactly as printed (its decimals set the precision).
    computed : float or None
        This run's value (None: not computed, ``explanation`` required).
    bound : {"upper", None}
        ``"upper"``: the report prints a bound ("less than 0.094"); the value is consistent when
        it is below the bound.
    explanation : str
        Why a number that does not match differs (required for it to count as explained).
    """
    if computed is not None and bound == "upper" and float(computed) < float(printed):
        status = STATUS_BOUND
    elif computed is not None and bound is None and matches_printed(printed, computed):
        status = STATUS_MATCHED
    elif explanation:
        status = STATUS_EXPLAINED
    else:
        status = STATUS_UNEXPLAINED
    return PrintedNumber(section, quantity, printed, None if computed is None else float(computed), unit,
                         status, explanation if status == STATUS_EXPLAINED else "")


# =============================================================================================
# gathering results (reuse by hash, else run the stage)
# =============================================================================================
@dataclass
class StageRun:
    """One results file the report used."""

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
    """A packaged acmm config with its results root set to ``root`` (``--fast``: short stair-case)."""
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
    """A packaged qpp config with its results root set to ``root``."""
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
    """``design.h5`` of an acmm config: reused when its ``design_hash`` matches, else designed.

    ``donor_roots``: other run directories whose ``design.h5`` may be copied when its design hash
    matches (the ``--fast`` stair-case reuses the full stair-case's design).
    """
    from common.results import config_hash
    from acmm.stages import design_hash, run_design

    want = design_hash(cfg)
    path = cfg.run_dir() / "design.h5"
    chash = config_hash(cfg.to_yaml())
    if not rerun:
        a = _try_attrs(path)
        if a is not None and a.get("design_hash") == want:
            return _record("acmm design", cfg.name, path, chash, want, True, 0.0)
        for donor in donor_roots:
            a = _try_attrs(Path(donor) / "design.h5")
            if a is not None and a.get("design_hash") == want:
                path.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(Path(donor) / "design.h5", path)
                return _record("acmm design", cfg.name, path, chash, want, True, 0.0)
    t0 = time.perf_counter()
    _, path = run_design(cfg, figures=False)
    return _record("acmm design", cfg.name, path, chash, want, False, time.perf_counter() - t0)


def ensure_acmm_simulation(cfg, *, rerun: bool = False) -> StageRun:
    """``sim.h5`` of an acmm config: reused when config and design hashes match, else simulated."""
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
    """``qpp_design.h5`` (``stage="design"``) or ``qpp_sim.h5`` (``"simulate"``), reused by config hash."""
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
    """Configs and results files of one report."""

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

    Returns
    -------
    (dict or None, str)
        ``{"rows": [...], "header": [...], "verdict": str, "summary": str, "files": [paths]}``
        and a note.  Never raises: a missing or failing sweep makes the section "not available".
    """
    import importlib

    try:
        importlib.import_module("acmm.sweep")
    except ImportError as exc:
        return None, f"acmm.sweep is not installed in this tree ({exc.name or exc})"
    try:
        return _robustness_from_sweep(root, fast=fast, rerun=rerun)
    except (AcmmError, AttributeError, TypeError, KeyError, ValueError, OSError) as exc:
        return None, f"the sweep failed: {type(exc).__name__}: {exc}"


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
    from acmm.sweep_config import parse_sweep

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
# hashing (determinism)
# =============================================================================================
def dataset_hashes(path: Path, exclude: tuple[str, ...] = TIMING_DATASETS) -> dict[str, str]:
    """SHA-256 (16 hex digits) of every dataset of an HDF5 file: dtype, shape and bytes.

    Attributes (creation time, commit) and the datasets named in ``exclude`` (timings) are left
    out, so two runs of the same computation hash equal exactly when their numbers are equal.
    """
    import h5py

    from common.results import _dimension_only

    out: dict[str, str] = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and name.rsplit("/", 1)[-1] not in exclude and not _dimension_only(obj):
            arr = np.ascontiguousarray(obj[()])
            h = hashlib.sha256(f"{arr.dtype.str}|{arr.shape}|".encode())
            h.update(arr.tobytes() if arr.dtype.kind != "O" else repr(arr.tolist()).encode())
            out[name] = h.hexdigest()[:16]

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return dict(sorted(out.items()))


def build_manifest(g: Gathered) -> dict:
    files = {}
    for key, r in g.runs.items():
        files[key] = {"path": str(r.path), "config_hash": r.config_hash, "design_hash": r.design_hash,
                      "created_utc": r.created_utc, "reused": r.reused, "datasets": dataset_hashes(r.path)}
    return {"created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "git_commit": _git_commit(), "files": files}


def compare_manifests(old: dict | None, new: dict) -> dict:
    """Compare two manifests dataset by dataset.

    Returns
    -------
    dict
        ``status`` ("no previous report" | "identical" | "different"), ``compared`` (number of
        datasets compared), ``recomputed`` (files recomputed since the previous report, i.e.
        with a different creation time), ``differences`` (list of "file: dataset"), ``missing``.
    """
    if not old:
        return {"status": "no previous report", "compared": 0, "recomputed": 0, "differences": [],
                "missing": [], "previous": None}
    diffs, missing, compared, recomputed = [], [], 0, 0
    for key, f in new["files"].items():
        o = old.get("files", {}).get(key)
        if o is None or o.get("config_hash") != f["config_hash"]:
            missing.append(key)
            continue
        recomputed += o.get("created_utc") != f["created_utc"]
        for ds, h in f["datasets"].items():
            if ds not in o["datasets"]:
                missing.append(f"{key}: {ds}")
            else:
                compared += 1
                if o["datasets"][ds] != h:
                    diffs.append(f"{key}: {ds}")
    return {"status": "identical" if not diffs else "different", "compared": compared,
            "recomputed": recomputed, "differences": diffs, "missing": missing,
            "previous": old.get("created_utc")}


# =============================================================================================
# helpers
# =============================================================================================
def _git_commit() -> str:
    from common.results import git_commit

    return git_commit()


def _git_dirty() -> str:
    try:
        out = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                             cwd=Path(__file__).resolve().parent, capture_output=True, text=True, timeout=5)
        if out.returncode == 0:
            return "modified files present" if out.stdout.strip() else "clean"
    except (OSError, subprocess.SubprocessError):
        pass
    return "unknown"


def _h5(path):
    from common.results import read_h5

    return read_h5(path)


def _fmt(x, f="{:.4g}"):
    if x is None:
        return "—"
    if isinstance(x, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_fmt(v, f) for v in np.ravel(x)) + "]"
    return f.format(float(x))


# =============================================================================================
# document model: blocks rendered to Markdown and HTML alike
# =============================================================================================
@dataclass
class Doc:
    """A list of blocks: ("h", level, text, anchor), ("p", text), ("list", items),
    ("table", header, rows, caption), ("fig", stem, caption, files)."""

    blocks: list = field(default_factory=list)

    def h(self, level, text, anchor=""):
        self.blocks.append(("h", level, text, anchor))

    def p(self, text):
        self.blocks.append(("p", text))

    def ul(self, items):
        self.blocks.append(("list", list(items)))

    def table(self, header, rows, caption=""):
        self.blocks.append(("table", list(header), [[str(c) for c in r] for r in rows], caption))

    def fig(self, stem, caption, files):
        self.blocks.append(("fig", stem, caption, files))


def _decode(x) -> str:
    """A name stored as bytes (HDF5) or str, as str."""
    x = x.item() if hasattr(x, "item") else x
    return x.decode() if isinstance(x, bytes) else str(x)


def _md_cell(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def render_markdown(doc: Doc, title: str) -> str:
    out = [f"# {title}", ""]
    for b in doc.blocks:
        if b[0] == "h":
            out += [f"{'#' * (b[1] + 1)} {b[2]}", ""]
        elif b[0] == "p":
            out += [b[1], ""]
        elif b[0] == "list":
            out += [f"- {x}" for x in b[1]] + [""]
        elif b[0] == "table":
            _, header, rows, caption = b
            if caption:
                out += [f"*{caption}*", ""]
            out.append("| " + " | ".join(_md_cell(c) for c in header) + " |")
            out.append("|" + "---|" * len(header))
            out += ["| " + " | ".join(_md_cell(c) for c in r) + " |" for r in rows]
            out.append("")
        elif b[0] == "fig":
            _, stem, caption, files = b
            out += [f"![{caption}](figures/{stem}.png)", "",
                    f"*{caption}* ([PDF](figures/{stem}.pdf))", ""]
    return "\n".join(out)


_CSS = """
body{font-family:-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;margin:.6em 0 1.2em;font-size:.86em}
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:left;vertical-align:top}
th{background:#f2f2f2}caption{caption-side:top;text-align:left;font-style:italic;padding:.3em 0}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#444}
.ok{color:#0a6b2f;font-weight:600}.explained{color:#8a5a00}.bad{color:#b00020;font-weight:700}
nav ul{columns:2}code{background:#f5f5f5;padding:0 .2em}
"""


def _status_class(text: str) -> str:
    if text.startswith(STATUS_MATCHED) or text.startswith(STATUS_BOUND) or text.startswith("✔"):
        return "ok"
    if text.startswith(STATUS_UNEXPLAINED):
        return "bad"
    if text.startswith(STATUS_EXPLAINED):
        return "explained"
    return ""


def render_html(doc: Doc, title: str, figdir: Path) -> str:
    e = html.escape
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>{e(title)}</title>", '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<style>{_CSS}</style></head><body>", f"<h1>{e(title)}</h1>",
             "<nav><strong>Contents</strong><ul>"]
    parts += [f'<li><a href="#{a}">{e(t)}</a></li>' for a, t in SECTIONS]
    parts.append("</ul></nav>")
    for b in doc.blocks:
        if b[0] == "h":
            anchor = f' id="{e(b[3])}"' if b[3] else ""
            parts.append(f"<h{b[1] + 1}{anchor}>{e(b[2])}</h{b[1] + 1}>")
        elif b[0] == "p":
            parts.append(f"<p>{e(b[1])}</p>")
        elif b[0] == "list":
            parts.append("<ul>" + "".join(f"<li>{e(x)}</li>" for x in b[1]) + "</ul>")
        elif b[0] == "table":
            _, header, rows, caption = b
            t = ["<table>"]
            if caption:
                t.append(f"<caption>{e(caption)}</caption>")
            t.append("<thead><tr>" + "".join(f"<th>{e(c)}</th>" for c in header) + "</tr></thead><tbody>")
            for r in rows:
                cells = []
                for c in r:
                    cls = _status_class(c)
                    cells.append(f'<td class="{cls}">{e(c)}</td>' if cls else f"<td>{e(c)}</td>")
                t.append("<tr>" + "".join(cells) + "</tr>")
            t.append("</tbody></table>")
            parts.append("".join(t))
        elif b[0] == "fig":
            _, stem, caption, files = b
            data = base64.b64encode(Path(files["png"]).read_bytes()).decode("ascii")
            parts.append(f'<figure><img alt="{e(caption)}" src="data:image/png;base64,{data}">'
                         f'<figcaption>{e(caption)} (<a href="figures/{e(stem)}.pdf">vector PDF</a>, '
                         f'<a href="figures/{e(stem)}.png">PNG</a>)</figcaption></figure>')
    parts.append("</body></html>")
    return "\n".join(parts)


# =============================================================================================
# figures
# =============================================================================================
AXES = ("roll", "pitch", "yaw")


def fig_gain_schedule(design: dict, drf_mode: str, figdir: Path):
    """K(i, j) vs pitch TEA for the 24 columns: LQR gains (markers) and the schedule (lines)."""
    from acmm.linearize import STATE_NAMES, state_units
    from acmm.report_style import COLORS, pyplot, save
    from acmm.schedule import schedule_gain

    plt = pyplot()
    K, tea = design["K"], design["tea"]
    sc = design["schedule"]
    form = design["attrs"].get("schedule_form", "polynomial")
    th = tea[:, 1]
    fine = np.linspace(th.min(), th.max(), 120)
    kf = np.array([schedule_gain(form, sc["coef"], sc["variable"], K, t) for t in fine])
    units = state_units(drf_mode)
    fig, axs = plt.subplots(6, 4, figsize=(11, 14), sharex=True)
    for j, ax in enumerate(axs.flat):
        for i in range(3):
            ax.plot(np.degrees(th), K[:, i, j], "o", ms=3, color=COLORS[i], label=f"K({i + 1},{j + 1}) LQR")
            ax.plot(np.degrees(fine), kf[:, i, j], "-", color=COLORS[i], lw=1,
                    label=f"K({i + 1},{j + 1}) schedule")
        ax.set_title(f"K(i,{j + 1}): {STATE_NAMES[j]}", fontsize=8)
        ax.set_ylabel(f"ft·lbf / ({units[j]})", fontsize=6.5)
        ax.tick_params(labelsize=6.5)
    for ax in axs[-1]:
        ax.set_xlabel("pitch TEA θ2* (deg)")
    handles, _ = axs[0, 0].get_legend_handles_labels()
    labels = [f"{kind}, row i = {i + 1} ({AXES[i]} torque)" for i in range(3) for kind in ("LQR gain", "schedule")]
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=7, bbox_to_anchor=(0.5, 0.985))
    fig.suptitle(f"Gain schedule vs TEA: LQR gains (markers) and the order-{sc['coef'].shape[0] - 1} "
                 f"{form} schedule (lines); rows i = roll, pitch, yaw torque", y=0.995, fontsize=9)
    # a fixed layout: tight_layout on 24 panels costs as much as drawing them (issue 16)
    fig.subplots_adjust(left=0.075, right=0.985, bottom=0.04, top=0.93, wspace=0.42, hspace=0.32)
    return save(fig, figdir, "gain_schedule")


def _sector(ax, sigma, half_angle_deg, xmin):
    t = np.tan(np.radians(half_angle_deg))
    x = np.linspace(xmin, -sigma, 50)
    ax.fill_between(x, t * x, -t * x, color="0.92", label="sector (Fig 5.2)", zorder=0)
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.6)
    ax.plot(x, t * x, "k-", lw=0.6)
    ax.plot(x, -t * x, "k-", lw=0.6)


def fig_pole_maps(stair: dict, mb3: dict, dec: dict, dec_true_poles, n, sector, figdir: Path):
    """Closed-loop poles / n: the stair-case schedule points, and the claim-1 designs."""
    from acmm.report_style import COLORS, pyplot, save

    plt = pyplot()
    sigma, phi = sector
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.6))
    ax = axs[0]
    pts = [stair["points"][k] for k in sorted(stair["points"])]
    allp = np.concatenate([p["poles"] for p in pts]) / n
    _sector(ax, sigma, phi, min(allp.real.min() * 1.05, -2 * sigma))
    cmap = plt.get_cmap("viridis")
    th = np.degrees(stair["tea"][:, 1])
    for k, p in enumerate(pts):
        q = p["poles"] / n
        ax.plot(q.real, q.imag, "x", ms=4, color=cmap(k / max(1, len(pts) - 1)),
                label=f"θ2* = {th[k]:.1f}°" if k in (0, len(pts) - 1) else None)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re λ / n (n = orbital rate)")
    ax.set_ylabel("Im λ / n")
    ax.set_title(f"Stair-case schedule: {len(pts)} design points")
    ax.legend(loc="upper left")
    ax = axs[1]
    pc = mb3["points"][sorted(mb3["points"])[0]]["poles"] / n
    pd = dec["points"][sorted(dec["points"])[0]]["poles"] / n
    pt = np.asarray(dec_true_poles) / n
    xmin = min(pc.real.min(), pd.real.min(), -2 * sigma) * 1.05
    _sector(ax, sigma, phi, xmin)
    ax.plot(pc.real, pc.imag, "x", color=COLORS[0], label="coupled design, coupled model")
    ax.plot(pd.real, pd.imag, "+", color=COLORS[2], label="no-cross-inertia design, its own model")
    ax.plot(pt.real, pt.imag, "o", mfc="none", color=COLORS[1], label="no-cross-inertia gain, true coupled model")
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re λ / n")
    ax.set_ylabel("Im λ / n")
    ax.set_title("Claim 1 (MB3): closed-loop poles")
    ax.legend(loc="upper left")
    fig.tight_layout()
    return save(fig, figdir, "pole_maps")


def fig_claim1(mb3: dict, dec: dict, figdir: Path):
    """Attitude error, torque and momentum per axis: coupled vs cross-inertia-free (Figs 6.2–6.13)."""
    from acmm.report_style import COLORS, pyplot, save

    plt = pyplot()
    fig, axs = plt.subplots(4, 3, figsize=(11, 10))
    for a in range(3):
        for d, lab, c, ls in ((mb3, "coupled design", COLORS[0], "-"),
                              (dec, "no-cross-inertia design", COLORS[1], "--")):
            o = d["orbits"]
            axs[0, a].plot(o, np.degrees(d["attitude_error"][:, a]), ls, color=c, label=lab)
            early = o <= 0.1
            axs[1, a].plot(o[early], np.degrees(d["attitude_error"][early, a]), ls, color=c, label=lab)
            axs[2, a].plot(o, d["u"][:, a], ls, color=c, label=lab)
            axs[3, a].plot(o, d["h"][:, a], ls, color=c, label=lab)
        axs[0, a].set_title(AXES[a])
        for r in range(4):
            axs[r, a].set_xlabel("time (orbits)")
    axs[0, 0].set_ylabel("attitude error θ − θ* (deg)")
    axs[1, 0].set_ylabel("attitude error, first 0.1 orbit (deg)")
    axs[2, 0].set_ylabel("control torque (ft·lbf)")
    axs[3, 0].set_ylabel("CMG momentum (ft·lbf·s)")
    axs[0, 0].legend()
    fig.suptitle("Claim 1, MB3: fully coupled vs cross-inertia-free design on the nonlinear model", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, "claim1_responses")


def fig_staircase(sim: dict, figdir: Path):
    """Inertia steps (Figs 6.14–6.19) and the responses (Figs 6.20–6.30)."""
    from acmm.report_style import COLORS, pyplot, save

    plt = pyplot()
    o = sim["orbits"]
    inertia = sim["levels"]["inertia"][sim["level"]]
    fig1, axs = plt.subplots(2, 3, figsize=(11, 5.5), sharex=True)
    for ax, (i, j) in zip(axs.flat, [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
        ax.step(o, inertia[:, i, j] / 1e6, where="post", color=COLORS[0], label=f"I({i + 1},{j + 1})")
        ax.set_ylabel(f"I({i + 1},{j + 1}) (10⁶ slug·ft²)")
        ax.legend(loc="best")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig1.suptitle("Inertia variation MB3 → AC (Figs 6.14–6.19 analogue)", fontsize=10)
    fig1.tight_layout()
    f1 = save(fig1, figdir, "staircase_inertia")
    fig2, axs = plt.subplots(4, 3, figsize=(11, 10), sharex=True)
    rows = [(np.degrees(sim["attitude_error"]), "attitude error θ − θ̂* (deg)"),
            (np.degrees(sim["rate_rel_lvlh"]), "body rate rel. LVLH (deg/s)"),   # stored in rad/s
            (sim["u"], "control torque (ft·lbf)"), (sim["h"], "CMG momentum (ft·lbf·s)")]
    for r, (data, label) in enumerate(rows):
        for a in range(3):
            axs[r, a].plot(o, data[:, a], color=COLORS[a], lw=0.6, label=AXES[a])
            if r == 0:
                axs[r, a].set_title(AXES[a])
            if a == 0:
                axs[r, a].set_ylabel(label)
            for s in sim["levels"]["start"][1:] * sim["orbits"][-1] / max(sim["t"][-1], 1e-300):
                axs[r, a].axvline(s, color="0.7", lw=0.4, ls=":")
        axs[r, 0].legend(loc="upper right")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig2.suptitle("Gain-scheduled responses, inertia MB3 → AC (Figs 6.20–6.30 analogue; dotted: level changes)",
                  fontsize=10)
    fig2.subplots_adjust(left=0.08, right=0.985, bottom=0.055, top=0.94, wspace=0.28, hspace=0.12)  # issue 16
    f2 = save(fig2, figdir, "staircase_responses")
    fig3, axs = plt.subplots(1, 2, figsize=(11, 3.8))
    th = np.degrees(sim["levels"]["tea_estimate"][:, 1])[: len(sim["levels"]["steady_error"])]
    for a in range(3):
        axs[0].plot(th, np.degrees(sim["levels"]["steady_error"][:, a]), "o-", color=COLORS[a], label=AXES[a])
    axs[0].set_xlabel("pitch TEA of the level θ2* (deg)")
    axs[0].set_ylabel("steady |θ − θ̂*| (deg)")
    axs[0].set_title("Steady attitude error per level (second half of each dwell)")
    axs[0].legend()
    axs[1].plot(th, sim["levels"]["peak_momentum"], "s-", color=COLORS[3], label="peak |h_i| over the level")
    axs[1].set_xlabel("pitch TEA of the level θ2* (deg)")
    axs[1].set_ylabel("peak CMG momentum (ft·lbf·s)")
    axs[1].set_title("Peak momentum per level")
    axs[1].legend()
    fig3.tight_layout()
    f3 = save(fig3, figdir, "staircase_levels")
    return f1, f2, f3


def fig_robustness(params: dict, base, verdict, peak, names, figdir: Path):
    """Peak attitude error (deg) vs max_k |δ_k| per Monte Carlo case, one panel per base."""
    from acmm.report_style import COLORS, pyplot, save

    plt = pyplot()
    keys = [k for k in ("dI11", "dI22", "dI33", "dI12", "dI13", "dI23") if k in params]
    dmax = np.max(np.abs(np.column_stack([params[k] for k in keys])), axis=1) if keys else np.zeros(len(base))
    fig, axs = plt.subplots(1, len(names), figsize=(5.2 * len(names), 4.0), squeeze=False)
    for k, lab in enumerate(names):
        ax = axs[0, k]
        sel = base == k
        ok = sel & (verdict == "bounded")
        bad = sel & (verdict != "bounded")
        pk = np.full(len(base), np.nan)
        finite = np.isfinite(peak).any(axis=1)
        pk[finite] = np.nanmax(peak[finite], axis=1)
        ax.plot(100 * dmax[ok], pk[ok], "o", ms=3.5, color=COLORS[0], label="bounded")
        top = np.nanmax(pk[ok]) * 1.5 if ok.any() and np.isfinite(pk[ok]).any() else 60.0
        yb = np.where(np.isfinite(pk[bad]), pk[bad], top)
        ax.plot(100 * dmax[bad], np.minimum(yb, top), "x", ms=4, color=COLORS[1],
                label="diverged / no equilibrium (clipped)")
        ax.set_yscale("log")
        ax.set_xlabel("largest inertia-element perturbation max|δ| (%)")
        ax.set_ylabel("peak attitude error, worst axis (deg)")
        ax.set_title(f"{lab.upper()}: {int(ok.sum())}/{int(sel.sum())} bounded")
        ax.legend(loc="lower right")
    fig.tight_layout()
    return save(fig, figdir, "robustness")


def fig_qpp(sim_path: Path, design: dict, beta_o: float, name: str, figdir: Path, out_labels):
    """Per scenario: y and y_o; |y − y_o| against β_o (Figs 13.3–13.9, 14.4)."""
    import h5py

    from acmm.report_style import COLORS, pyplot, save

    plt = pyplot()
    with h5py.File(sim_path, "r") as f:
        scen = [k for k in f.keys() if isinstance(f[k], h5py.Group)]
        data = {k: {d: f[k][d][()].T for d in ("t", "y", "y_o", "r", "u")} for k in scen}   # stored (t, channel)
    p = next(iter(data.values()))["y"].shape[0]
    fig, axs = plt.subplots(2, len(scen), figsize=(3.8 * len(scen) + 1, 6.5), squeeze=False)
    for c, k in enumerate(scen):
        d = data[k]
        for i in range(p):
            axs[0, c].plot(d["t"], d["y"][i], "-", color=COLORS[i], label=f"y{i + 1} ({out_labels[i]})")
            axs[0, c].plot(d["t"], d["y_o"][i], "--", color=COLORS[i], lw=0.8, label=f"y_o{i + 1} nominal")
            axs[1, c].plot(d["t"], np.abs(d["y"][i] - d["y_o"][i]), color=COLORS[i],
                           label=f"|y{i + 1} − y_o{i + 1}| ({out_labels[i]})")
        axs[1, c].axhline(beta_o, color="k", ls=":", lw=0.8, label=f"β_o = {beta_o:g}")
        axs[1, c].set_yscale("log")
        axs[1, c].set_ylim(beta_o * 1e-5, beta_o * 3)
        axs[0, c].set_title(f"scenario {k}")
        axs[0, c].set_ylabel("output")
        axs[1, c].set_ylabel("tracking error |y − y_o|")
        for r in range(2):
            axs[r, c].set_xlabel("time t (s)")
        axs[0, c].legend(fontsize=6.5)
        axs[1, c].legend(fontsize=6.5, loc="lower right")
    fig.suptitle(f"{name}: nonlinear closed loop, output vs nominal output and the output sphere", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, f"{name}_responses")


def fig_circle(design: dict, name: str, figdir: Path):
    """Circle criterion (lemma 1): h_ii(−a + jω) with Gershgorin mean radii and the critical disc."""
    from acmm.report_style import COLORS, pyplot, save
    from qpp.circle import critical_disc

    plt = pyplot()
    c = design["circle"]
    centres, radii, sector = np.atleast_2d(c["centres"]), np.atleast_2d(c["radii"]), design["sector"]
    m = centres.shape[0]
    fig, axs = plt.subplots(1, m, figsize=(4.6 * m, 4.4), squeeze=False)
    for i in range(m):
        ax = axs[0, i]
        h = centres[i]
        for k in np.unique(np.linspace(0, h.size - 1, 150).astype(int)):
            ax.add_patch(plt.Circle((h[k].real, h[k].imag), radii[i, k], fill=False, lw=0.3, color="0.7"))
        ax.plot(h.real, h.imag, color=COLORS[0], label="h_ii(−a + jω), ω ≥ 0")
        ax.plot(h.real, -h.imag, "--", color=COLORS[0], lw=0.7, label="ω ≤ 0")
        al, be = sector[i]
        cc, R = critical_disc(al, be)
        ax.add_patch(plt.Circle((cc, 0), R, fill=False, color=COLORS[1], lw=1.4))
        ax.plot([], [], color=COLORS[1], label=f"critical disc D({al:g}, {be:g})")
        lim = 1.1 * max(abs(cc) + R, np.abs(h).max() + radii[i].max())
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("Re h_ii (dimensionless)")
        ax.set_ylabel("Im h_ii")
        ax.set_title(f"channel {i + 1}: margin {np.atleast_1d(c['margins'])[i]:.3g}")
        ax.legend(fontsize=6.5, loc="upper right")
    fig.suptitle(f"{name}: circle criterion (Figs 13.1, 14.2–14.3 analogue)", fontsize=10)
    fig.tight_layout()
    return save(fig, figdir, f"{name}_circle")


# =============================================================================================
# sections
# =============================================================================================
TABLE1_PRINTED = {
    "mb3": {"I11": "23.22", "I22": "1.30", "I33": "23.23", "I12": "-0.023", "I13": "0.477", "I23": "-0.011",
            "tea": ("1.3", "-44.7", "2.1")},
    "ac": {"I11": "50.28", "I22": "10.80", "I33": "58.57", "I12": "-0.39", "I13": "0.16", "I23": "0.16",
           "tea": ("0.19", "-5.0", "0.56")},
}


class _Report:
    """Builds the document section by section; every section also fills the printed-number ledger."""

    def __init__(self, g: Gathered, figdir: Path, fast: bool):
        self.g, self.figdir, self.fast = g, figdir, fast
        self.doc = Doc()
        self.ledger: list[PrintedNumber] = []
        self.cache: dict = {}
        self.timings: dict[str, float] = {}

    def run(self, key):
        return self.g.runs[key]

    def data(self, key):
        if key not in self.cache:
            self.cache[key] = _h5(self.run(key).path)
        return self.cache[key]

    def ledger_add(self, *args, **kw) -> PrintedNumber:
        pn = check_printed(*args, **kw)
        self.ledger.append(pn)
        return pn

    def status_text(self, pn: PrintedNumber) -> str:
        return pn.status if pn.status != STATUS_EXPLAINED else f"{STATUS_EXPLAINED}: {pn.note}"

    def section(self, key):
        title = dict(SECTIONS)[key]
        self.doc.h(1, title, key)

    # ------------------------------------------------------------------ Table 1
    def table1(self):
        from acmm import tea as tea_mod

        self.section("table1")
        self.doc.p("Table 1 of CR-185644 next to this run. The bias torque is not printed in the report: each "
                   "config uses the bias back-solved from eq 4.1 at the printed attitude (bias_from_tea), and the "
                   "TEA is then recomputed by continuation from LVLH (NOTES.md), so the computed TEA is an "
                   "independent solve of eqs 4.1–4.3, not a copy. The zero-bias TEA shows how much of each "
                   "attitude the inertia alone explains.")
        rows = []
        for name in ("mb3", "ac"):
            cfg = self.g.configs[name]
            pr = TABLE1_PRINTED[name]
            I = cfg.inertia.matrix()
            for key, (i, j) in zip(("I11", "I22", "I33", "I12", "I13", "I23"),
                                   [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
                pn = self.ledger_add("Table 1", f"{name.upper()} {key}", pr[key], I[i, j] / 1e6, "10⁶ slug·ft²")
                rows.append([name.upper(), f"{key} (10⁶ slug·ft²)", pr[key], f"{I[i, j] / 1e6:.4g}", "—",
                             self.status_text(pn)])
            bias = tea_mod.resolve_bias(cfg.disturbance, I, cfg.orbit_rate)
            t = tea_mod.solve_tea(I, cfg.orbit_rate, bias)
            t0 = tea_mod.solve_tea(I, cfg.orbit_rate, np.zeros(3))
            self.cache[f"tea:{name}"] = (t, t0, bias)
            for a in range(3):
                pn = self.ledger_add("Table 1", f"{name.upper()} θ{a + 1}*", pr["tea"][a], t.theta_deg[a], "deg")
                rows.append([name.upper(), f"θ{a + 1}* (deg)", pr["tea"][a], f"{t.theta_deg[a]:+.4f}",
                             f"{t0.theta_deg[a]:+.3f}", self.status_text(pn)])
        self.doc.table(["config", "quantity", "printed", "computed", "zero-bias TEA", "status"], rows,
                       "Table 1: printed vs computed (TEA residual of eq 4.1 below 1e-12 ft·lbf)")
        brow = []
        for name in ("mb3", "ac"):
            t, t0, bias = self.cache[f"tea:{name}"]
            brow.append([name.upper(), _fmt(bias, "{:+.5f}"), f"{t.residual:.1e}",
                         _fmt(np.degrees(t.omega) * 3600, "{:+.4f}")])
        self.doc.table(["config", "bias used [roll, pitch, yaw] (ft·lbf)", "residual (ft·lbf)", "ω* (deg/h)"], brow,
                       "Bias torques used (back-solved from eq 4.1 at the printed TEA; not printed in the report)")

    # ------------------------------------------------------------------ schedule
    def schedule(self):
        from acmm import linearize as lin

        self.section("schedule")
        d = self.data("acmm design:" + self.g.configs["staircase"].name)
        cfg = self.g.configs["staircase"]
        n = cfg.orbit_rate
        sc = d["schedule"]
        form = d["attrs"].get("schedule_form", "polynomial")
        order = sc["coef"].shape[0] - 1
        pts = [d["points"][k] for k in sorted(d["points"])]
        margins = np.array([float(p["sector_margin"]) for p in pts])
        resid = np.array([float(p["riccati_residual"]) for p in pts])
        self.doc.p(f"{len(pts)} design points along the MB3 → AC blend, evenly spaced in pitch TEA from "
                   f"{np.degrees(d['tea'][0, 1]):.2f}° to {np.degrees(d['tea'][-1, 1]):.2f}°; sector LQR "
                   f"(Re λ ≤ −{cfg.design.sector.sigma}n, {cfg.design.sector.half_angle_deg:g}°) per point, "
                   f"then an order-{order} {form} schedule in θ2* (the report uses order 2), fitted by "
                   f"{_decode(sc.get('fit_method', b'least_squares'))}"
                   " (README, 'Gain schedule').")
        cm = np.asarray(sc["check_margin"])
        self.doc.table(["quantity", "value"], [
            ["worst sector margin of the LQR gains (units of n, > 0 inside)", f"{margins.min():+.4f}"],
            ["worst relative Riccati residual (scaled coordinates)", f"{resid.max():.2e}"],
            ["worst relative schedule fit residual (RMS / max|K_ij|)", f"{np.max(sc['rel_residual']):.3f}"],
            [f"scheduled gain on the local models: worst sector margin over {cm.size} checks (points and "
             "midpoints, units of n)",
             f"{cm.min():+.4f} ({'all in the sector' if cm.min() > 0 else 'NOT all in the 45° sector'})"],
        ] + ([["scheduled gain on the local models: largest closed-loop Re λ over the checks (units of n)",
               f"{np.max(sc['check_max_real']):+.4f} "
               f"({'stable at every check' if np.max(sc['check_max_real']) < 0 else 'UNSTABLE at some check'})"]]
             if "check_max_real" in sc else []), "Stair-case design summary")
        self._schedule_conditioning(d, pts)
        files = fig_gain_schedule(d, cfg.design.drf_mode, self.figdir)
        self.doc.fig("gain_schedule", "Gain schedule: the 72 gains K(i, j) vs pitch TEA (Figs 5.3–5.26 analogue)",
                     files)
        # claim-1 pole map: the decoupled gain on the true coupled model
        mb3 = self.data("acmm design:mb3")
        dec = self.data("acmm design:mb3_decoupled")
        cfg_m = self.g.configs["mb3"]
        theta = dec["tea"][0]
        true = lin.design_point(cfg_m.inertia.matrix(), theta, n, model="coupled",
                                drf_mode=cfg_m.design.drf_mode)
        ev = np.linalg.eigvals(true.A - true.B @ dec["K"][0])
        self.cache["dec_true_poles"] = ev
        files = fig_pole_maps(d, mb3, dec, ev, n, (cfg.design.sector.sigma, cfg.design.sector.half_angle_deg),
                              self.figdir)
        self.doc.fig("pole_maps", "Closed-loop poles (units of n) and the sector of Fig 5.2: every stair-case "
                     "design point (left); the claim-1 designs and the cross-inertia-free gain on the true "
                     "coupled MB3 model (right)", files)

    def _schedule_conditioning(self, d, pts):
        """Per-point conditioning and robustness; the scheduled gain along the whole path."""
        from acmm import plots

        if "max_eig_condition" in pts[0]:
            rows = []
            for name, p in zip(d["names"], pts):
                rows.append([_decode(name), f"{np.degrees(float(p['tea'][1])):.2f}",
                             f"{float(p['sector_margin']):+.3f}", f"{float(p['max_eig_condition']):.2e}",
                             f"{float(p['robustness_radius']):.1e}",
                             f"{float(p['robustness_radius_elementwise']):.1e}",
                             f"{float(p['riccati_condition']):.1e}"])
            self.doc.table(["point", "θ2* (deg)", "sector margin (n)", "max eigenvalue condition (scaled)",
                            "sector robustness radius ‖δK‖/‖K‖", "radius, elementwise", "CARE condition"],
                           rows, "Design points: conditioning of the closed loop and the estimated smallest "
                                 "relative gain error that moves a pole out of the sector (first order)")
        sc = d["schedule"]
        if "path" not in sc:
            return
        pa = sc["path"]
        mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
        self.doc.table(["quantity along the path", "value"], [
            ["TEAs checked (evenly spaced, first to last design point)", f"{mr.size}"],
            ["largest Re λ of the scheduled local loop (units of n)", f"{mr.max():+.3f}"],
            ["worst sector margin (units of n)", f"{mg.min():+.3f}"],
            ["fraction of the path with every pole in the sector", f"{float(np.mean(mg >= 0)):.3f}"],
            ["smallest disk margin α at the plant input (skew 0)", f"{dm.min():.3f}"],
        ], "The order-2 schedule judged on the closed loop at every path TEA")
        f1 = plots.schedule_path_check(pa["theta2"], mr, mg, dm, self.figdir / "schedule_path_margins", vector=True)
        self.doc.fig("schedule_path_margins", "Scheduled gain on the local model along the path: largest Re λ, "
                     "worst sector margin and disk margin at the plant input vs pitch TEA",
                     {"png": f1[0], "pdf": f1[1]})
        cfg = self.g.configs["staircase"]
        f2 = plots.scheduled_pole_map(pa["poles"], pa["theta2"], cfg.orbit_rate, cfg.design.sector.sigma,
                                      cfg.design.sector.half_angle_deg, self.figdir / "schedule_path_poles",
                                      vector=True)
        self.doc.fig("schedule_path_poles", "Poles of the scheduled loop at every path TEA with the sector of "
                     "Fig 5.2", {"png": f2[0], "pdf": f2[1]})

    # ------------------------------------------------------------------ claim 1
    def claim1(self):
        self.section("claim1")
        n = self.g.configs["mb3"].orbit_rate
        s_c, s_d = self.data("acmm simulate:mb3"), self.data("acmm simulate:mb3_decoupled")
        dd = self.data("acmm design:mb3_decoupled")
        ev = self.cache["dec_true_poles"]
        rows = []
        for lab, s, dkey in (("coupled (eq 4.46)", s_c, "mb3"), ("no cross-inertia (I12=I13=I23=0)", s_d,
                                                                   "mb3_decoupled")):
            a = s["attrs"]
            dz = self.data(f"acmm design:{dkey}")
            p = dz["points"][sorted(dz["points"])[0]]
            rows.append([lab, f"{float(p['sector_margin']):+.3f}", f"{float(p['riccati_residual']):.1e}",
                         a["verdict"].upper(), f"{float(a['stop_time_orbits']):.3f}",
                         f"{np.degrees(np.abs(s['attitude_error'])).max():.2f}"])
        self.doc.table(["design model", "sector margin (n)", "Riccati residual", "nonlinear verdict",
                        "stopped at (orbit)", "peak |θ − θ*| (deg)"], rows,
                       "Claim 1 on the nonlinear MB3 model (same TEA, initial condition and disturbances)")
        o, err = s_c["orbits"], np.degrees(np.abs(s_c["attitude_error"]))
        first = err[o <= 1.0].max(axis=0)
        late = err[o >= 2.0].max(axis=0) if (o >= 2.0).any() else np.full(3, np.nan)
        div = float(s_d["attrs"]["stop_time_orbits"])
        self.claim1_numbers = {"div": div, "maxre": ev.real.max() / n, "first": first, "late": late}
        self.doc.ul([
            f"Cross-inertia-free design: {s_d['attrs']['verdict']} at {div:.3f} orbit "
            f"({div * 2 * np.pi / n / 60:.1f} min) — the report: 'unstable within less than one-tenth of an orbit'.",
            f"Its gain on the true coupled linear model: largest Re λ = {ev.real.max() / n:+.3f} n "
            f"({'unstable' if ev.real.max() > 0 else 'stable'}) although all its design-model poles lie in the sector.",
            f"Coupled design: {s_c['attrs']['verdict']}; peak |error| in the first orbit "
            f"{_fmt(first, '{:.2f}')} deg (roll, pitch, yaw); from orbit 2 on {_fmt(late, '{:.2f}')} deg.",
            f"Verdict: claim 1 {'REPRODUCED' if (div < 0.1 and s_c['attrs']['verdict'] == 'bounded') else 'NOT reproduced'}.",
        ])
        self.ledger_add("Claim 1", "divergence of the cross-inertia-free design", "0.1", div, "orbit",
                        bound="upper")
        self.doc.fig("claim1_responses", "Claim 1: attitude error (full run and first 0.1 orbit), torque and "
                     "momentum per axis (Figs 6.2–6.13 analogue)",
                     fig_claim1(s_c, s_d, self.figdir))

    # ------------------------------------------------------------------ stair-case
    def staircase(self):
        self.section("staircase")
        cfg = self.g.configs["staircase"]
        s = self.data("acmm simulate:" + cfg.name)
        a = s["attrs"]
        if self.fast:
            self.doc.p(f"FAST MODE (--fast): the stair-case is shortened to {FAST_ORBITS:g} orbits "
                       f"(about one orbit per level). Run `acmm report` without --fast for the report's 130 orbits.")
        lv = s["levels"]
        o = s["orbits"]
        self.doc.p(f"{len(lv['start'])} inertia levels over {o[-1]:.1f} orbits, scheduled gain K(θ̂2*) per level, "
                   f"torque limit ±{cfg.actuators.torque_limit:g} ft·lbf, momentum limit "
                   f"±{cfg.actuators.momentum_limit:g} ft·lbf·s. Verdict: {a['verdict'].upper()} ({a['reason']}).")
        orbit = 2 * np.pi / cfg.orbit_rate
        rows = []
        for k in range(len(lv["steady_error"])):
            rows.append([str(k), f"{lv['start'][k] / orbit:.1f}", f"{np.degrees(lv['tea_estimate'][k, 1]):+.2f}",
                         f"{lv['inertia'][k, 0, 0] / 1e6:.2f} / {lv['inertia'][k, 1, 1] / 1e6:.2f} / "
                         f"{lv['inertia'][k, 2, 2] / 1e6:.2f}",
                         " / ".join(f"{v:.3f}" for v in np.degrees(lv["steady_error"][k])),
                         f"{lv['peak_momentum'][k]:.0f}"])
        self.doc.table(["level", "start (orbit)", "θ2* (deg)", "I11 / I22 / I33 (10⁶ slug·ft²)",
                        "steady |θ − θ̂*| roll / pitch / yaw (deg)", "peak |h| (ft·lbf·s)"], rows,
                       "Per-level statistics (steady: second half of each dwell)")
        tsat = float(np.mean(np.any(s["torque_saturated"] > 0, axis=1)))
        msat = float(np.mean(np.any(s["momentum_saturated"] > 0, axis=1)))
        self.doc.p(f"Samples with a torque-saturated axis: {100 * tsat:.2f} %; with a momentum-saturated axis: "
                   f"{100 * msat:.2f} %. Peak |u| = {np.abs(s['u']).max():.1f} ft·lbf, peak |h| = "
                   f"{np.abs(s['h']).max():.0f} ft·lbf·s.")
        if not self.fast:
            self.ledger_add("Claim 2", "stair-case length", "130", o[-1], "orbit")
        i0, i1 = lv["inertia"][0], lv["inertia"][-1] if len(lv["inertia"]) else lv["inertia"][0]
        if not self.fast:
            off = [(0, 1), (0, 2), (1, 2)]
            var = max(100 * abs(i1[i, j] / i0[i, j] - 1) for i, j in off if i0[i, j] != 0)
            self.ledger_add("Claim 2", "largest cross-inertia variation MB3 → AC ('up to 1600 %')", "1600", var,
                            "%", bound="upper")
        f1, f2, f3 = fig_staircase(s, self.figdir)
        self.doc.fig("staircase_inertia", "Inertia elements vs time (Figs 6.14–6.19 analogue)", f1)
        self.doc.fig("staircase_responses", "Attitude error, rate, torque and momentum per axis (Figs 6.20–6.30 "
                     "analogue)", f2)
        self.doc.fig("staircase_levels", "Per-level steady error and peak momentum vs the level's pitch TEA", f3)

    # ------------------------------------------------------------------ robustness
    def robustness(self):
        self.section("robustness")
        self.doc.p("The report (ch. 7): 'the closed-loop system remains stable for up to ±30 % variations in "
                   "the SSF inertia matrix'. It does not say which variations (elements, scaling), which TEA "
                   "estimate or which design were used.")
        r = self.g.robustness
        if r is None:
            self.doc.p(f"Not available in this run: {self.g.robustness_note}. "
                       "(The sweep of issue 7, acmm.sweep.run_sweep with configs/sweep_inertia30.yaml, provides it.)")
            self.ledger.append(PrintedNumber("Robustness", "stable for ±30 % inertia variation", "30", None, "%",
                                             STATUS_EXPLAINED, "not evaluated in this run: " + self.g.robustness_note))
            return
        d = r["data"]
        names = [x.decode() if isinstance(x, bytes) else str(x) for x in np.atleast_1d(d["base_names"])]
        verdict = np.array([x.decode() if isinstance(x, bytes) else str(x) for x in np.atleast_1d(d["verdict"])])
        base = np.atleast_1d(d["base"])
        peak = np.degrees(np.atleast_2d(d["peak_attitude_error"]))   # stored in rad
        params = d["parameters"]
        if r["fast"]:
            self.doc.p(f"FAST MODE: reduced sweep, {r['n_runs']} Monte Carlo runs per base of {r['orbits']:g} orbits, "
                       "no margin search. Run without --fast for the 200-run sweep of configs/sweep_inertia30.yaml.")
        self.doc.p(f"Sweep {r['run'].config}: every inertia element multiplied by (1 + δ), δ ~ U(−0.3, 0.3) "
                   f"independently (unphysical draws redrawn), seed {r['seed']}, {r['n_runs']} runs per base, "
                   f"{r['orbits']:g} orbits each; design '{r['design']}', TEA estimate '{r['tea_estimate']}' "
                   "(the controller does not know the perturbation); bias torque held at its nominal value.")
        rows, fracs = [], {}
        for k, lab in enumerate(names):
            sel = base == k
            v = verdict[sel]
            nb = int(np.sum(v == "bounded"))
            fracs[lab] = nb / max(1, v.size)
            others = ", ".join(f"{x} {int(np.sum(v == x))}" for x in sorted(set(v)) if x != "bounded")
            pk = peak[sel][v == "bounded"]
            med = _fmt(np.median(pk, axis=0), "{:.2f}") if pk.size else "—"
            mx = _fmt(np.max(pk, axis=0), "{:.2f}") if pk.size else "—"
            lim = ""
            mg = d.get("margin", {})
            if f"{lab}_down" in mg and f"{lab}_up" in mg:
                lim = f"[{float(mg[f'{lab}_down']['limit']):.3f}, {float(mg[f'{lab}_up']['limit']):.3f}]"
            rows.append([lab.upper(), f"{nb}/{v.size} ({100 * fracs[lab]:.0f} %)", others or "—", med, mx, lim or "—"])
        self.doc.table(["base", "bounded", "other verdicts", "median peak |err| r/p/y (deg), bounded",
                        "max peak |err| r/p/y (deg), bounded", "uniform scaling s tolerated"], rows,
                       "±30 % inertia Monte Carlo with the fixed nominal designs")
        verdict_txt = ("REPRODUCED" if all(f == 1.0 for f in fracs.values()) else
                       "NOT reproduced for arbitrary ±30 % element variations with the fixed nominal design "
                       "and nominal TEA estimate")
        self.doc.p(f"Verdict: the ±30 % robustness statement is {verdict_txt}.")
        self.ledger.append(PrintedNumber(
            "Robustness", "stable for ±30 % inertia variation", "30", None, "%", STATUS_EXPLAINED,
            "bounded fraction of the ±30 % element draws: " +
            ", ".join(f"{k.upper()} {100 * v:.0f} %" for k, v in fracs.items()) +
            ("" if all(f == 1.0 for f in fracs.values()) else
             "; the report does not define its variations, estimate or design, so the statement cannot be "
             "checked as printed; this is the strictest reading (unknown perturbation, fixed gains)")))
        files = fig_robustness(params, base, verdict, peak, names, self.figdir)
        self.doc.fig("robustness", "±30 % inertia Monte Carlo: peak attitude error vs the largest element "
                     "perturbation per case (bounded: filled; diverged or no equilibrium: crosses)", files)

    # ------------------------------------------------------------------ QPP
    def _qpp(self, key, name, printed_errors, out_labels):
        import h5py

        from qpp.hinf import hinf_gains

        self.section(key)
        cfg = self.g.configs[name]
        dpath, spath = self.run(f"qpp design:{name}").path, self.run(f"qpp simulate:{name}").path
        d = self.data(f"qpp design:{name}")
        pub = cfg.published
        chap = "13" if key == "qpp13" else "14"
        rows = []
        dgkf = hinf_gains(cfg.lure_plant(), rho=cfg.hinf.rho, a=cfg.hinf.a, nu=cfg.hinf.nu,
                          weight=cfg.hinf.weight, observer="dgkf")
        for gname, comp, printed in (("K1", d["K1"], pub.K1), ("Kc", d["Kc"], pub.Kc), ("H", d["H"], pub.H)):
            P = np.asarray(printed, float)
            for idx in np.ndindex(P.shape):
                if P[idx] == 0.0:
                    continue
                ps = _printed_str(P[idx], gname)
                expl = ""
                if gname == "H":
                    dv = float(np.asarray(dgkf.H)[idx])
                    expl = (f"observer gain from the filter Riccati (NOTES.md: printed eq 11.2 has an indefinite "
                            f"solution); DGKF-style reading gives {dv:.4f}"
                            + (" (matched)" if matches_printed(ps, dv) else "")
                            + f"; within {100 * abs(comp[idx] - P[idx]) / abs(P[idx]):.1f} % of the printed value")
                pn = self.ledger_add(f"ch. {chap}", f"{gname}{tuple(int(i) + 1 for i in idx)}", ps, comp[idx],
                                     explanation=expl)
                rows.append([f"{gname}{tuple(int(i) + 1 for i in idx)}", ps, f"{comp[idx]:.5g}", self.status_text(pn)])
        self.doc.table(["gain", "printed", "computed (ch. 11 Riccati)", "status"], rows,
                       f"Ch. {chap} gains (ρ = {cfg.hinf.rho:g}, a = {cfg.hinf.a:g} 1/s, servo weight [0 C_c])")
        with h5py.File(dpath, "r") as f:
            b1 = {rd: (float(f[f"beta1_{rd.replace('.', '_')}"][()]),
                       float(f[f"beta1_{rd.replace('.', '_')}"].attrs["grid_value"]),
                       float(f[f"beta1_{rd.replace('.', '_')}"].attrs["omega_peak_rad_s"])) for rd in ("eq10.7", "printed")}
            names = f["thresholds"].attrs["description"].split(":")[-1].replace(" ", "").split(",")
            circle_passed = bool(f.attrs["circle_passed"])
        th = {nm: row for nm, row in zip(names, np.atleast_2d(d["thresholds"]))}
        brow = []
        expl_b1 = (f"β1 is computed exactly (L∞ norm) for both readings of B_z: eq 10.7 gives {b1['eq10.7'][0]:.5f}, "
                   f"the printed B_z (H in the r-columns) {b1['printed'][0]:.5f}; the printed value matches neither "
                   "(NOTES.md: it looks like a coarse frequency grid)")
        pn = self.ledger_add(f"ch. {chap}", "β1", _num_str(pub.beta1), b1["eq10.7"][0], explanation=expl_b1)
        for rd, (v, gv, w) in b1.items():
            brow.append([f"β1, B_z {rd}", _num_str(pub.beta1), f"{v:.6f} (peak at {w:.4g} rad/s)",
                         self.status_text(pn) if rd == "eq10.7" else "see above"])
        m_pr = th["printed"][3] if "printed" in th else None
        pn_m = self.ledger_add(f"ch. {chap}", "m (from printed β3, β4)", _num_str(pub.m), m_pr)
        brow.append(["m = β_o/(β_ri + ‖d‖∞ + β_o β3 + β4), printed β3, β4", _num_str(pub.m), f"{m_pr:.5f}",
                     self.status_text(pn_m)])
        for nm, row in th.items():
            if nm == "printed":
                continue
            brow.append([f"β3 / β4 / m, {nm} bookkeeping", f"{pub.beta3} / {pub.beta4} / {pub.m}",
                         f"{row[1]:.5g} / {row[2]:.5g} / {row[3]:.5f}", "see the errata table"])
        for rd, (v, _, _) in b1.items():
            verd = ", ".join(f"{nm}: {'β1 ≤ m' if v <= row[3] else 'β1 > m'}" for nm, row in th.items())
            brow.append([f"design inequality β1 ≤ m, B_z {rd}", "β1 < m", verd, ""])
        brow.extend(self._qpp_printed_gain_rows(chap, d, pub, names))
        brow.append(["circle criterion (lemma 1), sector " + _fmt(d["sector"], "{:g}"), "satisfied",
                     f"{'PASS' if circle_passed else 'FAIL'}; margins {_fmt(d['circle']['margins'], '{:.4f}')}; "
                     f"largest admissible sector scale {float(d['circle']['max_scale']):.4g}",
                     "✔ reproduced" if circle_passed else "not reproduced"])
        self.doc.table(["quantity", "printed", "computed", "status"], brow,
                       f"Ch. {chap}: β1, thresholds and the circle criterion")
        self._qpp_thresholds(chap, cfg, th)
        with h5py.File(spath, "r") as f:
            scen = [k for k in f.keys() if isinstance(f[k], h5py.Group)]
            erow = []
            for k in scen:
                e = float(f[k]["error_inf"][()])
                per = np.atleast_1d(f[k]["error_per_output"][()])
                pas = bool(f[k]["error_inf"].attrs["passed"])
                erow.append([k, f"{float(f[k]['error_inf'].attrs['gamma']):g}", _fmt(per, "{:.5f}"),
                             f"{e:.5f}", f"{cfg.spheres.beta_o:g}", "within" if pas else "OUTSIDE"])
                for (scn, i, pstr, bound, expl) in printed_errors:
                    if scn == k:
                        self.ledger_add(f"ch. {chap}", f"‖y{i + 1} − y_o{i + 1}‖∞, {k}", pstr, per[i],
                                        out_labels[i], bound=bound, explanation=expl)
        self.doc.table(["scenario", "γ / payload", "sup |y_i − y_oi| per output", "‖y − y_o‖∞", "β_o", "sphere"],
                       erow, f"Ch. {chap}: simulated tracking errors (nonlinear closed loop)")
        led = [pn for pn in self.ledger if pn.section == f"ch. {chap}" and pn.quantity.startswith("‖y")]
        if led:
            self.doc.table(["printed", "quantity", "computed", "status"],
                           [[p.printed, p.quantity, _fmt(p.computed, "{:.5f}"), self.status_text(p)] for p in led],
                           "Printed simulation results")
        self.doc.fig(f"{name}_circle", f"Ch. {chap}: circle criterion", fig_circle(d, name, self.figdir))
        self.doc.fig(f"{name}_responses", f"Ch. {chap}: outputs vs nominal outputs and tracking errors",
                     fig_qpp(spath, d, cfg.spheres.beta_o, name, self.figdir, out_labels))

    def _qpp_printed_gain_rows(self, chap, d, pub, names=()):
        """β1, β3, β4, m of the *printed* gains (qpp_design.h5 ``published_certificate``) beside the
        synthesized ones; β1 of the printed gains also enters the ledger."""
        pc = d.get("published_certificate") if isinstance(d, dict) else None
        if not pc:
            return []
        rows = []
        b1e, b1p = float(pc["beta1_eq10_7"]), float(pc["beta1_printed"])
        pn = self.ledger_add(f"ch. {chap}", "β1 of the printed gains (B_z eq 10.7)", _num_str(pub.beta1), b1e,
                             explanation=f"printed gains, exact L∞ norm: {b1e:.5f} (eq 10.7 B_z), {b1p:.5f} "
                                         "(printed B_z); see the β1 row above for the synthesized gains")
        rows.append(["β1 with the printed gains, B_z eq 10.7 / printed", _num_str(pub.beta1),
                     f"{b1e:.6f} / {b1p:.6f}", self.status_text(pn)])
        for k, row in enumerate(np.atleast_2d(pc["thresholds"])):
            nm = f", {names[k]} bookkeeping" if k < len(names) else ""
            rows.append([f"β3 / β4 / m with the printed gains{nm}", f"{pub.beta3} / {pub.beta4} / {pub.m}",
                         f"{row[1]:.5g} / {row[2]:.5g} / {row[3]:.5f}", "printed gains"])
        rows.append(["circle criterion with the printed gains", "satisfied",
                     "PASS" if int(pc["circle_passed"]) else "FAIL", ""])
        return rows

    def _qpp_thresholds(self, chap, cfg, th):
        from qpp import spheres

        pub = cfg.published
        if chap == "13":
            nl = cfg.nonlinearity
            b3_5 = spheres.beta3_sinusoidal(0.05, 5.0, cfg.spheres.T)
            b3_1 = spheres.beta3_sinusoidal(0.05, nl.omega, cfg.spheres.T)
            self.ledger_add("ch. 13", "β3 = 0.05‖(sin 5t)_T‖₂, T = 0.5 s", _num_str(pub.beta3), b3_5,
                            explanation=f"the exact integral gives 0.05‖(sin 5t)_T‖₂ = {b3_5:.5f} "
                                        f"({100 * abs(b3_5 - pub.beta3) / pub.beta3:.2f} % above the printed value, "
                                        "presumably a coarse quadrature); the definition 10.54 with sin t gives "
                                        f"{b3_1:.5f} (NOTES.md)")
            self.cache["beta3"] = (b3_5, b3_1)
            b4 = th["report"][2]
            self.ledger_add("ch. 13", "β4 = 0.05·‖(y_o)_T‖₂", _num_str(pub.beta4), b4,
                            explanation=f"‖(y_o)_T‖₂ = {b4 / 0.05:.4f} here vs the printed 0.363: y_o is the "
                                        "nominal closed-loop output on [0, T], which depends on the gains and the "
                                        "initial servo state; m changes by "
                                        f"{abs(th['report'][3] - pub.m) / pub.m * 100:.1f} %")
        else:
            b3, b4 = th["trajectory"][1], th["trajectory"][2]
            why = (f"the arm mass μ is not printed (μ = {cfg.nonlinearity.mu:g} kg assumed) and the report does not "
                   "say how β3, β4 were evaluated; here they are sup over M ∈ [45, 55] kg along the nominal trajectory")
            self.ledger_add("ch. 14", "β3", _num_str(pub.beta3), b3, explanation=why + f" (β3 = {b3:.3g})")
            self.ledger_add("ch. 14", "β4", _num_str(pub.beta4), b4, explanation=why + f" (β4 = {b4:.3g})")

    def qpp(self):
        why14 = ("μ (arm mass) and the impulse size are not printed; this run uses μ = {mu:g} kg and impulse "
                 "{imp} at t = {ti:g} s (configs/qpp_manipulator.yaml), so the error sizes differ; both stay far "
                 "inside β_o = 0.14")
        self._qpp("qpp13", "qpp_siso", [("step_offset", 0, "0.094", "upper", ""),
                                         ("sin10", 0, "0.16", "upper", "")], ["y"])
        c = self.g.configs["qpp_manipulator"]
        sc0 = c.simulation.scenarios[0]
        w = why14.format(mu=c.nonlinearity.mu, imp=sc0.impulse, ti=sc0.impulse_time or 0.0)
        self._qpp("qpp14", "qpp_manipulator", [("M45", 0, "0.006", None, w), ("M45", 1, "0.0015", None, w)],
                  ["m", "rad"])

    # ------------------------------------------------------------------ errata
    def errata(self):
        self.section("errata")
        self.doc.p("Each misprint or convention of NOTES.md, the correction used, and the evidence: numbers "
                   "computed in this run where the check is cheap, otherwise the test file that confirms it.")
        rows = errata_rows(self)
        self.doc.table(["item", "printed / claim", "correction used", "evidence (this run)", "confirmed by"], rows)

    # ------------------------------------------------------------------ printed numbers
    def printed(self):
        self.section("printed")
        counts = {}
        for pn in self.ledger:
            counts[pn.status] = counts.get(pn.status, 0) + 1
        self.doc.p("Every printed number this report compares, with its status. Matched: |computed − printed| ≤ "
                   "half a unit of the last printed digit. Summary: " +
                   "; ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".")
        self.doc.table(["section", "quantity", "printed", "computed", "unit", "status"],
                       [[p.section, p.quantity, p.printed, "—" if p.computed is None else f"{p.computed:.6g}",
                         p.unit, self.status_text(p)] for p in self.ledger])


def _printed_str(v: float, gname: str) -> str:
    """The printed form of a gain (K: one decimal; H: four decimals, as in the report)."""
    return f"{v:.4f}" if gname == "H" else f"{v:.1f}"


def _num_str(v) -> str:
    return repr(float(v)) if v is not None else "—"


# =============================================================================================
# errata evidence
# =============================================================================================
def errata_rows(rep: _Report) -> list[list[str]]:
    """Rows of the errata table, with the evidence computed from this run (cheap checks only)."""
    from acmm import dynamics as dyn
    from acmm import linearize as lin
    from acmm import lqr
    from acmm import riccati as ric
    from acmm import tea as tea_mod
    from common.errors import ConvergenceError, NoEquilibriumError

    cfg = rep.g.configs["mb3"]
    n, I = cfg.orbit_rate, cfg.inertia.matrix()
    t, t0, bias = rep.cache["tea:mb3"]
    th = t.theta
    rows = []

    # eq 3.6
    def printed_f(theta):
        s1, s3, k1, k3 = np.sin(theta[0]), np.sin(theta[2]), np.cos(theta[0]), np.cos(theta[2])
        return np.array([[1, -k1 * s3, s1 * s3], [0, k1, -s1], [0, s1 * k3, k1 * k3]]) / k3

    def eq42(theta, f):
        return f(theta) @ dyn.lvlh_rate_in_body(theta, n) + np.array([0, n, 0])

    th_test = np.radians([10.0, -30.0, 25.0])
    r_mb3, r_test = np.abs(eq42(th, printed_f)).max(), np.abs(eq42(th_test, printed_f)).max()
    r_ok = max(np.abs(eq42(th, dyn.kinematics_matrix)).max(), np.abs(eq42(th_test, dyn.kinematics_matrix)).max())
    rows.append(["eq 3.6 (1,1) entry", "1 inside the bracket", "cos θ3 (so f11 = 1; eq 4.4 already uses it)",
                 f"printed f violates eq 4.2 (θ̇ = 0 at θ*) by {r_mb3:.2e} rad/s at the MB3 TEA and {r_test:.2e} rad/s "
                 f"({r_test / n:.3f} n) at θ = (10°, −30°, 25°); corrected f: {r_ok:.1e} rad/s",
                 "tests/test_dynamics.py"])
    rows.append(["eqs 3.1, 3.8 momentum", "—", "I ω̇ + ḣ + ω×(Iω + h) = τgg + w holds exactly, also saturated",
                 "checked along a saturated trajectory", "tests/test_dynamics.py, tests/test_simulate.py"])
    # TEA branches
    roots = tea_mod.all_equilibria(I, n, np.zeros(3))
    pitches = sorted({round(float(r.theta_deg[1]), 2) for r in roots})
    rows.append(["TEA roots (eqs 4.1–4.3)", "one TEA per configuration", "continuation from LVLH picks the "
                 "physical branch", f"MB3, zero bias: {len(roots)} equilibria found, pitch {pitches} deg; "
                 f"continuation gives {t0.theta_deg[1]:+.2f}°; Table 1 TEAs reproduced with back-solved bias "
                 f"{_fmt(bias, '{:+.4f}')} ft·lbf", "tests/test_tea.py"])
    cap = 3 * n ** 2 * np.hypot((I[2, 2] - I[0, 0]) / 2, I[0, 2])
    try:
        tea_mod.solve_tea(I, n, np.array([0.0, 4.0, 0.0]))
        msg = "an equilibrium was found (unexpected)"
    except NoEquilibriumError as exc:
        msg = "no equilibrium: " + str(exc).split(":", 1)[-1].strip()
    rows.append(["4 ft·lbf pitch bias (Wie et al. 1989)", "used with MB3", "MB3 has no TEA for it",
                 f"largest gravity-gradient pitch torque of MB3 = {cap:.3f} ft·lbf < 4; solve_tea: {msg}",
                 "tests/test_tea.py"])
    # linearization
    m = lin.design_point(I, th, n, model="coupled", drf_mode=cfg.design.drf_mode)
    d = cfg.design

    def design_on(A, B):
        try:
            r = lqr.sector_lqr(A, B, d.R * np.eye(3), n, sigma=d.sector.sigma,
                               half_angle_deg=d.sector.half_angle_deg, scale=m.scales)
        except AcmmError as exc:
            return f"design fails ({exc})"
        ev = np.linalg.eigvals(m.A - m.B @ r.K)
        return (f"a design on it (margin {r.margin:+.3f} n on its own model) is "
                f"{'UNSTABLE' if ev.real.max() > 0 else 'stable'} on the true model: max Re λ = {ev.real.max() / n:+.2f} n")

    # numerical Jacobian of τgg vs the closed form of 4.12–4.14 (corrected)
    h = 1e-6
    num = np.column_stack([(dyn.gravity_gradient_torque(th + h * e, I, n) - dyn.gravity_gradient_torque(th - h * e, I, n))
                           / (2 * h) for e in np.eye(3)])
    ana = dyn.gravity_gradient_jacobian(th, I, n)
    rows.append(["eqs 4.12–4.14 ∂τgg/∂θ", "prefactor −3n²; row 2 lacks −I23·B1·C1; 4.13/4.14 garbled",
                 "3n²(d_k×Ic + c×I d_k), d_k = ∂c/∂θ_k",
                 f"closed form vs central differences at the MB3 TEA: max difference "
                 f"{np.abs(num - ana).max():.1e} ft·lbf/rad (entries up to {np.abs(ana).max():.2f}); "
                 f"with the printed sign: {np.abs(num + ana).max():.2f} ft·lbf/rad",
                 "tests/test_linearize.py (numerical Jacobian of the nonlinear model, 50 random cases)"])
    rows.append(["eq 4.28 E1", "1/cos θ1 scales all of E1", "rows 1–3 only; rows 4–6 identity", "—",
                 "tests/test_linearize.py"])
    rows.append(["eq 4.29 column 6", "τgg² term in rows 1–3", "τgyr²·n·sin θ3 (units)", "—", "tests/test_linearize.py"])
    rows.append(["eqs 4.30, 4.33, 4.49 signs", "u, w signs", "u enters ω̇ as −u and ḣ as +u; w enters ω̇ as +w",
                 "input sign reversed: " + design_on(m.A, -m.B), "tests/test_dynamics.py, tests/test_linearize.py"])
    a2 = m.A[6:9, 6:9]
    Ap = m.A.copy()
    Ap[8, 6] = -Ap[8, 6]
    rows.append(["eq 4.34 A2(3,1)", "+n cos θ1 cos θ3", "−n cos θ1 cos θ3 (block −[ω*×] skew-symmetric)",
                 f"A2(3,1) = {a2[2, 0]:+.4e} rad/s; printed sign gives |A2 + A2ᵀ|max = {2 * abs(a2[2, 0]):.3e} rad/s "
                 f"(ours {np.abs(a2 + a2.T).max():.1e}); " + design_on(Ap, m.B), "tests/test_linearize.py"])
    Aq = m.A.copy()
    for src, good, bad in ((4, 20, 21), (5, 22, 23)):
        Aq[bad, src], Aq[good, src] = Aq[good, src], 0.0
    rows.append(["eq 4.44 DRF input rows", "θ2, θ3 drive rows 10, 12 of x3", "rows 9, 11 (β̇2, β̇3)",
                 "printed rows: " + design_on(Aq, m.B), "tests/test_linearize.py"])
    # eq 5.6
    alpha = d.sector.sigma * n
    As, Bs, Qs = ric.scale_problem(m.A + alpha * np.eye(24), m.B, np.zeros((24, 24)), m.scales)
    Rm = d.R * np.eye(3)
    Ham = np.block([[As, -Bs @ np.linalg.solve(Rm, Bs.T)], [-Qs, -As.T]])
    try:
        ric.matrix_sign(Ham, form="printed", max_iter=100)
        pr = "converged (unexpected)"
    except ConvergenceError as exc:
        pr = str(exc)
    ok = ric.matrix_sign(Ham)
    f = lambda x: x * (5 + 10 * x ** 2 + x ** 4) / (1 + 10 * x + 5 * x ** 4)  # noqa: E731
    rows.append(["eq 5.6 sign iteration", "denominator I + 10S + 5S⁴", "I + 10S² + 5S⁴",
                 f"scalar: printed map sends −1 to {f(-1.0):g} (sign(−1) is not a fixed point); MB3 scaled "
                 f"Hamiltonian (48×48): printed form — {pr}; corrected form converges in {ok.iterations} iterations",
                 "tests/test_riccati.py"])
    # scaling
    D = np.diag(m.scales)
    sc_rows = []
    for meth in ("scipy", "slycot", "sign"):
        try:
            P, _ = ric.solve_unverified(m.A + alpha * np.eye(24), m.B, np.zeros((24, 24)), Rm, method=meth)
            sc_rows.append(f"{meth} {ric.care_residual(As, Bs, Qs, Rm, D @ P @ D):.1e}")
        except (ConvergenceError, ImportError) as exc:
            sc_rows.append(f"{meth} failed ({type(exc).__name__})")
    scaled = []
    for meth in ("scipy", "slycot", "sign"):
        try:
            res = ric.solve_care(m.A + alpha * np.eye(24), m.B, np.zeros((24, 24)), Rm, method=meth,
                                 scale=m.scales, tol=np.inf)
            scaled.append(f"{meth} {res.residual:.1e}")
        except (ConvergenceError, ImportError) as exc:
            scaled.append(f"{meth} failed ({type(exc).__name__})")
    rows.append(["state scaling", "Riccati solved in physical units", "scale states by nominal magnitudes; "
                 "residual checked scaled", f"MB3 state scales span {m.scales.max() / m.scales.min():.1e}; "
                 f"relative residual (scaled coordinates), unscaled solve: {', '.join(sc_rows)}; scaled solve: "
                 f"{', '.join(scaled)}", "tests/test_riccati.py"])
    # sector LQR
    st = rep.data("acmm design:" + rep.g.configs["staircase"].name)
    pts = [st["points"][k] for k in sorted(st["points"])]
    ctrb = lin.controllability(lin.design_point(I, th, n, model="no_cross_inertia", drf_mode=d.drf_mode))
    rows.append(["sector LQR (Sunkel–Shieh)", "algorithm cited, not available", "shifted LQR + optimal pole "
                 "shifting of the DRF poles (Amin 1985); K exact LQR gain of a Q ⪰ 0",
                 f"{len(pts)} stair-case points: worst margin {min(float(p['sector_margin']) for p in pts):+.4f} n, "
                 f"worst residual {max(float(p['riccati_residual']) for p in pts):.1e}; cross-inertia-free MB3 model "
                 f"PBH σmin/σmax = {ctrb.min_ratio:.1e} (nearly uncontrollable)", "tests/test_lqr.py, tests/test_design.py"])
    sim = rep.data("acmm simulate:" + rep.g.configs["staircase"].name)
    rows.append(["saturation", "±150 ft·lbf, 20 000 ft·lbf·s", "CMG at its limit delivers only the torque that stops "
                 "|h_i| growing", f"stair-case: peak |u| {np.abs(sim['u']).max():.1f} ft·lbf, peak |h| "
                 f"{np.abs(sim['h']).max():.0f} ft·lbf·s", "tests/test_simulate.py"])
    c1 = rep.claim1_numbers
    rows.append(["claim 1", "cross-inertia-free design unstable within 0.1 orbit",
                 "design: minimum-energy shifted LQR (Q0 = 0, R = I/(100 ft·lbf)²) + pole shifting of the DRF poles",
                 f"diverges at {c1['div']:.3f} orbit; its gain on the true linear model: max Re λ = {c1['maxre']:+.3f} n; "
                 f"coupled design bounded, peak error first orbit {_fmt(c1['first'], '{:.1f}')} deg, from orbit 2 "
                 f"{_fmt(c1['late'], '{:.2f}')} deg", "tests/test_simulate.py"])
    # Part III
    s13 = rep.g.configs["qpp_siso"]
    d13 = rep.data("qpp design:qpp_siso")
    rows.append(["signs of 13.6 / Table 14.1", "u = +K x̂, L = −H; plant f sign differs (13.1/14.2 vs 10.1)",
                 "as NOTES.md", "A_z rebuilt from the printed gains equals 13.6 / Table 14.1",
                 "tests/test_qpp_core.py"])
    b = {rd: float(d13[f"beta1_{rd.replace('.', '_')}"]) for rd in ("eq10.7", "printed")}
    rows.append(["B_z of 13.6 / Table 14.1", "H in the r-columns of the observer rows", "eq 10.7 (zeros); β1 "
                 "reported for both", f"ch. 13 β1 = {b['eq10.7']:.5f} (eq 10.7), {b['printed']:.5f} (printed B_z); "
                 f"printed 1.61454", "tests/test_qpp_core.py"])
    rows.append(["ch. 11 weights", "state weight [C 0]ᵀ[C 0]; Lyapunov 11.2 for the observer",
                 "servo weight [0 C_c]ᵀ[0 C_c]; filter Riccati H = −h Cᵀ",
                 f"ch. 13 K1 = {_fmt(d13['K1'], '{:.1f}')}, Kc = {_fmt(d13['Kc'], '{:.1f}')} (printed "
                 f"{_fmt(s13.published.K1, '{:.1f}')}, {_fmt(s13.published.Kc, '{:.1f}')})",
                 "tests/test_qpp_core.py"])
    b3_5, b3_1 = rep.cache.get("beta3", (np.nan, np.nan))
    th13 = np.atleast_2d(d13["thresholds"])
    rows.append(["β3 (10.54) and m", "β3 = 0.02727; half-width 0.05 in m, [−0.5, 0.5] in the circle check",
                 "β3 = 0.05‖(sin 5t)_T‖₂; both bookkeepings reported",
                 f"0.05‖(sin 5t)_T‖₂ = {b3_5:.5f} at T = 0.5 s; with sin t: {b3_1:.5f}; m = "
                 + ", ".join(f"{v[3]:.4f}" for v in th13) + " (printed, report, circle bookkeepings)",
                 "tests/test_qpp_core.py"])
    a = rep.g.configs["qpp_manipulator"]
    rows.append(["ch. 14 target and unknowns", "Y_A1, Y_A2 ambiguous; μ, impulse not printed",
                 "Y_A1 = (x1 + a) sin x2, Y_A2 = (x1 + a) cos x2; μ and impulse are config parameters",
                 f"μ = {a.nonlinearity.mu:g} kg, impulse {a.simulation.scenarios[0].impulse} at "
                 f"t = {a.simulation.scenarios[0].impulse_time} s", "tests/test_qpp_cli.py"])
    return rows


# =============================================================================================
# entry point
# =============================================================================================
@dataclass
class ReportResult:
    """Files written by :func:`build_report` and what they contain."""

    out: Path
    html: Path
    markdown: Path
    manifest: Path
    figures: list
    stages: list
    ledger: list
    determinism: dict
    wall_time: float
    sections: list = field(default_factory=lambda: [k for k, _ in SECTIONS])
    #: wall time (s) of the gathering, of each stage group and of each section (issue 16)
    timings: dict = field(default_factory=dict)

    @property
    def unexplained(self) -> list:
        return [p for p in self.ledger if p.status == STATUS_UNEXPLAINED]


def build_report(out: Path | str = "runs/report", *, fast: bool = False, rerun: bool = False,
                 root: Path | str | None = None, progress: Callable[[str], None] | None = None,
                 robustness: bool = True) -> ReportResult:
    """Gather (or reuse) every result and write ``index.html``, ``report.md``, figures and manifest.

    Parameters
    ----------
    out : path
        Output directory (created).
    fast : bool
        CI mode: stair-case of :data:`FAST_ORBITS` orbits.
    rerun : bool
        Recompute every stage even when matching results exist (to check determinism against the
        previous report in ``out``).
    root : path or None
        Results root for the stages (default: each config's ``output.root``, i.e. ``runs``).
    progress : callable or None
        Called with one line of text per step.

    Returns
    -------
    ReportResult
    """
    t_start = time.perf_counter()
    say = progress or (lambda msg: None)
    out = Path(out)
    from common.errors import OutputError

    try:
        out.mkdir(parents=True, exist_ok=True)
        figdir = out / "figures"
        figdir.mkdir(exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the report directory {out}: {exc.strerror or exc}") from None
    say(f"gathering results ({'fast' if fast else 'full'} mode, root {root or 'from configs'})")
    g = gather(Path(root) if root is not None else None, fast=fast, rerun=rerun, progress=say,
               robustness=robustness)
    t_gather = time.perf_counter() - t_start
    rep = _Report(g, figdir, fast)
    say("writing sections and figures")
    t1 = time.perf_counter()
    from acmm import parallel_figures

    parallel_figures.enable()            # figures written by forked processes meanwhile (issue 16)
    try:
        for key in ("table1", "schedule", "claim1", "staircase", "robustness", "qpp", "errata", "printed"):
            t_sec = time.perf_counter()
            getattr(rep, key)()
            rep.timings[key] = time.perf_counter() - t_sec
            say(f"  section {key:<12} {rep.timings[key]:6.2f} s")
    finally:
        t_sec = time.perf_counter()
        parallel_figures.wait()
        rep.timings["figure writers (wait)"] = time.perf_counter() - t_sec
    t_sections = time.perf_counter() - t1
    # determinism
    man_path = out / "manifest.json"
    old = None
    if man_path.exists():
        try:
            old = json.loads(man_path.read_text())
        except (OSError, ValueError):
            old = None
    manifest = build_manifest(g)
    cmp = compare_manifests(old, manifest)
    _determinism_section(rep, cmp, manifest)
    total = time.perf_counter() - t_start
    _provenance_section(rep, g, {"gather (all stages)": t_gather, "sections, evidence and figures": t_sections,
                                 "total": total})
    title = "CR-185644 regenerated: ACMM (Part II) and QPP (Part III)" + (" — fast mode" if fast else "")
    md = render_markdown(rep.doc, title)
    page = render_html(rep.doc, title, figdir)
    manifest["determinism"] = {k: v for k, v in cmp.items() if k != "differences"}
    write_text(man_path, json.dumps(manifest, indent=1))
    write_text(out / "report.md", md)
    write_text(out / "index.html", page)
    figs = sorted(figdir.glob("*.png"))
    say(f"wrote {out / 'index.html'} ({len(figs)} figures) in {time.perf_counter() - t_start:.1f} s")
    res = ReportResult(out, out / "index.html", out / "report.md", man_path, figs, list(g.runs.values()),
                       rep.ledger, cmp, time.perf_counter() - t_start)
    res.timings = {"gather": t_gather, **g.timings, **rep.timings, "total": res.wall_time}
    return res


def _determinism_section(rep: _Report, cmp: dict, manifest: dict) -> None:
    rep.section("determinism")
    n_ds = sum(len(f["datasets"]) for f in manifest["files"].values())
    rep.doc.p(f"{len(manifest['files'])} HDF5 files, {n_ds} datasets hashed (SHA-256 of dtype, shape and bytes; "
              f"timing datasets {', '.join(TIMING_DATASETS)} and file attributes such as the creation time excluded); "
              "hashes are stored in manifest.json next to this page.")
    if cmp["status"] == "no previous report":
        rep.doc.p("No previous report in this directory: nothing to compare yet. Run the report again "
                  "(with --rerun to recompute every stage) to compare.")
    else:
        rec = cmp["recomputed"]
        rep.doc.p(f"Compared with the previous report of {cmp['previous']}: {cmp['compared']} datasets, "
                  f"{rec} of {len(manifest['files'])} files recomputed since then "
                  f"({'the others reused, identical by construction' if rec < len(manifest['files']) else 'none reused'}). "
                  f"Result: {cmp['status'].upper()}"
                  + (f" ({len(cmp['differences'])} datasets differ: {', '.join(cmp['differences'][:10])})"
                     if cmp["differences"] else " — every dataset has the same hash.")
                  + (f" Not compared (new or changed config): {', '.join(cmp['missing'][:10])}." if cmp["missing"] else ""))


def _provenance_section(rep: _Report, g: Gathered, timings: dict) -> None:
    import h5py
    import matplotlib
    import scipy

    from acmm import __version__

    rep.section("provenance")
    commit = _git_commit()
    rows = [["package", f"acmm-qpp {__version__}"], ["git commit", f"{commit} ({_git_dirty()})"],
            ["date (UTC)", datetime.now(timezone.utc).isoformat(timespec="seconds")],
            ["python", platform.python_version()], ["numpy / scipy", f"{np.__version__} / {scipy.__version__}"],
            ["h5py / matplotlib", f"{h5py.__version__} / {matplotlib.__version__}"],
            ["machine", f"{platform.system()} {platform.machine()}, {os.cpu_count()} CPUs"],
            ["mode", "fast (CI)" if rep.fast else "full"]]
    rows += [[f"wall time: {k}", f"{v:.1f} s"] for k, v in timings.items()]
    if g.robustness_wall:
        rows.append(["wall time: robustness sweep", f"{g.robustness_wall:.1f} s"])
    rep.doc.table(["item", "value"], rows, "Software and run")
    srows = []
    for r in g.runs.values():
        stale = "" if (not r.git_commit or r.git_commit == commit) else " (other commit)"
        srows.append([r.stage, r.config, r.config_hash, r.design_hash or "—", str(r.path),
                      "reused" if r.reused else "computed", "—" if r.reused else f"{r.wall_time:.1f}",
                      f"{r.created_utc}, {r.git_commit[:10]}{stale}"])
    rep.doc.table(["stage", "config", "config hash", "design hash", "file", "this run", "wall time (s)",
                   "file created, commit"], srows,
                  "Stages: results reused when the stored config hash (design hash for designs) matches")
