"""``run_sweep``: the driver (tasks → executor → journal → results), and the executors it runs
the tasks on (in-process, process pool, Dask): worker warm-up, base contexts made local or
scattered, a lost worker named on one line, and Dask workers checked to run this code
(:func:`code_identity`).

The case and margin tasks are cut into chunks for the executors by guided self-scheduling
(issue 16): sizes from the run's own measured throughput, so that a task's fixed cost stays a few
per cent at any number of workers and the last chunks leave no worker idle (docs/performance.md).
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import dataclasses
import functools
import hashlib
import math
import os
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from acmm_qpp.errors import ConfigError, FigureError, OutputError
from acmm_qpp.limits import limit
from acmm_qpp.outputs import CONFIG_FILE, config_text_of, owned_files, run_lock, write_text
from acmm_qpp.signals import interrupts_deferred
from acmm import LIMITS, __version__
from acmm.simulate.warmup import warm_up
from acmm.stages.pool import process_pool, stop_pool, submit
from acmm.sweep.config import Sweep, load_sweep
from acmm.sweep.case import BaseContext, margin_search, prepare_base, run_case, simulate_values
from acmm.sweep.cases import VERDICTS
from acmm.sweep.journal import Journal, read_journal
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
        verdicts = {b.label: [r["verdict"] for r in self.rows if r["base"] == b.label] for b in self.sweep.bases}
        return {lab: {**{v: vs.count(v) for v in VERDICTS}, "total": len(vs)} for lab, vs in verdicts.items()}


#: The files a sweep owns in its run folder (its journal is not one of them: it survives for --resume).
OUTPUTS = ("sweep.h5", "sweep.csv", "sweep_*.png")


def _remove_earlier(run_dir: Path, before: dict | None = None) -> None:
    """Remove the sweep's files of an earlier run: all of them, or those whose identity is the
    one in ``before`` (:func:`acmm_qpp.outputs.owned_files`: not written again by this run)."""
    for name, ident in owned_files(run_dir, OUTPUTS).items():
        if before is None or before.get(name) == ident:
            with contextlib.suppress(OSError):
                (run_dir / name).unlink()


def _in_run_folder(fn):
    """``run_sweep`` under the run lock of its folder (:func:`acmm_qpp.outputs.run_lock`), writing
    there itself, not through a staging folder (:func:`acmm_qpp.outputs.stage`): its tables are
    snapshots of its journal that say whether they are complete, kept when it fails or is
    interrupted, for ``--resume``.  When it finishes (or only a figure fails, exit 4) its
    ``config.yaml`` is written and its files of an earlier run that it did not write again go."""
    @functools.wraps(fn)
    def wrapper(sweep, *args, **kwargs):
        sweep = sweep if isinstance(sweep, Sweep) else load_sweep(sweep)
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
              snapshot_interval: float = 5.0, chunk: Optional[int] = None,
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
    chunk : int, optional
        Cases per task (default: sized as the chunks are submitted, from the measured cost of a
        case; 1 in-process).  The results do not depend on it.
    out : pathlib.Path
        Its run folder (a sweep writes there directly and keeps its snapshots when interrupted).

    Returns
    -------
    SweepResult
        What was done, with the rows and margins.

    Raises
    ------
    OutputError
        A worker died under a chunk (not the case's own error); the finished cases stay in the journal.
    """
    spec = sweep.spec
    t0 = time.perf_counter()
    key = sweep.results_key()
    jpath = out / "sweep.journal"
    resumed = resume and jpath.exists()
    done = _resumed(sweep, jpath, key) if resumed else {}
    n_resumed = len(done)
    tasks = [t for t in _sweep_tasks(sweep) if t not in done]
    total = n_resumed + len(tasks)
    contexts = {b.label: prepare_base(b, spec) for b in sweep.bases} if tasks else {}
    for ctx in contexts.values():          # warm up (and load the compiled simulator) before forking
        simulate_values(ctx, {})
    if workers is None:
        workers = spec.workers or os.cpu_count() or 1
    executor, close = None, lambda abort=False: None
    if tasks:        # before the journal: an unreachable scheduler writes nothing
        executor, close = _make_executor(workers if not scheduler else 0, scheduler)
    journal = None
    try:
        journal = Journal(jpath, key, fresh=not resume)
        # after the journal (one that cannot be written changes nothing): partial results must not
        # sit beside an earlier run's, so its tables and figures go and this sweep's config.yaml
        # comes first (an interrupted re-run with another seed left its results beside the earlier
        # run's config.yaml and figures: a review)
        if not resumed:
            _remove_earlier(out)
            write_text(out / CONFIG_FILE, config_text_of(sweep))
    except BaseException:
        if journal is not None:
            journal.close()
        close()
        raise
    serial = isinstance(executor, _SerialExecutor)
    n_workers = 1 if serial else _scheduler_workers(executor, workers)
    chunks = _Chunker(tasks, n_workers, chunk if chunk is not None else (1 if serial else None))
    window = 1 if serial else max(4, 2 * n_workers)
    remote = _task_arguments(executor, contexts)
    # keep `window` chunks in flight, journal each record as its chunk finishes and rebuild sweep.h5 in
    # the background; a sweep that does not complete (an interruption or a failure) cancels its chunks
    # in flight, closes the executor and writes a partial sweep.h5 from the records so far
    snaps = _Snapshots(sweep, snapshot_interval)
    pending: set = set()
    n_new, complete = 0, False
    try:
        while True:
            while len(pending) < window and (c := chunks.next()) is not None:
                pending.add(submit(executor, _call_chunk, c, *remote[c[0][1]]))
            if not pending:
                break
            finished, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                try:
                    recs = fut.result()
                except BaseException as exc:
                    why = _lost_worker(exc)
                    if why is None:
                        raise
                    raise OutputError(why) from None
                chunks.returned(len(recs))
                journal.append(recs)
                for rec in recs:
                    done[_task_key(rec)] = rec
                    n_new += 1
                    if progress is not None:
                        progress(len(done), total, rec)
                    if after_record is not None:
                        after_record(n_new)
            snaps.maybe(done)
        snaps.wait()
        snaps.check()
        complete = True
    finally:
        with interrupts_deferred():          # a second Ctrl-C in this cleanup hung the sweep (a review)
            journal.close()
            snaps.wait()
            if not complete:
                try:
                    for fut in pending:
                        fut.cancel()
                finally:
                    close(abort=True)
                    if done:
                        write_results(sweep, list(done.values()), complete=False)
    close()
    path, figs = write_results(sweep, list(done.values()), complete=True,
                               figures=sweep.file.output.figures if figures is None else figures,
                               wall_time=time.perf_counter() - t0)
    rows, margins = split_records(sweep, list(done.values()))
    return SweepResult(sweep, path, rows, margins, n_new, n_resumed, time.perf_counter() - t0, True, figs)


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
        task = _task_key(rec)
        if (task[0] == "case" and not 0 <= task[2] < n_cases) or (task[0] == "margin" and spec.margin is None):
            raise ConfigError(f"{jpath}: a record of {task[0]} {task[2]!r} of {task[1]}, which this sweep "
                              f"does not have ({n_cases} cases per base); delete the journal or run without "
                              "--resume")
        done[task] = rec
    return done


