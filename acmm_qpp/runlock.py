"""One run at a time per results directory ``<root>/<name>/`` (issue 13).

:func:`run_lock` takes an exclusive, non-blocking ``fcntl.flock`` on ``<run dir>/.lock`` for the
whole of a stage (``acmm tea|linearize|design|simulate|sweep``, ``qpp design|simulate``).  A
second run of the same name is refused at once with one :class:`~acmm_qpp.errors.OutputError` line
naming the holder's pid (exit 4) instead of racing it (last writer wins) or appending to its
journal.  The kernel releases the lock when the holder dies, even by ``kill -9``, so a stale
lock file never blocks a later run; the file is removed when the run ends.

While holding the lock a run also removes the temporary files (``.<file>.<random>.tmp``) that a
killed earlier run of the same name left behind, and a run that is refused or fails before
writing anything removes the directories it created, so a refusal leaves nothing on disk.

The lock is re-entrant within a process (``simulate`` runs ``design`` under its lock).
"""
from __future__ import annotations

import fcntl
import functools
import os
import re
from contextlib import contextmanager
from pathlib import Path

from acmm_qpp.errors import OutputError
from acmm_qpp.atomic_write import make_dirs, output_error, remove_empty_dirs
from acmm_qpp.signals import hold_interrupts, release_interrupts

LOCK_NAME = ".lock"
_TEMP = re.compile(r"^\..+\.tmp$")

#: absolute run dir → [fd, depth] for the locks this process holds
_held: dict[str, list] = {}


def _holder(fd: int) -> str:
    try:
        text = os.pread(fd, 64, 0).decode("ascii", "replace").strip()
    except OSError:
        text = ""
    return f"pid {text}" if text.isdigit() else "a process that has not yet written its pid"


def remove_stale_temps(directory: Path) -> list[str]:
    """Remove the temporary files of killed writers (``.<name>.*.tmp``) in ``directory``.

    Only call this while holding the directory's run lock: no live writer then owns them.

    Parameters
    ----------
    directory : Path
        The run directory.

    Returns
    -------
    list of str
        Names of the files removed.
    """
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for e in entries:
        if _TEMP.match(e.name) and e.is_file(follow_symlinks=False):
            try:
                os.unlink(e.path)
                removed.append(e.name)
            except OSError:
                pass
    return removed


def _take(lock: Path, d: Path) -> int:
    """Create and lock the file ``lock`` of run folder ``d`` (its pid written); returns its
    descriptor.  Another holder: :class:`OutputError`; an I/O failure: ``OSError`` (the file
    dropped when it was ours)."""
    fd = -1
    try:
        while True:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                who = _holder(fd)
                os.close(fd)
                fd = -1
                raise OutputError(f"{d} is in use by another run ({who}); wait for it to finish "
                                  "or give this run another name") from None
            try:                          # the holder we waited for may have unlinked the file
                same = os.stat(lock).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
            fd = -1
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    except OSError:
        if fd >= 0:                       # we hold the lock (writing the pid failed): drop the file
            try:
                os.unlink(lock)
            except OSError:
                pass
            os.close(fd)
        raise
    return fd


@contextmanager
def run_lock(run_dir: str | Path):
    """Hold the exclusive run lock of ``run_dir`` (created if needed) for the ``with`` block.

    Parameters
    ----------
    run_dir : path-like
        The run directory ``<root>/<name>/``.

    Yields
    ------
    Path
        ``run_dir``.

    Raises
    ------
    OutputError
        Another live process holds the lock (message names its pid), or the directory cannot
        be created / the lock file cannot be written (exit 4).
    output_error
        (the :class:`~acmm_qpp.errors.OutputError` built by
        :func:`acmm_qpp.results.output_error` from an OS error)
    """
    d = Path(run_dir)
    key = os.path.abspath(d)
    if key in _held and _held[key][2] == os.getpid():
        _held[key][1] += 1
        try:
            yield d
        finally:
            _held[key][1] -= 1
        return
    try:
        created = make_dirs(d)
    except OSError as exc:
        raise output_error(exc, "the run directory", d) from None
    lock = d / LOCK_NAME
    held = hold_interrupts()              # an interrupt is handled once the lock is released below
    try:
        fd = _take(lock, d)
    except OSError as exc:
        remove_empty_dirs(created)
        release_interrupts(held)
        raise output_error(exc, "the run lock", lock) from None
    except BaseException:
        release_interrupts(held)
        raise
    _held[key] = [fd, 1, os.getpid()]
    try:
        release_interrupts(held)
        remove_stale_temps(d)
        yield d
    finally:
        held = hold_interrupts()          # the lock goes whole, whatever arrives meanwhile
        try:
            del _held[key]
            try:
                os.unlink(lock)
            except OSError:
                pass
            os.close(fd)
            remove_empty_dirs(created)
        finally:
            release_interrupts(held)


def locked_stage(as_config):
    """Decorator for a stage runner ``fn(config, ...)``: resolve the config with ``as_config``
    (validation first: a refused config creates nothing), then run ``fn`` on it under
    :func:`run_lock` of its ``run_dir()``.

    Parameters
    ----------
    as_config : callable
        Resolves the stage's ``config`` argument (path, mapping or model) to a validated config.

    Returns
    -------
    callable
        The decorator.
    """

    def deco(fn):
        @functools.wraps(fn)
        def wrapper(config, *args, **kwargs):
            cfg = as_config(config)
            with run_lock(cfg.run_dir()):
                return fn(cfg, *args, **kwargs)
        return wrapper
    return deco
