"""``run_sweep``: the driver (tasks → executor → journal → results)."""
from __future__ import annotations

import concurrent.futures as cf
import functools
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

from acmm_qpp.atomic_write import write_text
from acmm_qpp.outputs import CONFIG_FILE, config_text_of, owned_files
from acmm_qpp.runlock import run_lock
from acmm.sweep.config import Sweep, load_sweep
from acmm.sweep.case import prepare_base, simulate_values
from acmm.sweep.cases import VERDICTS
from acmm.sweep.chunking import Chunker
from acmm.sweep.executors import (SerialExecutor, call_chunk, code_identity, remote_contexts, scheduler_workers,
                                  task_key, sweep_tasks, lost_worker, make_executor)
from acmm.sweep.journal import Journal, read_journal
from acmm_qpp.errors import ConfigError, FigureError, OutputError
from acmm_qpp.signals import interrupts_deferred
from acmm.stages.pool import submit
from acmm.sweep.output import split_records, write_results


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


#: The files a sweep owns in its run folder (its journal is not one of them: it survives for --resume).
OUTPUTS = ("sweep.h5", "sweep.csv", "sweep_*.png")


def _remove_earlier(run_dir: Path, before: dict | None = None) -> None:
    """Remove the sweep's files of an earlier run: all of them, or those whose identity is the
    one in ``before`` (:func:`acmm_qpp.outputs.owned_files`: not written again by this run)."""
    for name, ident in owned_files(run_dir, OUTPUTS).items():
        if before is None or before.get(name) == ident:
            try:
                (run_dir / name).unlink()
            except OSError:
                pass


def _in_run_folder(fn):
    """``run_sweep`` under the run lock of its folder (:func:`acmm_qpp.runlock.run_lock`), writing
    there itself, not through a staging folder (:func:`acmm_qpp.outputs.stage`): its tables are
    snapshots of its journal that say whether they are complete, kept when it fails or is
    interrupted, for ``--resume``.  When it finishes (or only a figure fails, exit 4) its
    ``config.yaml`` is written and its files of an earlier run that it did not write again go."""
    @functools.wraps(fn)
    def wrapper(sweep, *args, **kwargs):
        sweep = _as_sweep(sweep)
        with run_lock(sweep.run_dir()) as run_dir:
            before = owned_files(run_dir, OUTPUTS)
            try:
                result = fn(sweep, *args, out=run_dir, **kwargs)
            except FigureError:
                write_text(run_dir / CONFIG_FILE, config_text_of(sweep))
                _remove_earlier(run_dir, before)
                raise
            write_text(run_dir / CONFIG_FILE, config_text_of(sweep))
            _remove_earlier(run_dir, before)
            return result
    return wrapper


@_in_run_folder
def run_sweep(sweep: Sweep | str | Path, *, workers: Optional[int] = None, scheduler: Optional[str] = None,
              resume: bool = False, progress: Optional[Callable[[int, int, dict], None]] = None,
              after_record: Optional[Callable[[int], None]] = None, figures: Optional[bool] = None,
              snapshot_interval: float = 5.0, executor=None, chunk: Optional[int] = None,
              out: Path) -> SweepResult:
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
        Cases per task (default: sized as the chunks are submitted, :class:`Chunker`; 1
        in-process).  The results do not depend on it.
    out : pathlib.Path
        Its run folder (a sweep writes there directly and keeps its snapshots when interrupted).

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
    run_dir = out
    jpath = run_dir / "sweep.journal"
    done = _resumed(sweep, jpath, key) if resume and jpath.exists() else {}
    n_resumed = len(done)
    tasks = [t for t in sweep_tasks(sweep) if t not in done]
    total = n_resumed + len(tasks)
    contexts = {b.label: prepare_base(b, spec) for b in sweep.bases} if tasks else {}
    for ctx in contexts.values():          # warm up (and load the compiled simulator) before forking
        simulate_values(ctx, {})
    if workers is None:
        workers = spec.workers or os.cpu_count() or 1
    close = lambda abort=False: None  # noqa: E731
    if executor is None and tasks:        # before the journal: an unreachable scheduler writes nothing
        executor, close = make_executor(workers if not scheduler else 0, scheduler)
    afresh = not (resume and jpath.exists())
    journal = None
    try:
        journal = Journal(jpath, key, fresh=not resume)
        if afresh:              # after the journal: a journal that cannot be written changes nothing
            _start_afresh(sweep, run_dir)
    except BaseException:
        if journal is not None:
            journal.close()
        close()
        raise
    serial = isinstance(executor, SerialExecutor)
    n_workers = 1 if serial else scheduler_workers(executor, workers)
    chunks = Chunker(tasks, n_workers, chunk if chunk is not None else (1 if serial else None))
    window = 1 if serial else max(4, 2 * n_workers)
    remote = _task_arguments(executor, contexts)
    feed = _Feed(executor, chunks, remote, window, journal, done, total, progress, after_record)
    n_new = _drive(sweep, feed, close, snapshot_interval)
    close()
    path, figs = write_results(sweep, list(done.values()), complete=True,
                               figures=sweep.file.output.figures if figures is None else figures,
                               wall_time=time.perf_counter() - t0)
    rows, margins = split_records(sweep, list(done.values()))
    return SweepResult(sweep, path, rows, margins, n_new, n_resumed, time.perf_counter() - t0, True, figs)


