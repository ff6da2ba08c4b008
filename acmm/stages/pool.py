"""acmm's one local process pool (the design stage's LMI points, the sweep's cases, the report's tasks).

:func:`process_pool` is a standard :class:`concurrent.futures.ProcessPoolExecutor` whose workers
leave Ctrl-C to the parent (a terminal sends it to the whole process group: a worker interrupted
too printed a traceback or broke the pool's shutdown) and die with it (Linux
``prctl(PR_SET_PDEATHSIG)``, and elsewhere a daemon thread that watches ``os.getppid()``), so a
killed sweep or report leaves no orphans.  :func:`submit` forks new workers with the interrupts
deferred, so none breaks a fork; :func:`stop_pool` shuts the pool down, killing its
workers first when the parent was interrupted.  A caller whose tasks' warnings matter (the
report's) sends them back with each result (:func:`portable_warnings`) and raises them again in
the parent as if computed there (:func:`raise_warnings_again`); the sweep's workers print theirs.
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import time
import warnings

from acmm_qpp.errors import OutputError
from acmm_qpp.signals import TERMINATING, interrupts_deferred, switch_handlers

#: prctl(2) option: the signal a process gets when its parent thread exits (Linux)
PR_SET_PDEATHSIG = 1


def process_pool(workers: int, initializer=None) -> cf.ProcessPoolExecutor:
    """A process pool of ``workers`` processes set up by :func:`_pool_worker`.

    Parameters
    ----------
    workers : int
        Number of worker processes.
    initializer : callable, optional
        Called (without arguments) in each worker after its set-up (e.g. to empty a cache).

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        The pool (Linux: forked workers, which inherit this process's imports).
    """
    ctx = multiprocessing.get_context("fork") if sys.platform.startswith("linux") else None
    return cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_pool_worker,
                                  initargs=(os.getpid(), initializer))


def _pool_worker(parent: int, initializer=None, interval: float = 1.0) -> None:
    """A pool worker's set-up: Ctrl-C is the parent's alone; SIGTERM and SIGHUP take their default
    action (a child is stopped by its parent, or by the signal itself); the worker dies with
    ``parent``, however it exits (``kill -9`` included): SIGKILL from the kernel when the thread
    that forked it exits (Linux ``prctl(PR_SET_PDEATHSIG)``), an exit at once if it is already
    gone, and a daemon thread polling ``os.getppid()`` every ``interval`` s (where ``prctl`` does
    not exist); then ``initializer()``."""
    switch_handlers({signal.SIGINT: signal.SIG_IGN, **{sig: signal.SIG_DFL for sig in TERMINATING}})
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    if os.getppid() != parent:               # the parent died before the prctl above
        os._exit(1)

    def watch():
        while True:
            time.sleep(interval)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()
    if initializer is not None:
        initializer()


def submit(executor, fn, *args):
    """``executor.submit(fn, *args)``; for a process pool with the interrupts deferred
    (:func:`acmm_qpp.signals.interrupts_deferred`), so that none breaks the forking of a worker
    (other executors fork nothing).

    Parameters
    ----------
    executor : concurrent.futures.Executor
        The executor.
    fn : callable
        The task.
    *args : object
        Its arguments.

    Returns
    -------
    concurrent.futures.Future
        The task's future.
    """
    with interrupts_deferred() if isinstance(executor, cf.ProcessPoolExecutor) else contextlib.nullcontext():
        return executor.submit(fn, *args)


def _recording_warnings(fn, x):
    """``(fn(x), its warnings)`` for :func:`pool_map` (the warnings as :func:`portable_warnings`)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        value = fn(x)
    return value, portable_warnings(caught)


def pool_map(executor, fn, items):
    """``fn(x) for x in items`` computed on ``executor``: every task submitted first
    (:func:`submit`, the interrupts deferred), each result yielded as soon as it and those before it
    are done, in the order of ``items``, the warnings of each task raised again here first
    (:func:`raise_warnings_again`: this process's filters apply, as if computed in place).

    Parameters
    ----------
    executor : concurrent.futures.Executor
        The executor (e.g. :func:`process_pool`).
    fn : callable
        The task (picklable for a process pool).
    items : iterable
        Its arguments, one task each.

    Yields
    ------
    object
        The results, in order; the first task's error (in that order) is raised.

    Raises
    ------
    OutputError
        A worker process died.
    """
    futures = [submit(executor, _recording_warnings, fn, x) for x in items]
    for f in futures:
        try:
            value, raised = f.result()
        except cf.BrokenExecutor:
            raise OutputError("a worker process died (killed, or out of memory); nothing was written") from None
        raise_warnings_again(raised)
        yield value


def stop_pool(pool: cf.ProcessPoolExecutor, abort: bool = False) -> None:
    """Shut a pool down, the interrupts deferred (a second Ctrl-C broke the shutdown: a hang); with
    ``abort`` (the parent was interrupted or failed) its workers are killed first instead of
    finishing tasks whose results nobody will read.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        The pool.
    abort : bool, optional
        Kill the running tasks.
    """
    with interrupts_deferred():
        if abort:
            for p in list((getattr(pool, "_processes", None) or {}).values()):
                with contextlib.suppress(OSError, ValueError, AttributeError):   # already gone, or closed
                    p.kill()
        pool.shutdown(wait=True, cancel_futures=True)


def portable_warnings(caught) -> list:
    """Warnings recorded in a worker, ready to send to the parent: each is checked to come back
    out of a pickle; one that does not travels as its text with the nearest built-in category.

    Parameters
    ----------
    caught : list of warnings.WarningMessage
        What ``warnings.catch_warnings(record=True)`` recorded.

    Returns
    -------
    list of tuple
        (message, category, filename, lineno) of each, for :func:`raise_warnings_again`.
    """
    out = []
    for w in caught:
        item = (w.message, w.category, w.filename, w.lineno)
        try:
            pickle.loads(pickle.dumps(item[:2], protocol=pickle.HIGHEST_PROTOCOL))
        except Exception:  # noqa: BLE001
            base = next(c for c in w.category.__mro__ if c.__module__ == "builtins" and issubclass(c, Warning))
            item = (str(w.message), base, w.filename, w.lineno)
        out.append(item)
    return out


def raise_warnings_again(raised: list) -> None:
    """Raise a worker's warnings (:func:`portable_warnings`) in this process, each as from the
    module it came from: its filters and its ``__warningregistry__`` apply, so a warning already
    shown under "default" or "once" is not shown again, as computing in place would not.

    Parameters
    ----------
    raised : list of tuple
        (message, category, filename, lineno) of each warning, in the order raised.
    """
    if not raised:
        return
    by_file = {}
    for mod in list(sys.modules.values()):
        f = getattr(mod, "__file__", None)
        if isinstance(f, str):
            by_file.setdefault(os.path.realpath(f), mod)
    for message, category, filename, lineno in raised:
        mod = by_file.get(os.path.realpath(filename)) if isinstance(filename, str) else None
        if mod is None:
            warnings.warn_explicit(message, category, filename, lineno)
        else:
            warnings.warn_explicit(message, category, filename, lineno, module=mod.__name__,
                                   registry=mod.__dict__.setdefault("__warningregistry__", {}),
                                   module_globals=mod.__dict__)
