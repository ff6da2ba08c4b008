"""Termination signals unwind like Ctrl-C (issue 13: nothing half-written), for both products.

A command that receives SIGTERM or SIGHUP (``kill``, ``timeout``, a closed terminal, a batch
system's time limit) unwinds like Ctrl-C: :func:`terminate_like_ctrl_c` makes the signal raise
:class:`acmm_qpp.errors.Terminated` (a ``KeyboardInterrupt``), so Python's own interrupt path runs:
a stage removes its staging folder (:mod:`acmm_qpp.outputs`), a process pool is stopped by its
owner, and the command exits with 128 + the signal number.  The few
steps that must not stop halfway (a finished stage's files moved into place, a pool's workers
forked or stopped) run inside :func:`interrupts_deferred`.
"""
from __future__ import annotations

import contextlib
import signal
import threading
from contextlib import contextmanager

from acmm_qpp.errors import Terminated

#: the signals :func:`terminate_like_ctrl_c` turns into :class:`acmm_qpp.errors.Terminated`
TERMINATING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


def _raise_terminated(signum, frame) -> None:
    """The handler of SIGTERM and SIGHUP: raise :class:`acmm_qpp.errors.Terminated`."""
    raise Terminated(signum)


def switch_handlers(handlers: dict) -> dict:
    """Install ``handlers`` with those signals blocked meanwhile (main thread only).

    CPython runs a pending signal's handler at the start of each :func:`signal.signal`; a signal
    landing between that check and a switch to ``SIG_IGN`` was found pending by the next switch
    with no handler left, and reported on stderr ("Signal 2 ignored due to race condition", a
    traceback) under a second Ctrl-C (a test run).  Blocked, it waits for the end of the switch:
    then discarded (``SIG_IGN``) or handled by the new handler.

    Parameters
    ----------
    handlers : dict
        Signal number → handler (a callable, ``signal.SIG_IGN`` or ``signal.SIG_DFL``).

    Returns
    -------
    dict
        Signal number → the handler it replaced.
    """
    mask = getattr(signal, "pthread_sigmask", None)
    blocked = mask(signal.SIG_BLOCK, handlers) if mask is not None else None
    try:
        return {sig: signal.signal(sig, handler) for sig, handler in handlers.items()}
    finally:
        if blocked is not None:
            mask(signal.SIG_SETMASK, blocked)


def ignore_interrupts() -> None:
    """Ignore Ctrl-C, SIGTERM and SIGHUP from now on in this process (``SIG_IGN``; main thread only).

    The three are blocked while they are switched, so that one arriving meanwhile is discarded
    instead of reported on stderr as a race by CPython.
    """
    switch_handlers({sig: signal.SIG_IGN for sig in (signal.SIGINT, *TERMINATING)})


def _first_interrupt(signum, frame) -> None:
    """The handler of ``terminate_like_ctrl_c(once=True)``: every later interrupt ignored, then this
    one raised (Ctrl-C as ``KeyboardInterrupt``, SIGTERM or SIGHUP as :class:`acmm_qpp.errors.Terminated`)."""
    ignore_interrupts()
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


def terminate_like_ctrl_c(once: bool = False) -> list[int]:
    """Make SIGTERM and SIGHUP raise :class:`acmm_qpp.errors.Terminated` in this (main) thread,
    where their handler is still the default one (a caller's own handler is left alone).

    With ``once`` (a command's process) only the first interrupt counts: the first Ctrl-C, SIGTERM
    or SIGHUP unwinds and every later one is ignored, so that it cannot break the unwinding.  A
    terminal sends Ctrl-C twice in a row to the process group: the second one, arriving after the
    first had raised but before the clean-up deferred interrupts, skipped a sweep pool's shutdown,
    and the sweep hung at exit while its workers finished their cases (a CI run).

    Parameters
    ----------
    once : bool, optional
        Ctrl-C too, and only the first interrupt raises.

    Returns
    -------
    list of int
        The signals whose handler was installed (none outside the main thread).
    """
    if threading.current_thread() is not threading.main_thread():
        return []
    done = []
    defaults = {sig: signal.SIG_DFL for sig in TERMINATING}
    if once:
        defaults[signal.SIGINT] = signal.default_int_handler
    for sig, default in defaults.items():
        with contextlib.suppress(OSError, ValueError):        # not settable here
            if signal.getsignal(sig) is default:
                signal.signal(sig, _first_interrupt if once else _raise_terminated)
                done.append(int(sig))
    return done


@contextmanager
def interrupts_deferred():
    """Run the ``with`` block whole: Ctrl-C, SIGTERM or SIGHUP arriving meanwhile is handled at
    its end (by the handler that was in force, as if it arrived then).  Only in the main thread,
    where Python runs signal handlers; elsewhere the block just runs.

    Yields
    ------
    None
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived: list[int] = []
    old = {}
    try:
        old = switch_handlers({sig: lambda signum, frame: arrived.append(signum) for sig in (signal.SIGINT, *TERMINATING)})
        yield
    finally:
        switch_handlers(old)
        if arrived:
            signal.raise_signal(arrived[0])   # now, with the handler of before
