"""Worker-process hygiene for local process pools (issue 13: a killed sweep leaves no orphans).

:func:`die_with_parent` is the ``initializer`` of the sweep's ``ProcessPoolExecutor``: on Linux
it asks the kernel to send SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``,
which covers ``kill -9`` of the parent); elsewhere, and as a second line of defence, a daemon
thread polls ``os.getppid()`` once a second and exits the worker when the parent is gone.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time

PR_SET_PDEATHSIG = 1


def _set_pdeathsig() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


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
    _set_pdeathsig()
    if os.getppid() != parent:          # the parent died before the prctl took effect
        os._exit(1)
    threading.Thread(target=_watch, args=(parent, interval), daemon=True, name="parent-watch").start()
