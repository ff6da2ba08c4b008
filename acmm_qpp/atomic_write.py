"""Atomic file writing: a temporary file beside the target, renamed into place on success.

An interrupted or failed write never leaves a partial file nor the directories created for it;
an OS error (read-only, not a directory, no space, name too long) becomes one
:class:`~acmm_qpp.errors.OutputError` line (exit 4).  Bytes are written with plain ``os.write``
calls (HDF5 files and figures are built in memory first: HDF5 crashes on ENOSPC, so the
libraries never write to the disk themselves).
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from acmm_qpp.errors import OutputError

def make_dirs(directory: str | Path) -> list[Path]:
    """Create ``directory`` and its missing parents; return the ones created (outermost first),
    so that a refused run can remove them again (:func:`remove_empty_dirs`).

    Parameters
    ----------
    directory : path-like
        The directory to create.

    Returns
    -------
    list of Path
        The directories created, outermost first.

    Raises
    ------
    NotADirectoryError
        ``directory`` exists but is not a directory.
    """
    d = Path(directory)
    missing = []
    while not os.path.lexists(d) and d != d.parent:
        missing.append(d)
        d = d.parent
    created = []
    try:
        for q in reversed(missing):
            try:
                os.mkdir(q)
            except FileExistsError:
                if not os.path.isdir(q):
                    raise
                continue
            created.append(q)
    except BaseException:
        remove_empty_dirs(created)
        raise
    if not os.path.isdir(directory):
        raise NotADirectoryError(20, "Not a directory", str(directory))
    return created


def remove_empty_dirs(created: list[Path]) -> None:
    """Remove the directories of :func:`make_dirs` again, innermost first, while they are empty.

    Parameters
    ----------
    created : list of Path
        Directories as returned by :func:`make_dirs`.
    """
    for q in reversed(created):
        try:
            os.rmdir(q)
        except OSError:
            break


def output_error(exc: OSError, what: str, where: str | Path):
    """A one-line :class:`~acmm_qpp.errors.OutputError` (exit 4) for an OS error while writing.

    Parameters
    ----------
    exc : OSError
        The error (an OutputError is returned as it is).
    what : str
        What was being written ("results", "figure", ...).
    where : path-like
        Where it was being written.

    Returns
    -------
    OutputError
        The error to raise.
    """
    if isinstance(exc, OutputError):
        return exc
    why = exc.strerror or str(exc)
    return OutputError(f"cannot write {what} {where}: {why}")


def write_bytes(path: str | Path, data: bytes, what: str = "results") -> Path:
    """Write ``data`` to a temporary file beside ``path``, then rename it onto ``path``.

    The bytes go out in plain ``os.write`` calls and an fsync: a full disk is then an ordinary
    OSError, never a crash inside a C library.  The file gets the usual permissions (0666 & ~umask,
    not mkstemp's 0600).  On any error or interrupt the temporary file is removed, directories
    created for it are removed again and ``path`` is left as it was; an OS error (read-only, not a
    directory, no space, name too long, a directory where the file should go) becomes one
    :class:`~acmm_qpp.errors.OutputError` line.

    Parameters
    ----------
    path : path-like
        The target file.
    data : bytes-like
        The content.
    what : str
        What is written, for error messages.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    OutputError
        A directory of that name is in the way, or an OS error occurred.
    """
    path, created, tmp = Path(path), [], None
    try:
        created = make_dirs(path.parent)
        if os.path.isdir(path):
            raise OutputError(f"cannot write {what} {path}: a directory of that name is in the way")
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
            os.fsync(fd)
        finally:
            os.close(fd)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        remove_empty_dirs(created)
        if isinstance(exc, OSError):
            raise output_error(exc, what, path) from None
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file atomically (see :func:`write_bytes`).

    Parameters
    ----------
    path : path-like
        The target file.
    text : str
        The content, written as UTF-8.

    Returns
    -------
    Path
        ``path``.
    """
    return write_bytes(path, text.encode("utf-8"), "text")
