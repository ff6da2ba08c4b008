"""``build_report``: gather the results, write every section, render, hash and compare.

The sections cover Table 1, ch. 5–7 of Part II and ch. 13–14 of Part III (:mod:`acmm.report.sections`,
run as parts of :mod:`acmm.report.plan`); the three closing ones, written here once the others are
done, list the printed numbers of all of them, compare the dataset hashes with the previous
report's (determinism) and state the software, run and stage files used (provenance).
"""
from __future__ import annotations

import contextlib
import json
import os
import platform
import shutil
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

import h5py
import matplotlib
import numpy as np
import scipy

from acmm import __version__
from acmm_qpp.errors import OutputError
from acmm_qpp.outputs import file_identity, run_lock, write_text
from acmm_qpp.provenance import git_commit, git_dirty
from acmm_qpp.signals import interrupts_deferred
from acmm.report.constants import SECTIONS, TIMING_DATASETS
from acmm.report.context import SectionWriter
from acmm.report.document import render_html, render_markdown
from acmm.report.ledger import status_text
from acmm.report.gather import Gathered, keep_stage, order_runs, report_configs, stage_tasks, warm_workers
from acmm.report.manifest import build_manifest, compare_manifests
from acmm.report.plan import PARTS, run_part, section_tasks
from acmm.report.publish import publish
from acmm.report.runner import default_jobs, run_tasks
import resource

#: Kind of the report's figure staging folder (``<out>/.figures-<pid>-<random>``): the next report
#: in that folder removes one a killed report left (:func:`acmm_qpp.outputs.run_lock`'s ``staging``).
FIGURE_STAGING = "figures"


@dataclass
class ReportResult:
    """Files written by :func:`build_report` and what they contain.

    Attributes
    ----------
    out : pathlib.Path
        Output directory.
    html : pathlib.Path
        ``index.html``.
    markdown : pathlib.Path
        ``report.md``.
    manifest : pathlib.Path
        ``manifest.json``.
    figures : list of pathlib.Path
        The PNG figures.
    stages : list of acmm.report.gather.StageRun
        The results files used.
    ledger : list of acmm.report.ledger.PrintedNumber
        Every printed number compared.
    determinism : dict
        :func:`acmm.report.manifest.compare_manifests` with the previous report.
    wall_time : float
        Total wall time, s.
    sections : list of str
        Section keys.
    timings : dict
        Wall time of the gathering, each stage group and each section, s, and the total CPU
        time, s.
    jobs : int
        Processes that ran the stages and sections (1: all in this process).
    tasks : dict
        Task name of the graph (stages and section parts) → ``(wall s, CPU s)`` of the process
        that ran it.
    failures : list of (str, acmm.report.gather.Failed)
        Section key and failure of each part or section that failed, in section order (shown in
        the report; ``acmm report`` then exits with the first one's exit code).
    root : pathlib.Path or None
        The results root the stages ran in.
    """

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
    timings: dict = field(default_factory=dict)
    jobs: int = 1                   #: processes that ran the stages and sections
    tasks: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)
    root: Path | None = None        #: the results root of the stages


