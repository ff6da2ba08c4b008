"""``build_report``: gather the results, write every section, render, hash and compare.

The sections cover Table 1, ch. 5–7 of Part II and ch. 13–14 of Part III.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from common.errors import OutputError
from common.results import write_text
from report.constants import SECTIONS
from report.context import SectionWriter
from report.document import render_html, render_markdown
from report.gather import gather
from report.ledger import STATUS_UNEXPLAINED
from report.manifest import build_manifest, compare_manifests
from report.sections import claim1 as sec_claim1
from report.sections import determinism as sec_determinism
from report.sections import errata as sec_errata
from report.sections import printed as sec_printed
from report.sections import provenance as sec_provenance
from report.sections import qpp as sec_qpp
from report.sections import robustness as sec_robustness
from report.sections import schedule as sec_schedule
from report.sections import staircase as sec_staircase
from report.sections import table1 as sec_table1


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
    stages : list of report.gather.StageRun
        The results files used.
    ledger : list of report.ledger.PrintedNumber
        Every printed number compared.
    determinism : dict
        :func:`report.manifest.compare_manifests` with the previous report.
    wall_time : float
        Total wall time, s.
    sections : list of str
        Section keys.
    timings : dict
        Wall time of the gathering, each stage group and each section, s.
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
    #: wall time (s) of the gathering, of each stage group and of each section (issue 16)
    timings: dict = field(default_factory=dict)

    @property
    def unexplained(self) -> list:
        """The ledger entries whose status is ``NOT EXPLAINED``."""
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
    robustness : bool
        Include the ±30 % inertia robustness sweep.

    Returns
    -------
    ReportResult
        The files written and what they contain.

    Raises
    ------
    OutputError
        The output directory cannot be created.
    """
    t_start = time.perf_counter()
    say = progress or (lambda msg: None)
    out = Path(out)
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
    rep = SectionWriter(g, figdir, fast)
    say("writing sections and figures")
    timings: dict[str, float] = {}
    t1 = time.perf_counter()
    from acmm import parallel_figures

    parallel_figures.enable()            # figures written by forked processes meanwhile (issue 16)
    try:
        _write_sections(rep, timings, say)
    finally:
        t_sec = time.perf_counter()
        parallel_figures.wait()
        timings["figure writers (wait)"] = time.perf_counter() - t_sec
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
    _add(rep, "determinism", sec_determinism.build, cmp, manifest)
    total = time.perf_counter() - t_start
    _add(rep, "provenance", sec_provenance.build, g, {"gather (all stages)": t_gather,
                                                      "sections, evidence and figures": t_sections, "total": total})
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
    res.timings = {"gather": t_gather, **g.timings, **timings, "total": res.wall_time}
    return res


def _add(rep: SectionWriter, key: str, build, *args):
    """Run one section's ``build`` in a fresh writer and append its blocks and ledger to ``rep``."""
    w = rep.section_writer()
    result = build(w, *args)
    rep.doc.blocks.extend(w.doc.blocks)
    rep.ledger.extend(w.ledger)
    return result


def _write_sections(rep: SectionWriter, timings: dict, say) -> None:
    """The content sections in order; values one section needs from another pass explicitly."""
    def timed(key, build, *args):
        t_sec = time.perf_counter()
        result = _add(rep, key, build, *args)
        timings[key] = time.perf_counter() - t_sec
        say(f"  section {key:<12} {timings[key]:6.2f} s")
        return result

    teas = timed("table1", sec_table1.build)
    dec_true_poles = timed("schedule", sec_schedule.build)
    claim1 = timed("claim1", sec_claim1.build, dec_true_poles)
    timed("staircase", sec_staircase.build)
    timed("robustness", sec_robustness.build)
    beta3 = timed("qpp", sec_qpp.build)
    timed("errata", sec_errata.build, teas["mb3"], claim1, beta3)
    timed("printed", sec_printed.build, list(rep.ledger))
