"""Executors (in-process, process pool, Dask) and the tasks they run: case and margin tasks,
chunking, worker warm-up and base contexts made local or scattered."""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import math
import os
import sys
import time
from typing import Optional

import numpy as np

from common.errors import ConfigError
from acmm.sweep.config import Sweep
from acmm.sweep.case import BaseContext, margin_search, run_case


# ---------------------------------------------------------------------------------------------
# executors
# ---------------------------------------------------------------------------------------------
class SerialExecutor(cf.Executor):
    """Runs each task in the calling process when it is submitted (one worker)."""

    def submit(self, fn, /, *args, **kwargs):
        """Run ``fn(*args, **kwargs)`` now; its result or exception goes into the future.

        Parameters
        ----------
        fn : callable
            The task.
        *args : tuple
            Its positional arguments.
        **kwargs : dict
            Its keyword arguments.

        Returns
        -------
        concurrent.futures.Future
            A completed future (``KeyboardInterrupt`` is raised, not stored).
        """
        fut: cf.Future = cf.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 (re-raised by Future.result())
            if isinstance(exc, KeyboardInterrupt):
                raise
            fut.set_exception(exc)
        return fut


def make_executor(workers: int = 1, scheduler: Optional[str] = None):
    """(executor, close) for ``workers`` local processes or a Dask scheduler address.

    Parameters
    ----------
    workers : int, optional
        Local worker processes (≤ 1: :class:`SerialExecutor`, in-process).
    scheduler : str, optional
        Dask scheduler address (takes precedence over ``workers``).

    Returns
    -------
    tuple
        (concurrent.futures.Executor, callable that shuts it down).

    Raises
    ------
    ConfigError
        ``scheduler`` given but ``distributed`` is not installed, or it cannot be reached.
    """
    if scheduler:
        try:
            import distributed
        except ImportError:
            raise ConfigError("--scheduler needs the optional Dask dependency: pip install 'acmm-qpp[dask]'") from None
        try:
            from common.limits import limit

            client = distributed.Client(scheduler, timeout=f"{limit('DASK_CONNECT_SECONDS'):g}s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ConfigError(f"cannot connect to the Dask scheduler at {scheduler}: {exc}") from None
        return client.get_executor(pure=False), client.close
    if workers <= 1:
        return SerialExecutor(), lambda: None
    import multiprocessing

    ctx = multiprocessing.get_context("fork") if sys.platform.startswith("linux") else None
    from common.workers import die_with_parent

    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=die_with_parent,
                                  initargs=(os.getpid(),))
    return pool, lambda: pool.shutdown(wait=True, cancel_futures=True)




def _tasks(sweep: Sweep):
    n = sweep.spec.n_cases()
    for b in sweep.bases:
        for i in range(n):
            yield ("case", b.label, i)
    if sweep.spec.margin is not None:
        for b in sweep.bases:
            for d in ("up", "down"):
                yield ("margin", b.label, d)


def _task_key(rec_or_task) -> tuple:
    if isinstance(rec_or_task, dict):
        r = rec_or_task
        return ("case", r["base"], r["index"]) if r["kind"] == "case" else ("margin", r["base"], r["direction"])
    return tuple(rec_or_task)


def _call(task, ctx):
    kind, _, arg = task
    return run_case(ctx, arg) if kind == "case" else margin_search(ctx, arg)


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

_WARM = False


