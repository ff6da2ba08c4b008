"""Figures drawn and written in forked child processes while the caller goes on (issue 16).

Drawing a figure and encoding it (PNG, PDF) is most of its cost and needs nothing back from the
child, so a stage or the report can hand each ``savefig`` to a forked process and build the next
figure (or compute the next section) meanwhile; on a machine with a free core the figures then
cost little more than building them.

    parallel_figures.enable()        # from here on run() forks (POSIX, > 1 CPU)
    parallel_figures.run(lambda: fig.savefig(...), path)
    parallel_figures.wait()          # join; raises OutputError with the first failure's message

Opt-in: only with the environment variable ``ACMM_PARALLEL_FIGURES=1`` (and ``os.fork``, > 1 CPU).
Measured on the shared 2-core machine (load ≈ 2) it gained nothing — each child redraws with cold
font and glyph caches and there was no idle core — and forking a process that may hold threads
(a notebook, a Dask worker) is a risk, so the default stays sequential; on an idle multi-core
machine it overlaps the figure writing with the next figure.  Otherwise :func:`run` calls the
function in place, so callers need not care.  At most one writer per CPU runs at a time.

The stages (``acmm design``/``simulate``) no longer use it: :mod:`acmm_qpp.figure_worker` (one
pre-importing worker forked when the stage starts, skeletons built ahead) took ``acmm simulate
staircase`` with figures from 3.5 s to 1.6 s (2 cores, best of 3), where this module's
fork-per-``savefig`` gave 3.1 s (each writer still paid the drawing after the stage's own
building of the figure).  It stays opt-in for the report.
"""
from __future__ import annotations

import os
import sys
from typing import Callable

#: (pid, read end of the error pipe, what) of the running writers; None: not enabled
_PENDING: list | None = None


def enable(enabled: bool = True) -> bool:
    """Start forking figure writers; returns whether it is on.

    Parameters
    ----------
    enabled : bool, optional
        Ask for forking (granted only with ``ACMM_PARALLEL_FIGURES=1``, ``os.fork`` and > 1 CPU).

    Returns
    -------
    bool
        Forking is on.
    """
    global _PENDING
    if os.environ.get("ACMM_PARALLEL_FIGURES", "0") != "1":
        enabled = False
    if enabled and hasattr(os, "fork") and (os.cpu_count() or 1) > 1 and _PENDING is None:
        _PENDING = []
    return _PENDING is not None


def active() -> bool:
    """Whether :func:`run` forks (enabled and not yet waited for).

    Returns
    -------
    bool
        Forking is on.
    """
    return _PENDING is not None


def forget() -> None:
    """In a forked process: drop the parent's writers (not this process's children) and run
    in place from now on."""
    global _PENDING
    _PENDING = None


def run(fn: Callable[[], object], what: str = "figure") -> None:
    """``fn()`` in a forked child when enabled, else here.

    Parameters
    ----------
    fn : callable
        Writes one figure; takes no argument.
    what : str, optional
        What it writes, for the error message when the child fails.
    """
    if _PENDING is None:
        fn()
        return
    while len(_PENDING) >= (os.cpu_count() or 1):
        _join_one(_PENDING.pop(0))
    sys.stdout.flush()
    sys.stderr.flush()
    r, w = os.pipe()
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:                                      # child: write, report, leave without cleanup
        from acmm_qpp.signals import die_with_parent

        die_with_parent(parent)
        os.close(r)
        code = 0
        try:
            fn()
        except BaseException as exc:  # noqa: BLE001 (reported to the parent through the pipe)
            os.write(w, (str(exc) or type(exc).__name__).encode()[:4000])
            code = 1
        finally:
            os._exit(code)
    os.close(w)
    _PENDING.append((pid, r, what))


_FAILED: list[str] = []


def _join_one(entry) -> None:
    pid, fd, what = entry
    with os.fdopen(fd, "rb") as f:
        msg = f.read().decode(errors="replace")
    _, status = os.waitpid(pid, 0)
    if msg or os.waitstatus_to_exitcode(status) != 0:
        _FAILED.append(msg or f"cannot write {what}: the writer process failed")


def wait() -> None:
    """Join every writer and stop forking.

    Raises
    ------
    OutputError
        A figure could not be written (the first failure's message).
    """
    global _PENDING
    pending, _PENDING = _PENDING, None
    for entry in pending or []:
        _join_one(entry)
    if _FAILED:
        first = _FAILED[0]
        _FAILED.clear()
        from acmm_qpp.errors import OutputError

        raise OutputError(first)