def _task_arguments(executor, contexts: dict) -> dict:
    """Base label → the arguments of its chunks' tasks after the chunk: the base context (on
    Dask scattered) and, on Dask, whose workers may run other code, this code's identity."""
    remote = remote_contexts(executor, contexts)
    if getattr(executor, "_client", None) is None:
        return {k: (v,) for k, v in remote.items()}

    return {k: (v, code_identity()) for k, v in remote.items()}


def _resumed(sweep: Sweep, jpath: Path, key: str) -> dict:
    """The finished tasks of the journal ``jpath`` (task key → record) for ``--resume``.

    Raises
    ------
    ConfigError
        The journal is another sweep's, a line is corrupt, or a record is of a case index or
        margin search this sweep does not have (it added a 161st row to 160).
    """
    spec, done = sweep.spec, {}
    n_cases = spec.n_cases()
    try:
        records = read_journal(jpath, key, {b.label for b in sweep.bases})
    except ConfigError as exc:
        if "different sweep configuration" not in str(exc):
            raise
        changed = sweep.changed_since(jpath.parent / "config.yaml")
        raise ConfigError(f"{exc} (changed since: {'; '.join(changed[:4])}{' …' if len(changed) > 4 else ''})"
                          if changed else str(exc)) from None
    for rec in records:
        task = task_key(rec)
        if (task[0] == "case" and not 0 <= task[2] < n_cases) or (task[0] == "margin" and spec.margin is None):
            raise ConfigError(f"{jpath}: a record of {task[0]} {task[2]!r} of {task[1]}, which this sweep "
                              f"does not have ({n_cases} cases per base); delete the journal or run without "
                              "--resume")
        done[task] = rec
    return done


def _start_afresh(sweep: Sweep, run_dir: Path) -> None:
    """A sweep started afresh (not resumed) keeps partial results when interrupted, so it must not
    sit beside an earlier run's: that run's ``sweep.h5``, ``sweep.csv`` and figures are removed
    (its journal is replaced next) and this sweep's ``config.yaml`` is written first.  An
    interrupted re-run with another seed left its results beside the earlier run's config.yaml
    and figures (a review)."""
    _remove_earlier(run_dir)
    write_text(run_dir / CONFIG_FILE, config_text_of(sweep))


class _Snapshots:
    """``sweep.h5``/``sweep.csv`` rebuilt from the records so far, in a background thread.

    A rebuild costs O(records) (~0.1 s per 1 000 cases), so written in the driver thread it would
    stall the submission of chunks for longer and longer as a sweep grows (workers then idle), and
    every ``interval`` s it would take a growing share of the driver's CPU.  Here a rebuild runs
    beside the driver on a copy of the record list, at most one at a time, and the next one starts
    no sooner than ``interval`` s and :data:`COST_FACTOR` × the last rebuild's duration after the
    last ended (its share of one core stays ≤ 1/``COST_FACTOR``).  An error of a rebuild (disk
    full, read-only directory) is raised in the driver by :meth:`check`.
    """

    COST_FACTOR = 20.0

    def __init__(self, sweep: Sweep, interval: float):
        self.sweep, self.interval = sweep, interval
        self._thread: Optional[threading.Thread] = None
        self._error: Optional[BaseException] = None
        self._next = time.monotonic() + interval

    def _write(self, records: list) -> None:
        t0 = time.monotonic()
        try:
            write_results(self.sweep, records, complete=False)
        except BaseException as exc:  # noqa: BLE001 (re-raised in the driver by check())
            self._error = exc
        t1 = time.monotonic()
        self._next = t1 + max(self.interval, self.COST_FACTOR * (t1 - t0))

    def check(self) -> None:
        """Raise the error of a finished rebuild, if any."""
        if self._error is not None:
            err, self._error = self._error, None
            raise err

    def maybe(self, done: dict) -> None:
        """Start a rebuild of ``done``'s records if one is due and none is running."""
        self.check()
        if time.monotonic() < self._next or (self._thread is not None and self._thread.is_alive()):
            return
        self._thread = threading.Thread(target=self._write, args=(list(done.values()),),
                                        name="acmm-sweep-snapshot", daemon=True)
        self._thread.start()

    def wait(self) -> None:
        """Wait for a running rebuild (before the final or partial write of the same files)."""
        if self._thread is not None:
            self._thread.join()
            self._thread = None


