"""Terminal progress for the command lines (rich), on stderr and only on an interactive terminal.

When stderr is not a TTY (a pipe, a CI log, a test) no progress is shown (:func:`enabled`), so
errors stay one line and captured output is unchanged.  ``ACMM_PROGRESS=0`` silences it on a
terminal too, ``ACMM_PROGRESS=1`` forces it (for demonstrations).  Each product draws its own
with the :func:`console` (acmm's bar and notes, qpp's spinner).
"""
from __future__ import annotations

import os
import sys


def enabled() -> bool:
    """Progress is shown: stderr is a terminal (or ``ACMM_PROGRESS=1``), and not ``ACMM_PROGRESS=0``.

    Returns
    -------
    bool
        True when progress output goes to stderr.
    """
    env = os.environ.get("ACMM_PROGRESS")
    if env is not None and env.strip() in ("0", "1"):
        return env.strip() == "1"
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def console():
    """A rich console on stderr (a terminal forced by ``ACMM_PROGRESS=1``).

    Returns
    -------
    rich.console.Console
        The console.
    """
    from rich.console import Console  # deferred: rich start-up, only on a terminal

    return Console(stderr=True, force_terminal=True if os.environ.get("ACMM_PROGRESS") == "1" else None)

