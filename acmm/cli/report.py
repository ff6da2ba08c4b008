"""``acmm report``: regenerate every table and figure of CR-185644 into one HTML page.

Registered on the ``acmm`` app by :func:`register` (called from ``acmm.cli.app``).  Imports of
the report machinery stay inside the command so ``acmm --help`` stays fast.
"""
from __future__ import annotations

import functools
from collections import Counter
from pathlib import Path
import sys
from typing import Optional

import typer

from acmm.cli.command import acmm_command
from acmm_qpp.cli.plumbing import help_command
from acmm_qpp.cli.progress import enabled
from acmm_qpp.errors import AcmmError, ConfigError


def register(app: typer.Typer) -> None:
    """Add the ``report`` command to ``app``.

    Parameters
    ----------
    app : typer.Typer
        The ``acmm`` app.
    """

    @app.command("report", short_help="Every figure and table of CR-185644 in one HTML page.",
                 cls=help_command(["acmm report --fast                  # CI mode, a few minutes",
                                   "acmm report --out runs/report --jobs 2"]))
    @acmm_command
    def report(
        out: str = typer.Option("runs/report", "--out", help="output directory (index.html, report.md, "
                                                                     "figures/, manifest.json)"),
        fast: bool = typer.Option(False, "--fast", help="CI mode: a 13-orbit stair-case instead of 130 orbits, "
                                                          "a short sweep, and no quadratic schedule"),
        rerun: bool = typer.Option(False, "--rerun", help="recompute every stage even when results with the "
                                                          "same config hash exist (determinism check)"),
        root: Optional[Path] = typer.Option(None, "--root", help="results root the report computes its stages in, "
                                            "figures off, replacing files there (default: <out>/results, its own; "
                                            "never your runs/)"),
        jobs: Optional[int] = typer.Option(None, "--jobs", min=1, max=1024, help="processes running the stages and "
                                           "sections (default: 2 on a multi-core machine, or ACMM_REPORT_JOBS); "
                                           "1: one after the other; the output is the same"),
    ) -> None:
        """Every figure and table of CR-185644 regenerated and compared with the printed values;
        writes <out>/index.html (self-contained) and <out>/report.md; a failed section is shown there
        with its error and the command exits with that error's code."""
        from acmm.report.build import build_report  # deferred: --help needs no report (every stage, matplotlib)

        # progress on a terminal's stderr; elsewhere (CI, pipes) on stdout, so that stderr holds
        # the errors alone: one `error:` line when the report cannot go on (a full disk…)
        say = functools.partial(print, file=sys.stderr if enabled() else sys.stdout, flush=True)
        if not out.strip():              # Path("") would be the working directory itself
            raise ConfigError("--out: empty; give the report's output directory")
        r = build_report(Path(out), fast=fast, rerun=rerun, root=root, progress=say, jobs=jobs)
        counts = Counter(p.status for p in r.ledger)
        typer.echo(f"report: {len(r.sections)} sections, {len(r.figures)} figures, "
                   f"{len(r.stages)} result files ({sum(s.reused for s in r.stages)} reused) in {r.wall_time:.1f} s "
                   f"({r.jobs} process{'es' if r.jobs > 1 else ''})")
        typer.echo("  printed numbers: " + "; ".join(f"{v} {k}" for k, v in sorted(counts.items())))
        d = r.determinism
        typer.echo(f"  determinism: {d['status']}" +
                   (f" ({d['compared']} datasets compared, {d['recomputed']} files recomputed)"
                    if d["status"] != "no previous report" else ""))
        typer.echo(f"  wrote {r.html}")
        typer.echo(f"  wrote {r.markdown}")
        if r.failures:                   # the report is written, with each failure in its section
            section, first = r.failures[0]
            err = AcmmError(f"report incomplete: {len(r.failures)} failed section part(s), first in section "
                            f"{section}: {first.text()} (see {r.html})")
            err.exit_code = first.exit_code
            raise err
