"""Termination signals unwind like Ctrl-C (issue 13: nothing half-written), for both products.

A command that receives SIGTERM or SIGHUP (``kill``, ``timeout``, a closed terminal, a batch
system's time limit) unwinds like Ctrl-C: :func:`terminate_like_ctrl_c` makes the signal raise
:class:`acmm_qpp.errors.Terminated` (a ``KeyboardInterrupt``), so Python's own interrupt path runs:
the stage rolls its outputs back (:mod:`acmm_qpp.outputs`), a pool is stopped
(:func:`acmm_qpp.pool.stop_pool`), and the command exits with 128 + the signal number.  Steps
that must not stop halfway (a run lock taken, a rollback folder built or dropped) hold the
interrupts (:func:`hold_interrupts`) and take them at their end (:func:`release_interrupts`).
"""
from __future__ import annotations

import signal
import threading
import time

from acmm_qpp.errors import Terminated

#: the signals :func:`terminate_like_ctrl_c` turns into :class:`acmm_qpp.errors.Terminated`
TERMINATING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))

#: interrupts received while held (:func:`hold_interrupts`), handled at the release;
#: ``raised``: when (monotonic s) the handler last raised one
_HELD = {"depth": 0, "pending": [], "raised": None}

#: an interrupt this soon (s) after the one raised before it is dropped
REPEAT_WINDOW = 2.0


def _raise_terminated(signum, frame) -> None:
    """The handler: KeyboardInterrupt for SIGINT, :class:`acmm_qpp.errors.Terminated` for the
    others; recorded instead while :func:`hold_interrupts` is in force.

    One arriving within :data:`REPEAT_WINDOW` s of the last one raised is dropped: the command is
    unwinding from that one, and a second exception raised inside its cleanup (in
    ``threading``'s lock handling, in a pool's shutdown) broke it — "RuntimeError: release
    unlocked lock", or a hang (a review).  A later one is raised as usual (also when the first
    was swallowed somewhere, e.g. in an at-fork hook, and the command went on)."""
    if _HELD["depth"]:                       # in a step that must not stop halfway: later
        _HELD["pending"].append(int(signum))
        return
    now = time.monotonic()
    if _HELD["raised"] is not None and now - _HELD["raised"] < REPEAT_WINDOW:
        return
    _HELD["raised"] = now
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


def hold_interrupts():
    """Block SIGINT, SIGTERM and SIGHUP in this (main) thread for a step that must not stop
    halfway (a run lock taken, a stage's rollback folder built or dropped); one arriving
    meanwhile is handled by :func:`release_interrupts`.

    Returns
    -------
    object
        What :func:`release_interrupts` needs (None in another thread: nothing is held there).
    """
    if threading.current_thread() is not threading.main_thread():
        return None
    _HELD["depth"] += 1                      # the handlers of terminate_like_ctrl_c wait
    mask = None
    if hasattr(signal, "pthread_sigmask"):   # the default Ctrl-C handler, in this thread
        try:
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, *TERMINATING})
        except (OSError, ValueError):
            mask = None
    return (mask,)


def release_interrupts(held) -> None:
    """End what :func:`hold_interrupts` began: a signal held meanwhile is handled now (Ctrl-C or
    :class:`acmm_qpp.errors.Terminated` raised at this point).

    Parameters
    ----------
    held : object
        What :func:`hold_interrupts` returned.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C arrived while held.
    acmm_qpp.errors.Terminated
        SIGTERM or SIGHUP arrived while held.
    """
    if held is None:
        return
    (mask,) = held
    _HELD["depth"] -= 1
    if mask is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    if not _HELD["depth"] and _HELD["pending"]:
        signum = _HELD["pending"][0]
        _HELD["pending"].clear()
        _raise_terminated(signum, None)      # the handler's exception, now


def terminate_like_ctrl_c() -> list[int]:
    """Make SIGTERM and SIGHUP raise :class:`acmm_qpp.errors.Terminated` (and SIGINT
    KeyboardInterrupt, as Python's own handler does) in this (main) thread, where their handler is
    still the default one (a caller's own handler is left alone); held while
    :func:`hold_interrupts` is in force.

    Returns
    -------
    list of int
        The signals whose handler was installed (none outside the main thread).
    """
    if threading.current_thread() is not threading.main_thread():
        return []
    done = []
    for sig, default in [(sig, signal.SIG_DFL) for sig in TERMINATING] + [(signal.SIGINT, signal.default_int_handler)]:
        try:
            if signal.getsignal(sig) is default:
                signal.signal(sig, _raise_terminated)
                done.append(int(sig))
        except (OSError, ValueError):        # not settable here
            pass
    return done