def build_report(out: Path | str = "runs/report", *, fast: bool = False, rerun: bool = False,
                 root: Path | str | None = None, progress: Callable[[str], None] | None = None,
                 robustness: bool = True, jobs: int | None = None) -> ReportResult:
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
        Results root of the stages, which the report computes in (``<root>/<name>/``, figures
        off; files there are replaced); default ``<out>/results``, the report's own, so a
        user's ``runs/<name>/`` is never written.
    progress : callable or None
        Called with one line of text per step.
    robustness : bool
        Include the ±30 % inertia robustness sweep.
    jobs : int or None
        Processes that run the stages and the section parts (:mod:`acmm.report.runner`); default
        :func:`acmm.report.runner.default_jobs` (2 on a multi-core POSIX machine); 1: one after the
        other in this process.  The output is the same.

    Returns
    -------
    ReportResult
        The files written and what they contain.  A stage, part or section that raised a
        user-facing error (:func:`acmm.report.gather.failed`) is shown in its section with that
        error, the others complete, and it is listed in :attr:`ReportResult.failures`; a bug
        propagates and nothing is written.

    Raises
    ------
    OutputError
        The output directory cannot be created, or the results root is not a directory.
    """
    t_start = time.perf_counter()
    cpu0 = _cpu()
    say = progress or (lambda msg: None)
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    out, figdir = Path(out), Path(out) / "figures"
    root = out / "results" if root is None else Path(root)      # its own: never a user's runs/<name>/
    # one report at a time per folder; holding its lock, the report removes the staging folders
    # (.figures-<pid>-*) a killed report left (acmm_qpp.outputs.remove_leftovers)
    with run_lock(out, staging=(FIGURE_STAGING,)):
        if root.exists() and not root.is_dir():     # every stage would fail: refused before anything is written
            raise OutputError(f"--root: the results root {root} is not a directory")
        created = [figdir] if not figdir.exists() else []
        try:
            figdir.mkdir(exist_ok=True)
            staged = Path(tempfile.mkdtemp(prefix=f".{FIGURE_STAGING}-{os.getpid()}-", dir=out))
        except OSError as exc:
            _remove_empty(created)
            raise OutputError(f"cannot create the report directory {out}: {exc.strerror or exc}") from None
        say(f"gathering results and writing sections ({'fast' if fast else 'full'} mode, root "
            f"{root}, {jobs} process{'es' if jobs > 1 else ''})")
        try:
            res = _build_into(out, figdir, staged, root, fast, rerun, robustness, jobs, say, t_start, cpu0)
        except BaseException:
            shutil.rmtree(staged, ignore_errors=True)
            _remove_empty(created)               # a refused or failed report leaves no empty folders behind
            raise
        shutil.rmtree(staged, ignore_errors=True)
    return res


def _build_into(out: Path, figdir: Path, staged: Path, root, fast, rerun, robustness, jobs, say, t_start, cpu0):
    """The report, its figures drawn into ``staged`` and moved into ``figdir`` only with the
    pages: an interrupted or failed report leaves ``--out`` as it was (its figures were written
    as their tasks finished, beside the previous report's pages: a review)."""
    g, rep, timings, stats, jobs, failures = _run_graph(root, staged, fast, rerun, robustness, jobs, say)
    _add(rep, failures, "printed", _printed, list(rep.ledger))
    # determinism
    man_path = out / "manifest.json"
    try:
        old = json.loads(man_path.read_text())          # the previous report's
    except (OSError, ValueError):                       # none, or unreadable
        old = None
    manifest = build_manifest(g)
    cmp = compare_manifests(old, manifest)
    _add(rep, failures, "determinism", _determinism, cmp, manifest)
    total = time.perf_counter() - t_start
    _add(rep, failures, "provenance", _provenance, g, {
        "stages (until the last one finished)": timings["stages"],
        f"stages and sections ({jobs} process{'es' if jobs > 1 else ''})": timings["graph"], "total": total})
    title = "CR-185644 regenerated: ACMM (Part II) and QPP (Part III)" + (" — fast mode" if fast else "")
    md = render_markdown(rep.doc, title)
    page = render_html(rep.doc, title, staged)          # (embeds the PNGs it reads there)
    manifest["determinism"] = {k: v for k, v in cmp.items() if k != "differences"}
    # the stages' locks are not held while sections read: another run of that name may have rewritten one
    changed = [k for k, ident in g.identities.items() if file_identity(g.runs[k].path) != ident]
    if changed:
        raise OutputError(f"{changed[0]}: its results file {g.runs[changed[0]].path} was rewritten while the "
                          "report ran (another run of that name?); nothing was written: run the report again")
    pairs = [(f, figdir / f.name) for f in sorted(staged.iterdir())]
    pages = staged / ".pages"          # written beside the figures first: a full disk changes nothing
    try:
        pages.mkdir()
    except OSError as exc:
        raise OutputError(f"cannot write the report in {out}: {exc.strerror or exc}; nothing was written") from None
    for name, text in (("manifest.json", json.dumps(manifest, indent=1)), ("report.md", md), ("index.html", page)):
        pairs.append((write_text(pages / name, text), out / name))
    with interrupts_deferred():                        # the figures and the pages go together
        publish(pairs, staged / ".replaced")
    figs = sorted(figdir.glob("*.png"))
    say(f"wrote {out / 'index.html'} ({len(figs)} figures) in {time.perf_counter() - t_start:.1f} s")
    wall = time.perf_counter() - t_start
    res = ReportResult(out, out / "index.html", out / "report.md", man_path, figs, list(g.runs.values()),
                       rep.ledger, cmp, wall, timings={**timings, "total": wall, "cpu (all processes)": _cpu() - cpu0},
                       jobs=jobs, tasks=stats, failures=failures, root=root)
    for section, f in failures:
        say(f"  section {section}: {f.text()}")
    return res


def _cpu() -> float:
    """User + system CPU time (s) of this process and of its finished children."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _run_graph(root, figdir: Path, fast: bool, rerun: bool, robustness: bool, jobs: int, say):
    """Stages and section parts as one task graph (:mod:`acmm.report.runner`); returns the gathered
    results, the writer holding every content section, the wall times (s: stages, graph, each stage
    group and section), each task's (wall s, CPU s), the processes used and the failed parts."""
    t0 = time.perf_counter()
    g = Gathered(report_configs(root, fast=fast), {})
    rep = SectionWriter(g, figdir, fast)
    stages = stage_tasks(g.configs, root, fast=fast, rerun=rerun, robustness=robustness, jobs=jobs)
    names = {t.name for t in stages}
    parts = section_tasks(g, figdir, fast, names, rep.results if jobs == 1 else None)
    timings: dict[str, float] = {"stages": 0.0}
    stats: dict[str, tuple] = {}

    def on_done(name, result):
        if name in names:
            keep_stage(g, name, result, say)
            timings["stages"] = time.perf_counter() - t0
        else:
            say(f"  part {name:<20} {result.seconds:6.2f} s")

    done = run_tasks(stages + parts, jobs, on_done, warm=warm_workers, stats=stats)
    timings["graph"] = time.perf_counter() - t0
    order_runs(g, stages)
    sections: dict[str, float] = {}
    failures: list = []
    for name, section, *_ in PARTS:         # in section order, whichever process wrote which part
        _append(rep, failures, section, done[name])
        sections[section] = sections.get(section, 0.0) + done[name].seconds
    for key, sec in sections.items():
        say(f"  section {key:<12} {sec:6.2f} s")
    timings.update(g.timings)
    timings.update({f"section {k}": v for k, v in sections.items()})
    return g, rep, timings, stats, min(jobs, len(stages) + len(parts)), failures     # run_tasks forks no more


def _add(rep: SectionWriter, failures: list, key: str, build, *args):
    """Run one section's ``build`` as a part (:func:`acmm.report.plan.run_part`, a fresh writer) and
    :func:`_append` it as section ``key``; returns its value."""
    part = run_part(build, rep.g, rep.figdir, rep.fast, args, rep.results, key, key)
    _append(rep, failures, key, part)
    return part.value


def _append(rep: SectionWriter, failures: list, section: str, part) -> None:
    """Append the blocks and printed numbers of ``part`` (a :class:`acmm.report.plan.Part`) to
    ``rep``, and ``(section, Failed)`` to ``failures`` when it failed (its blocks then show the
    section's heading and the error)."""
    if part.failed is not None:
        failures.append((section, part.failed))
    rep.doc.blocks.extend(part.blocks)
    rep.ledger.extend(part.ledger)


def _printed(ctx: SectionWriter, ledger: list) -> None:
    """Section printed numbers: every entry of ``ledger`` (all sections before this one), with its
    status."""
    ctx.section("printed")
    counts = Counter(pn.status for pn in ledger)
    ctx.doc.p("Every printed number this report compares, with its status. Matched: |computed − printed| ≤ "
              "half a unit of the last printed digit. Summary: " +
              "; ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".")
    ctx.doc.table(["section", "quantity", "printed", "computed", "unit", "status"],
                  [[p.section, p.quantity, p.printed, "—" if p.computed is None else f"{p.computed:.6g}",
                    p.unit, status_text(p)] for p in ledger])


def _determinism(rep: SectionWriter, cmp: dict, manifest: dict) -> None:
    """Section determinism: this report's ``manifest`` (:func:`acmm.report.manifest.build_manifest`)
    and its comparison ``cmp`` with the previous report's (:func:`acmm.report.manifest.compare_manifests`)."""
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
                     if cmp["differences"] else " — every dataset has the same hash." if cmp["compared"]
                     else " — no file of the previous report has the same name and config.")
                  + (f" Not compared (new or changed config): {', '.join(cmp['missing'][:10])}." if cmp["missing"] else ""))


def _provenance(rep: SectionWriter, g: Gathered, timings: dict) -> None:
    """Section provenance: software, machine, wall times (``timings``: step → s) and every stage file
    of ``g`` used."""
    rep.section("provenance")
    commit = git_commit()
    tree = {"yes": "modified files present", "no": "clean"}.get(git_dirty(), "unknown")   # no git: unknown
    rows = [["package", f"acmm-qpp {__version__}"], ["git commit", f"{commit} ({tree})"],
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


def _remove_empty(dirs: list) -> None:
    """Remove the folders ``dirs`` (innermost last in the list) that are empty."""
    for d in reversed(dirs):
        with contextlib.suppress(OSError):
            d.rmdir()
