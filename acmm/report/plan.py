"""The report's sections as tasks of :mod:`acmm.report.runner` (issue 16): each section is one or
more *parts* (``fn(ctx, *values)`` of a fresh :class:`~acmm.report.context.SectionWriter`, declared
in its module's ``PARTS``), serial or on worker processes; values other parts computed (Table 1's
TEAs, the claim-1 poles, β3 of ch. 13) are passed explicitly, and the parts' blocks and printed
numbers are put together in the order of :data:`PARTS`, whichever process wrote them.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

from acmm.report.context import SectionWriter
from acmm.report.gather import Failed, Gathered, blocked, failed
from acmm.report.runner import WORKER_CACHE, Task
from acmm.report.sections import claim1
from acmm.report.sections import errata
from acmm.report.sections import qpp
from acmm.report.sections import robustness
from acmm.report.sections import schedule
from acmm.report.sections import staircase
from acmm.report.sections import table1


@dataclass
class Part:
    """What one part of a section produced.

    Attributes
    ----------
    blocks : list
        Document blocks (of a :class:`acmm.report.document.Doc`), in order.
    ledger : list of acmm.report.ledger.PrintedNumber
        The printed numbers it compared.
    value : object
        Its return value, passed on to other parts (e.g. the claim-1 poles in rad/s, β3 of ch. 13).
    seconds : float
        Wall time of the part, s.
    failed : acmm.report.gather.Failed or None
        The part failed (or was not run, a stage or part it reads having failed): its blocks are
        the section's heading (first part) and the one-line error; ``value`` is None.
    """

    blocks: list          #: document blocks (:class:`acmm.report.document.Doc`)
    ledger: list          #: printed numbers (:class:`acmm.report.ledger.PrintedNumber`)
    value: object         #: its return value (passed on to other parts)
    seconds: float        #: wall time of the part
    failed: Failed | None = None     #: the part's failure, shown in its section


def run_part(fn, g: Gathered, figdir: Path, fast: bool, values: tuple, results: dict | None,
             name: str, heading: str | None, not_run: Failed | None = None) -> Part:
    """``fn(ctx, *values)`` on a fresh writer, matplotlib's settings reset first (a figure looks the
    same whichever figures the process drew before).  A user-facing error it raises
    (:func:`acmm.report.gather.failed`) becomes the part's :attr:`Part.failed` and its one-line
    text; a bug propagates.

    Parameters
    ----------
    fn : callable
        The part, ``fn(ctx, *values)`` (a function of :data:`PARTS`).
    g : acmm.report.gather.Gathered
        Configs and results files of the report.
    figdir : pathlib.Path
        Folder of the figures.
    fast : bool
        ``--fast`` report (short stair-case, reduced sweep).
    values : tuple
        Values of the parts this one takes (:attr:`Part.value`).
    results : dict or None
        Results files already read (run key ``"stage:name"`` → contents as read by
        :func:`acmm_qpp.results.read_h5`); None: this worker process's cache.
    name : str
        Task name of the part (in its failure's message).
    heading : str or None
        Section key whose heading this part writes (shown above its failure), or None.
    not_run : acmm.report.gather.Failed or None, optional
        A stage or part it reads failed: the part is not run and shows that failure.

    Returns
    -------
    Part
        Its blocks, printed numbers, return value and wall time (and failure).
    """
    t0 = time.perf_counter()
    cache = WORKER_CACHE if results is None else results
    f = not_run
    if f is None:
        if "matplotlib" in sys.modules:
            sys.modules["matplotlib"].rc_file_defaults()
        ctx = SectionWriter(g, figdir, fast, cache)
        try:
            value = fn(ctx, *values)
            return Part(ctx.doc.blocks, ctx.ledger, value, time.perf_counter() - t0)
        except Exception as exc:  # noqa: BLE001 (re-raised unless a user-facing failure)
            f = failed(name, exc)
            if f is None:
                raise
    ctx = SectionWriter(g, figdir, fast, cache)
    if heading is not None:             # the failed part is the one that writes the heading
        ctx.section(heading)
    ctx.doc.p(f"FAILED — {f.text()}. (The other sections are complete; acmm report exits with code "
              f"{f.exit_code}.)")
    return Part(ctx.doc.blocks, ctx.ledger, None, time.perf_counter() - t0, f)


#: stages a part shows when they ran and leaves out, saying why, when they failed: the report's
#: quadratic beside the packaged schedule (the packaged table and figure do not fail with it)
OPTIONAL = {"design:staircase_quadratic", "simulate:staircase_quadratic"}
#: (task name, section, function, stage tasks it reads, parts whose values it takes, rough cost in s:
#: CPU of the part in a warmed worker on the 2-core machine, issue 16), each section's own rows
PARTS = table1.PARTS + schedule.PARTS + claim1.PARTS + staircase.PARTS + robustness.PARTS + qpp.PARTS + errata.PARTS


def section_tasks(g: Gathered, figdir: Path, fast: bool, stage_names: set, results: dict | None) -> list[Task]:
    """The parts of :data:`PARTS` as tasks.

    Parameters
    ----------
    g : acmm.report.gather.Gathered
        Configs and results files; filled by the stage tasks before a part is submitted.
    figdir : pathlib.Path
        Folder of the figures.
    fast : bool
        ``--fast`` report.
    stage_names : set of str
        Names of the stage tasks in the same graph (:func:`acmm.report.gather.stage_tasks`); a
        part waits only for those.
    results : dict or None
        Shared cache of read results files (serial run), or None (each worker's own cache).

    Returns
    -------
    list of acmm.report.runner.Task
        One task per part, named as in :data:`PARTS`; each returns a :class:`Part`.
    """
    tasks, headed = [], set()
    for name, section, fn, stage_deps, value_deps, cost in PARTS:
        deps = tuple(d for d in stage_deps if d in stage_names) + value_deps
        heading = None if section in headed else section      # the first part of a section writes it
        headed.add(section)
        tasks.append(Task(name, run_part, deps, _part_args(fn, value_deps, g, figdir, fast, results, name, heading,
                                                           tuple(d for d in deps if d not in OPTIONAL)), cost))
    return tasks


def _part_args(fn, value_deps, g, figdir, fast, results, name, heading, deps):
    """``done → arguments of run_part`` (built when the part is submitted: ``g`` then holds the
    stages it reads): the values of the parts ``value_deps``; a part whose stage or part in
    ``deps`` failed is not run."""
    def args(done):
        not_run = blocked(name, done, deps)
        values = () if not_run else tuple(done[d].value for d in value_deps)
        return (fn, g, figdir, fast, values, results, name, heading, not_run)

    return args