# ---------------------------------------------------------------------------------------------
# executors and the tasks they run
# ---------------------------------------------------------------------------------------------
class _SerialExecutor(cf.Executor):
    """Runs each task in the calling process when it is submitted (one worker)."""

    def submit(self, fn, /, *args, **kwargs):
        """A completed future of ``fn(*args, **kwargs)`` (``KeyboardInterrupt`` is raised, not stored)."""
        fut: cf.Future = cf.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except KeyboardInterrupt:
            raise
        except BaseException as exc:  # noqa: BLE001 (re-raised by Future.result())
            fut.set_exception(exc)
        return fut


def _make_executor(workers: int = 1, scheduler: Optional[str] = None):
    """(executor, close(abort=False)) for a Dask scheduler address, else ``workers`` local processes
    (≤ 1: :class:`_SerialExecutor`, in-process); ConfigError when Dask is missing or unreachable."""
    if scheduler:
        try:
            import distributed  # deferred: dask start-up, and an optional dependency
        except ImportError:
            raise ConfigError("--scheduler needs the optional Dask dependency: pip install 'acmm-qpp[dask]'") from None

        timeout = f"{limit('DASK_CONNECT_SECONDS', LIMITS):g}s"        # (its own error, not the address's)
        try:
            client = distributed.Client(scheduler, timeout=timeout)
        except Exception as exc:  # noqa: BLE001 (tls:// without a context, ucx:// without ucx…: a bad address)
            raise ConfigError(f"--scheduler: cannot connect to the Dask scheduler at {scheduler}: "
                              f"{type(exc).__name__}: {exc}") from None
        return client.get_executor(pure=False), lambda abort=False: client.close()
    if workers <= 1:
        return _SerialExecutor(), lambda abort=False: None
    pool = process_pool(workers)
    return pool, lambda abort=False: stop_pool(pool, abort)


