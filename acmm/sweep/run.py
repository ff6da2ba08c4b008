"""``run_sweep``: the driver (tasks → executor → journal → results)."""
from __future__ import annotations

import concurrent.futures as cf
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

from common.outputs import owns_outputs
from common.runlock import locked_stage
from acmm.sweep.config import Sweep, load_sweep
from acmm.sweep.case import prepare_base, simulate_values
from acmm.sweep.cases import VERDICTS
from acmm.sweep.executors import (SerialExecutor, _call_chunk, _remote_contexts, _scheduler_workers, _task_key,
                                  _tasks, chunk_size, make_chunks, make_executor)
from acmm.sweep.journal import GroupCommitJournal, read_journal
from acmm.sweep.output import _split, write_results


# ---------------------------------------------------------------------------------------------
# the sweep driver
# ---------------------------------------------------------------------------------------------
@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    sweep : acmm.sweep.config.Sweep
        The sweep.
    path : pathlib.Path
        ``sweep.h5``.
    rows : list of dict
        Case rows, sorted by base then index.
    margins : list of dict
        Margin-search records.
    n_new : int
        Tasks run by this call.
    n_resumed : int
        Tasks taken from the journal.
    wall_time : float
        Wall time, s.
    complete : bool
        Every task is done.
    figures : list of pathlib.Path
        Figures written.
    """

    sweep: Sweep
    path: Path
    rows: list
    margins: list
    n_new: int
    n_resumed: int
    wall_time: float
    complete: bool
    figures: list = field(default_factory=list)

    def summary(self) -> dict:
        """Per base: counts of cases by verdict.

        Returns
        -------
        dict
            Base label → {verdict: count, ..., "total": count}.
        """
        out = {}
        for b in self.sweep.bases:
            rows = [r for r in self.rows if r["base"] == b.label]
            out[b.label] = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
            out[b.label]["total"] = len(rows)
        return out



def _as_sweep(sweep) -> Sweep:
    return sweep if isinstance(sweep, Sweep) else load_sweep(sweep)


@locked_stage(_as_sweep)
@owns_outputs("sweep", lambda s: _as_sweep(s))
def run_sweep(sweep: Sweep | str | Path, *, workers: Optional[int] = None, scheduler: Optional[str] = None,
              resume: bool = False, progress: Optional[Callable[[int, int, dict], None]] = None,
              after_record: Optional[Callable[[int], None]] = None, figures: Optional[bool] = None,
              snapshot_interval: float = 5.0, executor=None, chunk: Optional[int] = None) -> SweepResult:
    """Run (or resume) a sweep; writes ``sweep.journal``, ``sweep.h5``, ``sweep.csv`` and figures.

    Parameters
    ----------
    sweep : Sweep or path
    workers : int, optional
        Local workers (1: in-process); default ``sweep.workers`` or the CPU count.
    scheduler : str, optional
        Dask scheduler address; the cases then run on that cluster.
    resume : bool
        Keep the journal's finished cases and run only the others.
    progress : callable(done, total, record), optional
        Called after each finished task.
    after_record : callable(n_new), optional
        Called after each record is committed (tests use it to interrupt a sweep).
    figures : bool, optional
        Write the figures (default: ``output.figures`` of the sweep file).
    snapshot_interval : float, optional
        Period of the intermediate ``sweep.h5`` snapshots, s.
    executor : concurrent.futures.Executor, optional
        Use this executor instead of making one (it is not shut down).
    chunk : int, optional
        Cases per task (default :func:`chunk_size`: ~8 tasks per worker, ≤ :data:`MAX_CHUNK`;
        1 in-process).  The results do not depend on it.

    Returns
    -------
    SweepResult
        What was done, with the rows and margins.
    """
    if not isinstance(sweep, Sweep):
        sweep = load_sweep(sweep)
    spec = sweep.spec
    t0 = time.perf_counter()
    key = sweep.results_key()
    run_dir = sweep.run_dir()
    jpath = run_dir / "sweep.journal"
    done: dict[tuple, dict] = {}
    if resume and jpath.exists():
        for rec in read_journal(jpath, key):
            done[_task_key(rec)] = rec
    n_resumed = len(done)
    tasks = [t for t in _tasks(sweep) if t not in done]
    total = n_resumed + len(tasks)
    contexts = {b.label: prepare_base(b, spec) for b in sweep.bases} if tasks else {}
    for ctx in contexts.values():          # warm up (and load the compiled simulator) before forking
        simulate_values(ctx, {})
    if workers is None:
        workers = spec.workers or os.cpu_count() or 1
    close = lambda: None  # noqa: E731
    if executor is None and tasks:        # before the journal: an unreachable scheduler writes nothing
        executor, close = make_executor(workers if not scheduler else 0, scheduler)
    try:
        journal = GroupCommitJournal(jpath, key, fresh=not resume)
    except BaseException:
        close()
        raise
    serial = isinstance(executor, SerialExecutor)
    n_workers = 1 if serial else _scheduler_workers(executor, workers)
    size = chunk if chunk is not None else (1 if serial else chunk_size(len(tasks), n_workers))
    window = 1 if serial else max(4, 2 * n_workers)
    remote = _remote_contexts(executor, contexts)
    n_new = _drive(sweep, executor, close, journal, make_chunks(tasks, size), remote, window, done, total,
                   progress, after_record, snapshot_interval)
    close()
    path, figs = write_results(sweep, list(done.values()), complete=True,
                               figures=sweep.file.output.figures if figures is None else figures,
                               wall_time=time.perf_counter() - t0)
    rows, margins = _split(sweep, list(done.values()))
    return SweepResult(sweep, path, rows, margins, n_new, n_resumed, time.perf_counter() - t0, True, figs)


def _drive(sweep: Sweep, executor, close, journal, chunks: list, remote: dict, window: int, done: dict,
           total: int, progress, after_record, snapshot_interval: float) -> int:
    """Submit the chunks (at most ``window`` in flight), journal every record as it comes back and
    snapshot ``sweep.h5`` every ``snapshot_interval`` s; on any exit the journal is closed, and on
    an interruption the pending tasks are cancelled, the executor closed and a partial
    ``sweep.h5`` written.  Returns the number of new records (added to ``done``)."""
    n_new = 0
    last_snap = time.monotonic()
    complete = False
    pending: dict = {}
    try:
        it = iter(chunks)
        exhausted = False
        while True:
            while not exhausted and len(pending) < window:
                c = next(it, None)
                if c is None:
                    exhausted = True
                    break
                pending[executor.submit(_call_chunk, c, remote[c[0][1]])] = c
            if not pending:
                break
            finished, _ = cf.wait(list(pending), return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                pending.pop(fut)
                recs = fut.result()
                journal.append_many(recs)
                for rec in recs:
                    done[_task_key(rec)] = rec
                    n_new += 1
                    if progress is not None:
                        progress(len(done), total, rec)
                    if after_record is not None:
                        after_record(n_new)
            if time.monotonic() - last_snap > snapshot_interval:
                write_results(sweep, list(done.values()), complete=False)
                last_snap = time.monotonic()
        complete = True
    finally:
        journal.close()
        if not complete:
            try:
                for fut in list(pending):
                    fut.cancel()
            finally:
                close()
                if done:
                    write_results(sweep, list(done.values()), complete=False)
    return n_new
