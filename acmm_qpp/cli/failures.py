"""How a command's failures and side notes become one line each (used by :func:`acmm_qpp.cli.plumbing.user_errors`):
exceptions outside the :class:`acmm_qpp.errors.AcmmError` hierarchy (:func:`acmm_qpp.errors.plain_failure`,
shared with the report's failed sections), an interrupt that Python
wrapped in another exception, the numerical warnings of a run, a closed
standard output."""
from __future__ import annotations

import os
import sys

import typer


def interrupt_behind(exc: BaseException):
    """The Ctrl-C/SIGTERM behind ``exc`` (its cause or context), else None.

    Parameters
    ----------
    exc : BaseException
        The exception a command raised.

    Returns
    -------
    KeyboardInterrupt or None
        The interrupt in its chain of causes and contexts.
    """
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def note_warnings(caught) -> None:
    """One summary line for the numpy/scipy warnings a successful command raised (never raw).

    Parameters
    ----------
    caught : list of warnings.WarningMessage
        The warnings recorded while the command ran.
    """
    if not caught:
        return
    first = caught[0]
    typer.echo(f"note: {len(caught)} distinct numerical warning(s) during the run; first: "
               f"{first.category.__name__}: {' '.join(str(first.message).split())}", err=True)


#: exit code when the reader of standard output closed it (128 + SIGPIPE, as a C tool killed by it)
EXIT_PIPE_CLOSED = 141


def quiet_stdout() -> None:
    """Point stdout at /dev/null, so that flushing it at exit raises nothing more."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
