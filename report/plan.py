"""The report's sections as tasks of :mod:`report.runner` (issue 16).

Each section is one or more *parts* (its text and tables, then figures) run in section order when
serial, or concurrently on worker processes.  A part is a function ``fn(ctx, *values)`` of a fresh
:class:`~report.context.SectionWriter`; values other sections computed (the MB3 TEA of Table 1,
the claim-1 poles and numbers, β3 of ch. 13) are passed explicitly.  Its blocks and printed numbers
come back as a :class:`Part` and are put together in the order of :data:`PARTS`, so the document
is the same whichever process wrote which part.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

from report.context import SectionWriter
from report.gather import Gathered
from report.runner import WORKER_CACHE, Task
from report.sections import claim1, errata, qpp, robustness, schedule, staircase, table1


@dataclass
class Part:
    """What one part of a section produced."""

    blocks: list          #: document blocks (:class:`report.document.Doc`)
    ledger: list          #: printed numbers (:class:`report.ledger.PrintedNumber`)
    value: object         #: its return value (passed on to other parts)
    seconds: float        #: wall time of the part


def run_part(fn, g: Gathered, figdir: Path, fast: bool, values: tuple, results: dict | None) -> Part:
    """``fn(ctx, *values)`` on a fresh writer; ``results``: HDF5 files already read (None: this
    worker process's cache).  matplotlib's settings are reset first, so a figure looks the same
    whichever figures the process drew before."""
    t0 = time.perf_counter()
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].rc_file_defaults()
    ctx = SectionWriter(g, figdir, fast, WORKER_CACHE if results is None else results)
    value = fn(ctx, *values)
    return Part(ctx.doc.blocks, ctx.ledger, value, time.perf_counter() - t0)


def _design(c):
    return f"design:{c}"


def _simulate(c):
    return f"simulate:{c}"


#: (task name, section, function, stage tasks it reads, parts whose values it takes, rough cost in s)
PARTS = [
    ("table1", "table1", table1.build, (), (), 0.1),
    ("schedule", "schedule", schedule.summary, (_design("staircase"),), (), 0.3),
    ("schedule/paths", "schedule", schedule.path_figures, (_design("staircase"),), (), 0.9),
    ("poles", "schedule", schedule.true_poles, (_design("mb3"), _design("mb3_decoupled")), (), 0.05),
    ("schedule/figures", "schedule", schedule.figures,
     (_design("staircase"), _design("mb3"), _design("mb3_decoupled")), ("poles",), 2.0),
    ("claim1", "claim1", claim1.build, (_design("mb3"), _design("mb3_decoupled"), _simulate("mb3"),
                                        _simulate("mb3_decoupled")), ("poles",), 1.3),
    ("staircase", "staircase", staircase.summary, (_simulate("staircase"),), (), 0.1),
    ("staircase/inertia", "staircase", staircase.figure_inertia, (_simulate("staircase"),), (), 0.7),
    ("staircase/responses", "staircase", staircase.figure_responses, (_simulate("staircase"),), (), 1.0),
    ("staircase/levels", "staircase", staircase.figure_levels, (_simulate("staircase"),), (), 0.4),
    ("robustness", "robustness", robustness.build, ("sweep",), (), 0.7),
    ("qpp13", "qpp13", qpp.text13, ("qpp design:qpp_siso", "qpp simulate:qpp_siso"), (), 0.5),
    ("qpp13/figures", "qpp13", qpp.figures13, ("qpp design:qpp_siso", "qpp simulate:qpp_siso"), (), 1.0),
    ("qpp14", "qpp14", qpp.text14, ("qpp design:qpp_manipulator", "qpp simulate:qpp_manipulator"), (), 0.3),
    ("qpp14/figures", "qpp14", qpp.figures14, ("qpp design:qpp_manipulator", "qpp simulate:qpp_manipulator"),
     (), 1.6),
    ("errata", "errata", errata.build, (_design("staircase"), _simulate("staircase"), "qpp design:qpp_siso"),
     ("table1", "claim1", "qpp13"), 0.3),
]


def _errata_values(done: dict) -> tuple:
    return done["table1"].value["mb3"], done["claim1"].value, done["qpp13"].value


def section_tasks(g: Gathered, figdir: Path, fast: bool, stage_names: set, results: dict | None) -> list[Task]:
    """The parts of :data:`PARTS` as tasks; ``stage_names``: the stage tasks of the same graph
    (a part waits only for those), ``results``: the shared cache of read files when serial."""
    tasks = []
    for name, _, fn, stage_deps, value_deps, cost in PARTS:
        if name == "errata":
            values = _errata_values
        else:
            values = (lambda deps: (lambda done: tuple(done[d].value for d in deps)))(value_deps)
        deps = tuple(d for d in stage_deps if d in stage_names) + value_deps
        tasks.append(Task(name, run_part, deps,
                          (lambda fn, values: (lambda done: (fn, g, figdir, fast, values(done), results)))(fn, values),
                          cost))
    return tasks


def assemble(rep: SectionWriter, done: dict, timings: dict) -> None:
    """Append every part's blocks and printed numbers to ``rep`` in section order; per-section wall
    time (sum of its parts) into ``timings``."""
    for name, section, *_ in PARTS:
        part: Part = done[name]
        rep.doc.blocks.extend(part.blocks)
        rep.ledger.extend(part.ledger)
        timings[section] = timings.get(section, 0.0) + part.seconds