def chunk_size(n_tasks: int, workers: int, case_seconds: Optional[float] = None,
               n_total: Optional[int] = None) -> int:
    """Cases per task when ``n_tasks`` cases remain for ``workers`` workers (a pool or a Dask
    cluster; the in-process executor runs one case per task).

    ⌈n / (8·workers)⌉: about 8 tasks per worker over what remains (the tail imbalance is then
    ≤ 1/8 of a worker's remaining share).  Without ``case_seconds`` (the cost of one case on one
    worker, s; not yet measured) it is clipped to [1, :data:`MAX_CHUNK`]; with it, to the cases
    that take :data:`MIN_TASK_SECONDS` … :data:`MAX_TASK_SECONDS`, and never above
    ⌈``n_total`` / workers⌉ (every worker gets a share of a small sweep; ``n_total``: the tasks of
    the whole sweep, default ``n_tasks``).  See README *Performance* for why this holds at large N.

    Parameters
    ----------
    n_tasks : int
        Tasks still to hand out.
    workers : int
        Number of workers.
    case_seconds : float, optional
        Measured cost of one case on one worker, s (None: not measured yet).
    n_total : int, optional
        Tasks of the whole sweep (default ``n_tasks``).

    Returns
    -------
    int
        Cases per task.
    """
    n_workers = max(1, workers)
    c = -(-n_tasks // (CHUNKS_PER_WORKER * n_workers))
    if case_seconds is None or not case_seconds > 0:
        return max(1, min(MAX_CHUNK, c))
    lo = max(1, math.ceil(MIN_TASK_SECONDS / case_seconds))
    hi = max(lo, int(MAX_TASK_SECONDS / case_seconds))
    return max(1, min(max(c, lo), hi, -(-(n_total or n_tasks) // n_workers)))


class Chunker:
    """The tasks handed out in chunks as they are submitted (guided self-scheduling).

    Each chunk holds consecutive case tasks of one base (a margin search alone).  Its size is
    ``size`` when given, else :func:`chunk_size` of the tasks still to hand out with the cost of
    a case measured so far: ``workers`` × the time since the first chunk came back / the cases
    that came back since (the throughput of the whole run, so it includes every per-task cost;
    before every worker can have returned a chunk, unmeasured).  The results do not depend on
    the chunking.

    Parameters
    ----------
    tasks : list of tuple
        Tasks ``("case", base, index)`` or ``("margin", base, direction)``, in order.
    workers : int
        Number of workers (Dask: worker threads).
    size : int, optional
        Fixed cases per chunk (None: guided, as above).
    """

    def __init__(self, tasks: list, workers: int, size: Optional[int] = None):
        self._tasks, self._pos = tasks, 0
        self.workers = max(1, workers)
        self.size = size
        self._first_back: Optional[float] = None
        self._cases_since = 0
        self._chunks_since = 0

    def case_seconds(self) -> Optional[float]:
        """Measured cost of one case on one worker.

        Returns
        -------
        float or None
            Cost of one case, s; None before there is a measure.
        """
        if self._first_back is None or self._chunks_since < self.workers or self._cases_since == 0:
            return None
        return self.workers * (time.monotonic() - self._first_back) / self._cases_since

    def returned(self, n_tasks: int) -> None:
        """Record that a chunk came back.

        Parameters
        ----------
        n_tasks : int
            Tasks in the chunk.
        """
        if self._first_back is None:
            self._first_back = time.monotonic()
        else:
            self._chunks_since += 1
            self._cases_since += n_tasks

    def next(self) -> Optional[list]:
        """The next chunk.

        Returns
        -------
        list of tuple or None
            Its tasks, or None when every task was handed out.
        """
        tasks, pos = self._tasks, self._pos
        if pos >= len(tasks):
            return None
        size = self.size or chunk_size(len(tasks) - pos, self.workers, self.case_seconds(), len(tasks))
        chunk = [tasks[pos]]
        pos += 1
        if chunk[0][0] == "case":
            while (pos < len(tasks) and len(chunk) < size and tasks[pos][0] == "case"
                   and tasks[pos][1] == chunk[0][1]):
                chunk.append(tasks[pos])
                pos += 1
        self._pos = pos
        return chunk


def make_chunks(tasks: list, size: int) -> list[list]:
    """Consecutive case tasks of one base in lists of ``size``; each margin search alone.

    Parameters
    ----------
    tasks : list of tuple
        Tasks ``("case", base, index)`` or ``("margin", base, direction)``, in order.
    size : int
        Most case tasks per chunk.

    Returns
    -------
    list of list
        The chunks, in order.
    """
    chunks: list[list] = []
    for t in tasks:
        if (t[0] == "case" and chunks and len(chunks[-1]) < size and chunks[-1][0][0] == "case"
                and chunks[-1][0][1] == t[1]):
            chunks[-1].append(t)
        else:
            chunks.append([t])
    return chunks


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
        import ctypes

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
        from distributed.worker import Worker

        return bool(Worker._instances)
    except (ImportError, AttributeError):
        return False


def _warm_worker() -> None:
    """Once per worker process: load the compiled kernels (from numba's cache: no compile) and
    in a Dask worker restore heap reuse (:func:`_restore_heap_reuse`); a long-lived Dask cluster can be warmed
    ahead with ``client.run(acmm.sweep._warm_worker)``."""
    global _WARM
    if not _WARM:
        from acmm.warmup import warm_up

        if _in_dask_worker():        # only the nanny's environment needs it; the user's own
            _restore_heap_reuse()    # MALLOC_* choice in a driver or pool process is left alone
        warm_up()
        _WARM = True


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


def _call_chunk(chunk, ctx) -> list[dict]:
    """Run the tasks of one chunk in order; returns their records."""
    _warm_worker()
    ctx = _local_context(ctx)
    return [_call(t, ctx) for t in chunk]


def _scheduler_workers(executor, default: int) -> int:
    """Number of workers (threads) of the Dask cluster behind ``executor``, else ``default``."""
    client = getattr(executor, "_client", None)
    if client is None:
        return max(1, default)
    try:
        return max(1, sum(int(v) for v in client.nthreads().values()))
    except (AttributeError, KeyError, OSError, TypeError, ValueError):
        return max(1, default)


def _remote_contexts(executor, contexts: dict) -> dict:
    """The base contexts as the executor's tasks take them: on a Dask cluster scattered once to
    every worker (a task then carries a reference, not a pickled design); else as they are."""
    client = getattr(executor, "_client", None)
    if client is None or not contexts:
        return contexts
    try:
        return {k: client.scatter(v, broadcast=True, hash=False) for k, v in contexts.items()}
    except (AttributeError, TypeError, ValueError):
        return contexts

