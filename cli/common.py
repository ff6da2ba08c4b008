"""Shared CLI plumbing: one clear message and a documented exit code for every user error
(:mod:`acmm.errors` lists the codes)."""
from __future__ import annotations

import functools
import sys

import typer

from acmm.errors import EXIT_INPUT, EXIT_INTERRUPTED, AcmmError

EXIT_USER_ERROR = EXIT_INPUT


def fail(message: str, code: int = EXIT_INPUT) -> None:
    """Print ``error: message`` on stderr (one line) and exit with ``code`` (no traceback)."""
    message = " ".join(str(message).split())
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def user_errors(fn):
    """Decorator for typer commands: turn :class:`AcmmError` into one line on stderr and the
    error's ``exit_code``."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except AcmmError as exc:
            fail(str(exc), exc.exit_code)
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)

    return wrapper
