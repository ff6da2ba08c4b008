"""Shared CLI plumbing: one clear message and a documented exit code for every user error
(:mod:`acmm.errors` lists the codes)."""
from __future__ import annotations

import functools
import sys

import typer

from acmm.errors import EXIT_INPUT, EXIT_INTERRUPTED, EXIT_NUMERICAL, EXIT_OUTPUT, AcmmError

EXIT_USER_ERROR = EXIT_INPUT


def fail(message: str, code: int = EXIT_INPUT) -> None:
    """Print ``error: message`` on stderr (one line) and exit with ``code`` (no traceback)."""
    message = " ".join(str(message).split())
    if len(message) > MAX_MESSAGE:        # e.g. a megabyte-long key echoed in a field name
        message = message[:MAX_MESSAGE - 20] + " … (truncated)"
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


MAX_MESSAGE = 600


def _plain_failure(exc: BaseException):
    """(message, exit code) for an exception that is not an :class:`AcmmError` but still a
    user-facing failure; ``None`` for a genuine bug (left to propagate)."""
    import numpy as np

    if isinstance(exc, RecursionError):
        return "input nested too deeply to process", EXIT_INPUT
    if isinstance(exc, MemoryError):
        return "out of memory (reduce the problem size)", EXIT_OUTPUT
    if isinstance(exc, (FloatingPointError, OverflowError, ZeroDivisionError, np.linalg.LinAlgError)):
        return f"numerical failure: {type(exc).__name__}: {exc}", EXIT_NUMERICAL
    if isinstance(exc, OSError):
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        return f"I/O error: {exc.strerror or exc}{where}", EXIT_OUTPUT
    return None


def _note_warnings(caught) -> None:
    """One summary line for the numpy/scipy warnings a successful command raised (never raw)."""
    if not caught:
        return
    first = caught[0]
    typer.echo(f"note: {len(caught)} distinct numerical warning(s) during the run; first: "
               f"{first.category.__name__}: {' '.join(str(first.message).split())}", err=True)


def user_errors(fn):
    """Decorator for typer commands: turn :class:`AcmmError` into one line on stderr and the
    error's ``exit_code``.

    numpy/scipy warnings are captured: a refused run prints only its error line; a successful
    one a single ``note:`` line counting them.  Numerical exceptions outside the hierarchy
    (``LinAlgError``, ``FloatingPointError``…) exit 3, OS errors 4, a ``RecursionError`` 2, all
    on one line."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import warnings

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")      # each distinct warning once (a hot loop stays cheap)
            try:
                out = fn(*args, **kwargs)
            except AcmmError as exc:
                fail(str(exc), exc.exit_code)
            except KeyboardInterrupt:
                typer.echo("interrupted", err=True)
                sys.exit(EXIT_INTERRUPTED)
            except Exception as exc:  # noqa: BLE001 (re-raised unless a known kind of failure)
                plain = _plain_failure(exc)
                if plain is None:
                    raise
                fail(*plain)
        _note_warnings([w for w in caught if not issubclass(w.category, (DeprecationWarning,
                                                                           PendingDeprecationWarning))])
        return out

    return wrapper