def _lost_worker(exc: BaseException) -> Optional[str]:
    """One line for the user when a task's future raised ``exc`` because its worker, not its case,
    failed (None: the task's own error)."""
    if isinstance(exc, cf.BrokenExecutor):
        what = "a sweep worker process died (killed, or out of memory)"
    elif type(exc).__name__ == "KilledWorker":
        what = f"the Dask workers that ran a task died too often (KilledWorker: {exc})"
    elif isinstance(exc, cf.CancelledError):
        what = "the Dask cluster dropped a task (its scheduler or workers went away)"
    else:
        return None
    return what + "; the finished cases are kept in the journal: run the sweep again with --resume"


def _sweep_tasks(sweep: Sweep):
    """The tasks of a sweep, in order: ``("case", base, index)`` for every case of every base, then
    ``("margin", base, direction)``."""
    n = sweep.spec.n_cases()
    yield from (("case", b.label, i) for b in sweep.bases for i in range(n))
    if sweep.spec.margin is not None:
        yield from (("margin", b.label, d) for b in sweep.bases for d in ("up", "down"))


def _task_key(rec: dict) -> tuple:
    """The task (:func:`_sweep_tasks`' tuple) of the journal record ``rec``."""
    return ("case", rec["base"], rec["index"]) if rec["kind"] == "case" else ("margin", rec["base"], rec["direction"])


#: glibc ``mallopt`` parameter numbers
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
#: fixed mmap threshold set in a worker whose dynamic threshold is off (bytes; glibc's dynamic
#: threshold ranges from 128 KiB to 32 MiB): a 10-orbit case's largest arrays are well below it.
#: The trim threshold goes with it to twice that, as glibc's dynamic adjustment itself sets it.
MMAP_THRESHOLD = 4 << 20


def _restore_heap_reuse() -> bool:
    """Serve a case's short-lived arrays from the heap again where the worker's environment stopped it.

    Dask's nanny starts every worker with ``MALLOC_TRIM_THRESHOLD_=65536`` (config
    ``distributed.nanny.pre-spawn-environ``) to return freed memory to the system promptly.
    Setting that variable also switches off glibc's *dynamic* mmap threshold, so every array
    above 128 KiB — the trajectory arrays of each case — is ``mmap``-ed and unmapped again, case
    after case: ~45 page faults per 10-orbit case (~2 900 per chunk of 64, against ~8 in a
    forked pool worker), several per cent of the worker's CPU in the kernel and in cache misses.
    This sets in such a process (Linux/glibc only, and only when ``MALLOC_MMAP_THRESHOLD_`` was
    not chosen explicitly) what glibc's dynamic adjustment would have reached: a fixed mmap
    threshold of :data:`MMAP_THRESHOLD` and a trim threshold of twice that, i.e. a worker keeps
    at most 8 MiB of freed heap for reuse instead of 64 KiB.  Returns True when it changed them.
    """
    if (not sys.platform.startswith("linux") or "MALLOC_TRIM_THRESHOLD_" not in os.environ
            or "MALLOC_MMAP_THRESHOLD_" in os.environ):
        return False
    try:
        libc = ctypes.CDLL(None)
        return (libc.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
                and libc.mallopt(M_TRIM_THRESHOLD, 2 * MMAP_THRESHOLD) == 1)
    except (OSError, AttributeError, TypeError):      # not glibc (e.g. musl): nothing to restore
        return False


