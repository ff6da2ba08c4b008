"""Executors (in-process, process pool, Dask) and the tasks they run: case and margin tasks
(cut into chunks by :mod:`acmm.sweep.chunking`), worker warm-up and base contexts made local or
scattered."""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import functools
import hashlib
import os
import sys
from pathlib import Path
from typing import Optional

import numpy as np

from acmm_qpp.errors import ConfigError
from acmm.stages.pool import process_pool, stop_pool
from acmm.sweep.config import Sweep
from acmm.sweep.case import BaseContext, margin_search, run_case
import ctypes
from acmm_qpp.limits import limit
from acmm import LIMITS, __version__
from acmm.simulate.warmup import warm_up


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
        return SerialExecutor(), lambda abort=False: None
    pool = process_pool(workers)
    return pool, lambda abort=False: stop_pool(pool, abort)


def lost_worker(exc: BaseException) -> Optional[str]:
    """What went wrong when a task's future raised ``exc`` because its worker, not its case,
    failed (None: the task's own error).

    Parameters
    ----------
    exc : BaseException
        The exception of ``future.result()``.

    Returns
    -------
    str or None
        One line for the user.
    """
    if isinstance(exc, cf.BrokenExecutor):
        what = "a sweep worker process died (killed, or out of memory)"
    elif type(exc).__name__ == "KilledWorker":
        what = f"the Dask workers that ran a task died too often (KilledWorker: {exc})"
    elif isinstance(exc, cf.CancelledError):
        what = "the Dask cluster dropped a task (its scheduler or workers went away)"
    else:
        return None
    return what + "; the finished cases are kept in the journal: run the sweep again with --resume"


def sweep_tasks(sweep: Sweep):
    """The tasks of a sweep, in order: every case of every base, then the margin searches.

    Parameters
    ----------
    sweep : Sweep
        The sweep.

    Yields
    ------
    tuple
        ``("case", base, index)`` or ``("margin", base, direction)``.
    """
    n = sweep.spec.n_cases()
    for b in sweep.bases:
        for i in range(n):
            yield ("case", b.label, i)
    if sweep.spec.margin is not None:
        for b in sweep.bases:
            for d in ("up", "down"):
                yield ("margin", b.label, d)


def task_key(rec_or_task) -> tuple:
    """The key of a task, or of the record a task returned (:func:`sweep_tasks`' tuples).

    Parameters
    ----------
    rec_or_task : dict or tuple
        A journal record or a task.

    Returns
    -------
    tuple
        ``("case", base, index)`` or ``("margin", base, direction)``.
    """
    if isinstance(rec_or_task, dict):
        r = rec_or_task
        return ("case", r["base"], r["index"]) if r["kind"] == "case" else ("margin", r["base"], r["direction"])
    return tuple(rec_or_task)


def _call(task, ctx):
    kind, _, arg = task
    return run_case(ctx, arg) if kind == "case" else margin_search(ctx, arg)


_WARM = False


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


def warm_worker() -> None:
    """Once per worker process: load the compiled kernels (from numba's cache: no compile) and
    in a Dask worker restore heap reuse (:func:`_restore_heap_reuse`); a long-lived Dask cluster can be warmed
    ahead with ``client.run(acmm.sweep.executors.warm_worker)``."""
    global _WARM
    if not _WARM:
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


def call_chunk(chunk, ctx, code: Optional[str] = None) -> list[dict]:
    """Run the tasks of one chunk in order.  ``code``: the driver's
    :func:`code_identity`, checked on a Dask worker (started elsewhere, it may
    run other acmm code, whose rows would enter the table unnoticed: a review).

    Parameters
    ----------
    chunk : list of tuple
        The tasks (:func:`sweep_tasks`).
    ctx : object
        The bases' contexts (or their Dask futures).
    code : str, optional
        The driver's code identity.

    Returns
    -------
    list of dict
        The tasks' records.
    """
    if code is not None:
        same_code(code)
    warm_worker()
    ctx = _local_context(ctx)
    return [_call(t, ctx) for t in chunk]


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


def same_code(code: str) -> None:
    """Check that this (worker) process runs the code of the driver.

    Parameters
    ----------
    code : str
        The driver's :func:`code_identity`.

    Raises
    ------
    ConfigError
        This process runs other code.
    """
    if code != code_identity():
        raise ConfigError(f"--scheduler: a Dask worker runs other acmm code ({code_identity()}) than this "
                          f"command ({code}): start the workers from the same installation")


def scheduler_workers(executor, default: int) -> int:
    """Number of workers (threads) of the Dask cluster behind ``executor``, else ``default``.

    Parameters
    ----------
    executor : concurrent.futures.Executor
        The sweep's executor.
    default : int
        The count when it has no Dask client.

    Returns
    -------
    int
        At least 1.
    """
    client = getattr(executor, "_client", None)
    if client is None:
        return max(1, default)
    try:
        return max(1, sum(int(v) for v in client.nthreads().values()))
    except (AttributeError, KeyError, OSError, TypeError, ValueError):
        return max(1, default)


def remote_contexts(executor, contexts: dict) -> dict:
    """The base contexts as the executor's tasks take them: on a Dask cluster scattered once to
    every worker (a task then carries a reference, not a pickled design); else as they are.

    Parameters
    ----------
    executor : concurrent.futures.Executor
        The sweep's executor.
    contexts : dict
        Base label → its context.

    Returns
    -------
    dict
        Base label → the context or its future.
    """
    client = getattr(executor, "_client", None)
    if client is None or not contexts:
        return contexts
    try:
        return {k: client.scatter(v, broadcast=True, hash=False) for k, v in contexts.items()}
    except (AttributeError, TypeError, ValueError):
        return contexts

