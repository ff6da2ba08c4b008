"""Section provenance: software, run and the stage files used."""
from __future__ import annotations

import os
import platform
from datetime import datetime, timezone

import numpy as np

from acmm.report.context import SectionWriter
from acmm.report.gather import Gathered
from acmm_qpp.provenance import git_commit, git_dirty
import h5py
import scipy
from acmm import __version__
import matplotlib


def build(rep: SectionWriter, g: Gathered, timings: dict) -> None:
    """Software, machine, wall times and every stage file used.

    Parameters
    ----------
    rep : acmm.report.context.SectionWriter
        The section's inputs and output.
    g : acmm.report.gather.Gathered
        The gathered configs and stage results.
    timings : dict
        Step name → wall time, s.
    """
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
