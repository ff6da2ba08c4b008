"""A stage's files in its run folder: written in a staging folder, moved into place when it succeeds.

Policy (docs/howto/results.md, *Run folders*): a rerun **replaces the outputs the stage owns** in
``runs/<name>/`` — no history folders.  Each stage declares the glob patterns of its files
(:func:`stage`) and writes them into a staging folder ``runs/<name>/.staging-<pid>-<random>``
that :func:`_staged_outputs` gives it.  When the stage succeeds, its resolved config goes there as
``config.yaml`` (a comment names the source file and the command-line overrides), every file is
moved into the run folder with :func:`os.replace`, and the stage's files of an earlier run that
this one did not write are removed: a figure of another scenario name, of a schedule that no
longer exists or of a run with figures, cannot be mistaken for a result of this one.  When it
fails or is interrupted, the staging folder is removed and the run folder is as it was; a folder
left by a killed process is removed by the next run of that name (:func:`run_lock`).

Files of other stages are left alone (a stage does not remove the files of the stage it reads;
a journal survives for ``--resume``).  When a stage run by this one (a simulation that designs
first) finished first, that stage's files stay with its new ``config.yaml``, and the earlier run's files
of the failed stage, which that ``config.yaml`` no longer describes, are removed.
A stage whose results are written and only a figure fails (:class:`acmm_qpp.errors.FigureError`,
exit 4) finishes as above, results and ``config.yaml`` kept.

Atomic file writing (:func:`write_bytes`): a temporary file beside the target, renamed into place
on success.  An interrupted or failed write never leaves a partial file nor the directories
created for it; an OS error (read-only, not a directory, no space, name too long) becomes one
:class:`~acmm_qpp.errors.OutputError` line (exit 4).  Bytes are written with plain ``os.write``
calls (HDF5 files and figures are built in memory first: HDF5 crashes on ENOSPC, so the
libraries never write to the disk themselves).

One run at a time per results directory ``<root>/<name>/`` (issue 13), on `filelock`_:
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

import functools
import os
import re
import shutil
import stat
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path

import filelock

from acmm_qpp.errors import FigureError, OutputError
from acmm_qpp.configio import origin_of
from acmm_qpp.signals import interrupts_deferred


def _make_dirs(directory: str | Path) -> list[Path]:
    """Create ``directory`` and its missing parents; return the ones created (outermost first),
    so that a refused run can remove them again; NotADirectoryError when it is no directory."""
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
        _remove_empty_dirs(created)
        raise
    if not os.path.isdir(directory):
        raise NotADirectoryError(20, "Not a directory", str(directory))
    return created


def _remove_empty_dirs(created: list[Path]) -> None:
    """Remove the directories of :func:`_make_dirs` again, innermost first, while they are empty."""
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
    return OutputError(f"cannot write {what} {where}: {exc.strerror or exc}")


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
        created = _make_dirs(path.parent)
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
            with suppress(OSError):
                os.unlink(tmp)
        _remove_empty_dirs(created)
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


LOCK_NAME = ".lock"
#: Kind of the staging folders of stages (``.staging-<pid>-<random>``, :func:`_staged_outputs`).
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
        with suppress(OSError):
            if e.is_dir():
                shutil.rmtree(e.path)
            else:
                os.unlink(e.path)
            removed.append(e.name)
    return removed


def _release(lock: filelock.FileLock, path: Path, created: list) -> None:
    """Release ``lock``; the outermost release removes the lock file (while still held:
    filelock's next holder checks that its inode is still linked) and the folders created."""
    with interrupts_deferred():            # the lock goes whole, whatever arrives meanwhile
        if lock.lock_counter == 1:
            with suppress(OSError):
                os.unlink(path)
        lock.release()
        if not lock.is_locked:
            _remove_empty_dirs(created)


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
        created = _make_dirs(d)
    except OSError as exc:
        raise output_error(exc, "the run directory", d) from None
    path = d / LOCK_NAME
    lock = filelock.FileLock(path, timeout=0, is_singleton=True, thread_local=False)
    try:
        lock.acquire()
    except filelock.Timeout:
        _remove_empty_dirs(created)
        raise OutputError(f"{d} is in use by another run ({_holder(path)}); wait for it to finish "
                          "or give this run another name") from None
    except OSError as exc:
        _remove_empty_dirs(created)
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


CONFIG_FILE = "config.yaml"
#: Suffixes of figure files: one whose place is taken is a :class:`~acmm_qpp.errors.FigureError`
#: (the results are kept), any other file an :class:`~acmm_qpp.errors.OutputError`.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".eps", ".ps")


def file_identity(path) -> tuple | None:
    """(device, inode, modification time in ns, size) of a regular file, None when there is none
    (or it cannot be read): a file written again (atomically: a new inode) has another identity.

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    tuple or None
        The identity.
    """
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size) if stat.S_ISREG(st.st_mode) else None


def owned_files(run_dir, patterns: tuple) -> dict:
    """The files of ``run_dir`` matching ``patterns`` (a stage's), each with its :func:`file_identity`.

    Parameters
    ----------
    run_dir : path-like
        The run folder.
    patterns : tuple of str
        Glob patterns of the stage's files.

    Returns
    -------
    dict
        File name → identity.
    """
    run_dir = Path(run_dir)
    files = [p for pattern in patterns for p in run_dir.glob(pattern)] if run_dir.is_dir() else []
    return {p.name: ident for p in files if (ident := file_identity(p)) is not None}


