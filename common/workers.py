"""Worker-process hygiene for local process pools (issue 13: a killed sweep leaves no orphans).

:func:`die_with_parent` is the ``initializer`` of the sweep's ``ProcessPoolExecutor``: on Linux
it asks the kernel to send SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``,
which covers ``kill -9`` of the parent); elsewhere, and as a second line of defence, a daemon
thread polls ``os.getppid()`` once a second and exits the worker when the parent is gone.
"""
from __future__ import annotations

import os
import threading
import time

from common.signals import die_with_parent as _die_with_parent


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
