"""One run at a time per results directory ``<root>/<name>/`` (issue 13), on `filelock`_.

:func:`run_lock` holds an exclusive, non-blocking lock on ``<run dir>/.lock``
(:class:`filelock.FileLock`: ``flock`` on POSIX) for the whole of a stage or report.  A second run
of the same name is refused at once with one :class:`~acmm_qpp.errors.OutputError` line naming the
holder's pid (exit 4) instead of racing it.  The kernel releases the lock when the holder dies,
even by ``kill -9``, so a stale lock file never blocks a later run; the file is removed when the
run ends.  Holding the lock, a run removes what a killed earlier run of the same folder left
behind (:func:`remove_leftovers`: staging folders, the caller's kinds among them, temporary
files), and a run refused or failed before writing anything removes the directories it created.
The lock is re-entrant within a process (``simulate`` runs ``design`` under its lock).

.. _filelock: https://py-filelock.readthedocs.io
"""
from __future__ import annotations

import os
import re
import shutil
from contextlib import contextmanager
from pathlib import Path

import filelock

from acmm_qpp.atomic_write import make_dirs, output_error, remove_empty_dirs
from acmm_qpp.errors import OutputError
from acmm_qpp.signals import interrupts_deferred

LOCK_NAME = ".lock"
#: Kind of the staging folders of stages (``.staging-<pid>-<random>``, :mod:`acmm_qpp.outputs`).
STAGING = "staging"


def _holder(lock: Path) -> str:
    try:
        text = lock.read_text(encoding="ascii", errors="replace").strip()
    except OSError:
        text = ""
    return f"pid {text}" if text.isdigit() else "a process that has not yet written its pid"


def remove_leftovers(directory: Path, staging: tuple = ()) -> list[str]:
    """Remove what killed runs left in ``directory``: temporary files of an atomic write
    (``.<file>.<random>.tmp``) and staging folders ``.<kind>-<pid>-<random>`` of the stages'
    kind (:data:`STAGING`) and of the caller's kinds.

    Only call this while holding the directory's run lock: no live run then owns them.

    Parameters
    ----------
    directory : Path
        The run directory.
    staging : tuple of str, optional
        The caller's own kinds of staging folder.

    Returns
    -------
    list of str
        Names of the files and folders removed.
    """
    kinds = "|".join(re.escape(k) for k in (STAGING, *staging))
    removed, pattern = [], re.compile(rf"^\.(.+\.tmp|(?:{kinds})-\d+-.+)$")
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for e in entries:
        if not pattern.match(e.name) or e.is_symlink():
            continue
        try:
            if e.is_dir():
                shutil.rmtree(e.path)
            else:
                os.unlink(e.path)
            removed.append(e.name)
        except OSError:
            pass
    return removed


def _release(lock: filelock.FileLock, path: Path, created: list) -> None:
    """Release ``lock``; the outermost release removes the lock file (while still held:
    filelock's next holder checks that its inode is still linked) and the folders created."""
    with interrupts_deferred():            # the lock goes whole, whatever arrives meanwhile
        if lock.lock_counter == 1:
            try:
                os.unlink(path)
            except OSError:
                pass
        lock.release()
        if not lock.is_locked:
            remove_empty_dirs(created)


@contextmanager
def run_lock(run_dir: str | Path, staging: tuple = ()):
    """Hold the exclusive run lock of ``run_dir`` (created if needed) for the ``with`` block.

    Parameters
    ----------
    run_dir : path-like
        The run directory ``<root>/<name>/``.
    staging : tuple of str, optional
        The kinds of staging folder (``.<kind>-<pid>-<random>``) the caller makes besides the
        stages', removed as a killed run's leftovers (:func:`remove_leftovers`).

    Yields
    ------
    Path
        ``run_dir``.

    Raises
    ------
    OutputError
        Another live process holds the lock (message names its pid), or the directory cannot
        be created / the lock file cannot be written (exit 4).
    """
    d = Path(run_dir)
    try:
        created = make_dirs(d)
    except OSError as exc:
        raise output_error(exc, "the run directory", d) from None
    path = d / LOCK_NAME
    lock = filelock.FileLock(path, timeout=0, is_singleton=True, thread_local=False)
    try:
        lock.acquire()
    except filelock.Timeout:
        remove_empty_dirs(created)
        raise OutputError(f"{d} is in use by another run ({_holder(path)}); wait for it to finish "
                          "or give this run another name") from None
    except OSError as exc:
        remove_empty_dirs(created)
        raise output_error(exc, "the run lock", path) from None
    try:
        if lock.lock_counter == 1:      # the holder's pid, for the message of a refused run
            path.write_text(f"{os.getpid()}\n", encoding="ascii")
            remove_leftovers(d, staging)
    except OSError as exc:
        _release(lock, path, created)
        raise output_error(exc, "the run lock", path) from None
    try:
        yield d
    finally:
        _release(lock, path, created)