@dataclass
class _Feed:
    """The chunks in flight on the executor and what came back (:func:`_drive`).

    Attributes
    ----------
    executor : concurrent.futures.Executor
        Where the chunks run (the serial executor, the process pool or Dask's).
    chunks : acmm.sweep.chunking.Chunker
        The chunks still to submit (sizes guided by what came back).
    remote : dict
        Base label → the arguments after the chunk of each task (:func:`_task_arguments`).
    window : int
        At most this many chunks in flight.
    journal : acmm.sweep.journal.Journal
        Every record is appended as it comes back.
    done : dict
        Task key → record: the finished tasks (resumed ones included); filled here.
    total : int
        Number of tasks of the sweep (for ``progress``).
    progress, after_record : callable or None
        ``progress(done, total, record)`` and ``after_record(n_new)``, called per record.
    """

    executor: object
    chunks: Chunker
    remote: dict
    window: int
    journal: object
    done: dict
    total: int
    progress: Optional[Callable] = None
    after_record: Optional[Callable] = None
    pending: dict = field(default_factory=dict)
    n_new: int = 0

    def fill(self) -> None:
        """Submit chunks until ``window`` are in flight or none is left."""
        while len(self.pending) < self.window:
            c = self.chunks.next()
            if c is None:
                return
            self.pending[submit(self.executor, call_chunk, c, *self.remote[c[0][1]])] = c

    def take(self, fut) -> None:
        """Journal and record the records of a finished chunk."""
        self.pending.pop(fut)
        recs = _records(fut)
        self.chunks.returned(len(recs))
        self.journal.append(recs)
        for rec in recs:
            self.done[task_key(rec)] = rec
            self.n_new += 1
            if self.progress is not None:
                self.progress(len(self.done), self.total, rec)
            if self.after_record is not None:
                self.after_record(self.n_new)


def _drive(sweep: Sweep, feed: _Feed, close, snapshot_interval: float) -> int:
    """Keep ``feed``'s window of chunks in flight, take each chunk as it finishes, and rebuild
    ``sweep.h5`` in the background every ``snapshot_interval`` s or more (:class:`_Snapshots`).

    On any exit the journal is closed; on an interruption or a failure the chunks in flight are
    cancelled, the executor is closed (``close(abort=True)``) and a partial ``sweep.h5`` is
    written from the records so far.  Returns the number of new records (added to ``feed.done``).
    """
    snaps = _Snapshots(sweep, snapshot_interval)
    complete = False
    try:
        feed.fill()
        while feed.pending:
            finished, _ = cf.wait(list(feed.pending), return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                feed.take(fut)
            snaps.maybe(feed.done)
            feed.fill()
        snaps.wait()
        snaps.check()
        complete = True
    finally:
        _close_feed(sweep, feed, close, snaps, complete)
    return feed.n_new


def _close_feed(sweep: Sweep, feed: _Feed, close, snaps: _Snapshots, complete: bool) -> None:
    """The end of :func:`_drive`, interrupts held (a second Ctrl-C in this cleanup hung the sweep:
    a review): the journal closed, the background rebuild awaited and, when the sweep did not
    complete, the chunks in flight cancelled, the executor aborted and the partial results written."""
    with interrupts_deferred():
        feed.journal.close()
        snaps.wait()
        if not complete:
            try:
                for fut in list(feed.pending):
                    fut.cancel()
            finally:
                close(abort=True)
                if feed.done:
                    write_results(sweep, list(feed.done.values()), complete=False)


def _records(fut) -> list:
    """The records of a finished chunk; a worker lost under it (not the case's own error) is
    one clear :class:`OutputError`."""
    try:
        return fut.result()
    except BaseException as exc:
        why = lost_worker(exc)
        if why is None:
            raise
        raise OutputError(why) from None