def _in_dask_worker() -> bool:
    """Whether this process hosts a Dask worker (also inside ``client.run``, where
    ``distributed.get_worker`` finds no task)."""
    if "distributed" not in sys.modules:
        return False
    try:
        from distributed.worker import Worker  # deferred: dask, an optional dependency

        return bool(Worker._instances)
    except (ImportError, AttributeError):
        return False


@functools.cache
def warm_worker() -> None:
    """Once per worker process: load the compiled kernels (from numba's cache: no compile) and
    in a Dask worker restore heap reuse (:func:`_restore_heap_reuse`); a long-lived Dask cluster can be warmed
    ahead with ``client.run(acmm.sweep.run.warm_worker)``."""
    if _in_dask_worker():        # only the nanny's environment needs it; the user's own
        _restore_heap_reuse()    # MALLOC_* choice in a driver or pool process is left alone
    warm_up()


_LOCAL: dict = {}


def _local_context(ctx: BaseContext) -> BaseContext:
    """``ctx`` with writable arrays, made once per worker and context.

    Dask hands a task its (scattered) context deserialized from shared buffers, i.e. with
    read-only arrays; numba types read-only arrays differently, so the simulator would be
    compiled afresh on every Dask worker (~10 s) instead of loaded from the cache.
    """
    hit = _LOCAL.get(id(ctx))
    if hit is not None and hit[0] is ctx:
        return hit[1]
    sc = ctx.scenario
    fix = {f.name: np.array(getattr(sc, f.name)) for f in dataclasses.fields(sc)
           if isinstance(getattr(sc, f.name), np.ndarray) and not getattr(sc, f.name).flags.writeable}
    local = dataclasses.replace(ctx, scenario=dataclasses.replace(sc, **fix)) if fix else ctx
    if len(_LOCAL) > 16:
        _LOCAL.clear()
    _LOCAL[id(ctx)] = (ctx, local)
    return local


def _call_chunk(chunk, ctx, code: Optional[str] = None) -> list[dict]:
    """The records of the tasks of ``chunk``, run in order on base context ``ctx``.  ``code``: the
    driver's :func:`code_identity`, checked first on a Dask worker (started elsewhere, it may run
    other acmm code, whose rows would enter the table unnoticed: a review)."""
    if code is not None and code != code_identity():
        raise ConfigError(f"--scheduler: a Dask worker runs other acmm code ({code_identity()}) than this "
                          f"command ({code}): start the workers from the same installation")
    warm_worker()
    ctx = _local_context(ctx)
    return [run_case(ctx, arg) if kind == "case" else margin_search(ctx, arg) for kind, _, arg in chunk]


@functools.lru_cache(maxsize=1)
def code_identity() -> str:
    """The package version and a hash of the project's Python sources (``acmm``, ``acmm_qpp``,
    ``qpp``), computed once per process: two processes with the same identity run the same code.

    Returns
    -------
    str
        ``<version>+<12 hex digits>``.
    """
    root = Path(__file__).resolve().parents[2]
    h = hashlib.sha256()
    for package in ("acmm", "acmm_qpp", "qpp"):
        for f in sorted((root / package).rglob("*.py")):
            h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return f"{__version__}+{h.hexdigest()[:12]}"


def _scheduler_workers(executor, default: int) -> int:
    """Number of workers (threads, ≥ 1) of the Dask cluster behind ``executor``, else ``default``."""
    client = getattr(executor, "_client", None)
    with contextlib.suppress(AttributeError, KeyError, OSError, TypeError, ValueError):
        if client is not None:
            return max(1, sum(int(v) for v in client.nthreads().values()))
    return max(1, default)


def _task_arguments(executor, contexts: dict) -> dict:
    """Base label → the arguments of its chunks' tasks after the chunk: its context, and on a Dask
    cluster that context scattered once to every worker (a task then carries a reference, not a
    pickled design) and this code's identity (its workers may run other code)."""
    client = getattr(executor, "_client", None)
    if client is None:
        return {k: (v,) for k, v in contexts.items()}
    remote = contexts
    with contextlib.suppress(AttributeError, TypeError, ValueError):
        remote = {k: client.scatter(v, broadcast=True, hash=False) for k, v in contexts.items()}
    return {k: (v, code_identity()) for k, v in remote.items()}


