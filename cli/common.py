"""Shared CLI plumbing: one clear message and exit code 2 for every user error."""
from __future__ import annotations

import functools
import sys

import typer

from acmm.errors import AcmmError

EXIT_USER_ERROR = 2


def fail(message: str) -> None:
    """Print ``error: message`` on stderr and exit with code 2 (no traceback)."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(EXIT_USER_ERROR)


def user_errors(fn):
    """Decorator for typer commands: turn :class:`AcmmError` (and a missing optional
    dependency) into one line on stderr and exit code 2."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except AcmmError as exc:
            fail(str(exc))
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            sys.exit(130)

    return wrapper
