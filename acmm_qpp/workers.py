"""Worker-process hygiene for local process pools (issue 13: a killed sweep leaves no orphans).

:func:`pool_worker` is the ``initializer`` of the sweep's and the report's ``ProcessPoolExecutor``
(submitted to with :func:`submit`, stopped with :func:`stop_pool`); its :func:`die_with_parent`: on Linux
it asks the kernel to send SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``,
which covers ``kill -9`` of the parent); elsewhere, and as a second line of defence, a daemon
thread polls ``os.getppid()`` once a second and exits the worker when the parent is gone.
"""
from __future__ import annotations

import os
import threading
import time

from acmm_qpp.signals import die_with_parent as _die_with_parent
from acmm_qpp.signals import hold_interrupts, release_interrupts


def _watch(parent: int, interval: float) -> None:
    while True:
        time.sleep(interval)
        if os.getppid() != parent:
            os._exit(1)


def die_with_parent(parent: int, interval: float = 1.0) -> None:
    """Make this (worker) process exit when process ``parent`` dies.

    Parameters
    ----------
    parent : int
        Process id of the parent (the pool's owner).
    interval : float, optional
        Polling period of the watch thread, s.
    """
    _die_with_parent(parent)            # PR_SET_PDEATHSIG; SIGTERM/SIGHUP back to their defaults
    threading.Thread(target=_watch, args=(parent, interval), daemon=True, name="parent-watch").start()


def pool_worker(parent: int) -> None:
    """Set up a local pool's worker (the sweep's, the report's; call it first in the pool's
    ``initializer``): Ctrl-C, which a terminal sends to the whole process group, is the parent's
    alone, which then stops the pool (a worker interrupted too printed a traceback or broke the
    pool's shutdown: a review), and the worker dies with the parent (:func:`die_with_parent`).
    The parent forks it with the interrupts held (:func:`acmm_qpp.signals.hold_interrupts`, a mask
    that a fork inherits), so no Ctrl-C reaches it before this; they are unblocked here.

    Parameters
    ----------
    parent : int
        Process id of the parent (the pool's owner).
    """
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(parent)             # SIGTERM and SIGHUP back to their default action
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP})


def submit(executor, fn, *args):
    """``executor.submit(fn, *args)``; for a process pool with the interrupts held, so that a
    worker it forks now inherits the held mask and no Ctrl-C reaches it before
    :func:`pool_worker` (other executors fork nothing).

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
    import concurrent.futures as cf

    held = hold_interrupts() if isinstance(executor, cf.ProcessPoolExecutor) else None
    try:
        return executor.submit(fn, *args)
    finally:
        release_interrupts(held)


def stop_pool(pool, abort: bool = False) -> None:
    """Shut a ``ProcessPoolExecutor`` down, the interrupts held (a second Ctrl-C broke the
    shutdown: a hang); with ``abort`` (the parent was interrupted or failed) its workers are
    killed first instead of finishing tasks whose results nobody will read.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        The pool.
    abort : bool, optional
        Kill the running tasks.
    """
    held = hold_interrupts()
    try:
        if abort:
            for p in list((getattr(pool, "_processes", None) or {}).values()):
                try:
                    p.kill()
                except (OSError, ValueError, AttributeError):   # already gone, or closed
                    pass
        pool.shutdown(wait=True, cancel_futures=True)
    finally:
        release_interrupts(held)