# ---------------------------------------------------------------------------------------------
# chunks (guided self-scheduling)
# ---------------------------------------------------------------------------------------------
#: cases per task while the cost of a case is not yet measured (the first chunk of each worker):
#: 64 10-orbit cases are ~0.2–2 s of work
MAX_CHUNK = 64
#: chunks per worker aimed at over the rest of the sweep (guided: the chunks shrink towards the
#: end, so that the last ones do not leave workers idle)
CHUNKS_PER_WORKER = 8
#: work per task (s) once the cost of a case is measured: at least this, so that the fixed cost
#: of a task (a few ms of scheduler, client and worker time on Dask) stays a few per cent at any
#: number of workers and the scheduler sees at most ~10 tasks per second per worker ...
MIN_TASK_SECONDS = 0.1
#: ... and at most this, so that progress, the journal and an interruption stay live
MAX_TASK_SECONDS = 1.0


def _chunk_size(n_tasks: int, workers: int, case_seconds: Optional[float] = None,
                n_total: Optional[int] = None) -> int:
    """Cases per task when ``n_tasks`` cases remain for ``workers`` workers (a pool or a Dask
    cluster; the in-process executor runs one case per task).

    ⌈n / (8·workers)⌉: about 8 tasks per worker over what remains (the tail imbalance is then
    ≤ 1/8 of a worker's remaining share).  Without ``case_seconds`` (the cost of one case on one
    worker, s; not yet measured) it is clipped to [1, :data:`MAX_CHUNK`]; with it, to the cases
    that take :data:`MIN_TASK_SECONDS` … :data:`MAX_TASK_SECONDS`, and never above
    ⌈``n_total`` / workers⌉ (every worker gets a share of a small sweep; ``n_total``: the tasks of
    the whole sweep, default ``n_tasks``).  See docs/performance.md for why this holds at large N.
    """
    n_workers = max(1, workers)
    c = -(-n_tasks // (CHUNKS_PER_WORKER * n_workers))
    if case_seconds is None or not case_seconds > 0:
        return max(1, min(MAX_CHUNK, c))
    lo = max(1, math.ceil(MIN_TASK_SECONDS / case_seconds))
    hi = max(lo, int(MAX_TASK_SECONDS / case_seconds))
    return max(1, min(max(c, lo), hi, -(-(n_total or n_tasks) // n_workers)))


class _Chunker:
    """The tasks (in order) handed out in chunks as they are submitted (guided self-scheduling).

    Each chunk holds consecutive case tasks of one base (a margin search alone).  Its size is
    ``size`` when given, else :func:`_chunk_size` of the tasks still to hand out with the cost of
    a case measured so far: ``workers`` (Dask: worker threads) × the time since the first chunk
    came back / the cases that came back since (the throughput of the whole run, so it includes
    every per-task cost; before every worker can have returned a chunk, unmeasured).  The results
    do not depend on the chunking.
    """

    def __init__(self, tasks: list, workers: int, size: Optional[int] = None):
        self._tasks, self._pos = tasks, 0
        self.workers = max(1, workers)
        self.size = size
        self._first_back: Optional[float] = None
        self._cases_since = self._chunks_since = 0

    def case_seconds(self) -> Optional[float]:
        """Measured cost of one case on one worker, s (None before there is a measure)."""
        if self._first_back is None or self._chunks_since < self.workers or self._cases_since == 0:
            return None
        return self.workers * (time.monotonic() - self._first_back) / self._cases_since

    def returned(self, n_tasks: int) -> None:
        """Record that a chunk of ``n_tasks`` tasks came back."""
        if self._first_back is None:
            self._first_back = time.monotonic()
        else:
            self._chunks_since += 1
            self._cases_since += n_tasks

    def next(self) -> Optional[list]:
        """The tasks of the next chunk, or None when every task was handed out."""
        tasks, pos = self._tasks, self._pos
        if pos >= len(tasks):
            return None
        size = self.size or _chunk_size(len(tasks) - pos, self.workers, self.case_seconds(), len(tasks))
        chunk = [tasks[pos]]
        pos += 1
        if chunk[0][0] == "case":
            while (pos < len(tasks) and len(chunk) < size and tasks[pos][0] == "case"
                   and tasks[pos][1] == chunk[0][1]):
                chunk.append(tasks[pos])
                pos += 1
        self._pos = pos
        return chunk


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
