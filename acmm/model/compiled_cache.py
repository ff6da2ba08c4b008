"""numba's on-disk cache of the compiled kernels (the simulator, the TEA continuation), where the
machine has one.

numba caches a ``cache=True`` function in ``__pycache__`` beside its source, else in the user's
cache folder (``~/.cache``), else in ``NUMBA_CACHE_DIR``; with none writable — a read-only
install for a user whose home is ``/nonexistent`` — it refuses to define the function at all
(``RuntimeError: cannot cache function …: no locator available``, a traceback at import: a
review).  :func:`njit_cached` then compiles the kernel without the cache, in every run, and
:func:`uncached_note` says so.  A cache that cannot be written (a full disk under
``NUMBA_CACHE_DIR``) likewise no longer fails the run ("I/O error: No space left on device",
naming nothing): the kernel compiled in this run is used and not kept.
"""
from __future__ import annotations

from numba import njit

#: qualified names of the kernels compiled without a cache (no writable cache folder)
UNCACHED: list[str] = []
#: why a compiled kernel could not be written into the cache (the first of each reason)
CACHE_WRITE_ERRORS: list[str] = []


def njit_cached(**options):
    """``numba.njit(cache=True, **options)``, or without the cache where numba has no writable
    place for one.

    Parameters
    ----------
    **options : dict
        Further ``njit`` options (``fastmath``…).

    Returns
    -------
    callable
        The decorator.
    """

    def decorate(fn):
        try:
            compiled = njit(cache=True, **options)(fn)
        except RuntimeError as exc:
            if "no locator available" not in str(exc):
                raise
            UNCACHED.append(fn.__qualname__)
            return njit(**options)(fn)
        _tolerate_write_errors(compiled)
        return compiled

    return decorate


def _tolerate_write_errors(dispatcher) -> None:
    """Let a kernel whose machine code cannot be saved (disk full, folder gone) run uncached."""
    cache = getattr(dispatcher, "_cache", None)
    save = getattr(cache, "save_overload", None)
    if save is None:                # numba's internals moved: its own behaviour
        return

    def save_overload(sig, data):
        try:
            save(sig, data)
        except OSError as exc:
            where = getattr(cache, "_cache_path", "")
            reason = f"{exc.strerror or exc}" + (f" in {where}" if where else "")
            if reason not in CACHE_WRITE_ERRORS:
                CACHE_WRITE_ERRORS.append(reason)

    cache.save_overload = save_overload


def uncached_note() -> str | None:
    """The line saying that the kernels are compiled in every run, when numba has no cache folder.

    Returns
    -------
    str or None
        The note; None when the cache is usable.
    """
    if not UNCACHED:
        return None
    return ("numba has no writable folder for its cache of the compiled kernels (neither __pycache__ beside "
            "the package nor the user's cache folder; set NUMBA_CACHE_DIR to a writable folder): they are "
            "compiled in every run (~20–60 s, longer on a busy machine)")


def write_error_notes() -> list[str]:
    """One line for each reason a compiled kernel could not be saved in the cache in this process.

    Returns
    -------
    list of str
        The notes (empty when every save worked).
    """
    return [f"numba could not save the compiled kernels in its cache ({r}): they are compiled again in the next "
            "run" for r in CACHE_WRITE_ERRORS]