def _remove(run_dir: Path, names) -> None:
    for name in names:
        with suppress(OSError):
            (run_dir / name).unlink()


def config_text_of(config=None, config_text: str | None = None) -> str:
    """The text of ``config.yaml``: the resolved config headed by a comment naming its source and
    overrides.

    Parameters
    ----------
    config : model, optional
        The resolved config (its ``to_yaml()`` and its recorded origin are used).
    config_text : str, optional
        The resolved config as YAML; takes precedence over ``config.to_yaml()``.

    Returns
    -------
    str
        The file's text.
    """
    source, overrides = origin_of(config) if config is not None else (None, [])
    lines = ["# resolved config of this run (every default filled in, numbers in the config's canonical units)"]
    if source:
        lines.append(f"# source: {source}")
    if overrides:
        lines.append("# command-line overrides: " + " ".join(overrides))
    # a line break inside a path or an override stays inside the comment
    head = "\n".join(line.replace("\r", "\\r").replace("\n", "\n#   ") for line in lines) + "\n"
    return head + (config_text if config_text is not None else config.to_yaml())


def _commit(staging: Path, run_dir: Path, patterns: tuple) -> None:
    """Move the files of ``staging`` into ``run_dir`` (``config.yaml`` last), remove the stage's
    files of an earlier run that this one did not write, then the staging folder.

    Raises
    ------
    OutputError
        A directory takes the place of a result or of ``config.yaml``: nothing is moved.
    FigureError
        A directory takes the place of a figure: everything else is moved.
    """
    names = sorted((p.name for p in staging.iterdir()), key=lambda n: n == CONFIG_FILE)
    blocked = [n for n in names if (run_dir / n).is_dir() and not (run_dir / n).is_symlink()]
    for name in blocked:
        if not name.endswith(FIGURE_SUFFIXES):
            raise OutputError(f"cannot write {'the run config' if name == CONFIG_FILE else 'results'} "
                              f"{run_dir / name}: a directory of that name is in the way")
    moved = [n for n in names if n not in blocked]
    with interrupts_deferred():          # the run folder changes whole
        try:
            for name in moved:
                os.replace(staging / name, run_dir / name)
        except OSError as exc:
            raise output_error(exc, "results", run_dir / name) from None
        _remove(run_dir, set(owned_files(run_dir, patterns)) - set(moved))
        shutil.rmtree(staging, ignore_errors=True)
    if blocked:
        raise FigureError(f"cannot write figure {run_dir / blocked[0]}: a directory of that name is in the way")


@contextmanager
def _staged_outputs(run_dir, patterns: tuple, config=None, config_text: str | None = None):
    """Context of one stage writing its files (see the module docstring): yields the staging folder in
    the existing ``run_dir``; ``patterns`` globs the files the stage owns there; ``config`` (its
    ``to_yaml()``, source and overrides) or ``config_text`` (YAML) goes into ``config.yaml``;
    OutputError when the staging folder cannot be made or a directory is in the way of a result."""
    run_dir = Path(run_dir)
    text = config_text_of(config, config_text) if config is not None or config_text is not None else None
    config_before = file_identity(run_dir / CONFIG_FILE)
    try:
        staging = Path(tempfile.mkdtemp(prefix=f".{STAGING}-{os.getpid()}-", dir=run_dir))
    except OSError as exc:
        raise output_error(exc, "results", run_dir) from None
    try:
        try:
            yield staging
        except FigureError as exc:
            if getattr(exc, "committed_by", None) is not None:     # a nested stage's figure
                raise
            exc.committed_by = staging           # only a figure failed: the results stay, with config.yaml
            _finish(staging, run_dir, patterns, text)
            raise
        _finish(staging, run_dir, patterns, text)
    except BaseException as exc:
        if isinstance(exc, FigureError) and getattr(exc, "committed_by", None) is None:
            exc.committed_by = staging           # a figure's place taken: the rest was moved
        if getattr(exc, "committed_by", None) is staging:
            raise
        shutil.rmtree(staging, ignore_errors=True)
        if file_identity(run_dir / CONFIG_FILE) != config_before:
            # a stage run by this one finished: its config.yaml does not describe this stage's
            # files of an earlier run
            _remove(run_dir, owned_files(run_dir, patterns))
        if isinstance(exc, OutputError) and str(staging) in str(exc):    # named where it was going
            raise OutputError(str(exc).replace(str(staging), str(run_dir))) from None
        raise


def _finish(staging: Path, run_dir: Path, patterns: tuple, text: str | None) -> None:
    if text is not None:
        write_text(staging / CONFIG_FILE, text)
    _commit(staging, run_dir, patterns)


def stage(patterns: tuple, load):
    """Decorator of a stage runner ``fn(config, ..., out)``: resolve ``config`` with ``load``
    (validation first: a refused config creates nothing), take the run lock of its ``run_dir()``
    (:func:`run_lock`), then run ``fn`` with ``out``, the folder to write its
    files in, inside :func:`_staged_outputs`.

    Parameters
    ----------
    patterns : tuple of str
        Glob patterns of the files the stage owns in its run folder.
    load : callable
        ``load(config)`` → validated config (with ``run_dir()``).

    Returns
    -------
    callable
        The decorator.
    """

    def deco(fn):
        @functools.wraps(fn)
        def wrapper(config=None, *args, **kwargs):
            cfg = load(config)
            with run_lock(cfg.run_dir()) as run_dir:
                with _staged_outputs(run_dir, patterns, cfg) as out:
                    return fn(cfg, *args, out=out, **kwargs)
        return wrapper
    return deco
