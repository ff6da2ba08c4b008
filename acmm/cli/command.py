"""The wrapper of every ``acmm`` command: :func:`acmm_qpp.cli.plumbing.user_errors` (one ``error:``
line, with the hint the error was raised with) and the ``note:`` lines numba's cache leaves after
a run."""
from __future__ import annotations

import sys

from acmm_qpp.cli.plumbing import user_errors


def compiled_cache_notes() -> list[str]:
    """A line for each reason numba could not save a kernel it compiled in this run.

    Returns
    -------
    list of str
        The notes (none when nothing was compiled: the cache module was not even imported).
    """
    cache = sys.modules.get("acmm.model.compiled_cache")       # (not imported: nothing was compiled)
    return cache.write_error_notes() if cache is not None else []


def acmm_command(fn):
    """:func:`acmm_qpp.cli.plumbing.user_errors` for an ``acmm`` command, with numba's cache notes.

    Parameters
    ----------
    fn : callable
        The command function.

    Returns
    -------
    callable
        The wrapped command.
    """
    return user_errors(fn, notes=compiled_cache_notes)
