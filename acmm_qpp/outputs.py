"""A stage's files in its run folder: written in a staging folder, moved into place when it succeeds.

Policy (docs/howto/results.md, *Run folders*): a rerun **replaces the outputs the stage owns** in
``runs/<name>/`` — no history folders.  Each stage declares the glob patterns of its files
(:func:`stage`) and writes them into a staging folder ``runs/<name>/.staging-<pid>-<random>``
that :func:`staged_outputs` gives it.  When the stage succeeds, its resolved config goes there as
``config.yaml`` (a comment names the source file and the command-line overrides), every file is
moved into the run folder with :func:`os.replace`, and the stage's files of an earlier run that
this one did not write are removed: a figure of another scenario name, of a schedule that no
longer exists or of a run with figures, cannot be mistaken for a result of this one.  When it
fails or is interrupted, the staging folder is removed and the run folder is as it was; a folder
left by a killed process is removed by the next run of that name (:func:`acmm_qpp.runlock.run_lock`).

Files of other stages are left alone (a stage does not remove the files of the stage it reads;
a journal survives for ``--resume``).  When a stage run by this one (a simulation that designs
first) finished first, that stage's files stay with its new ``config.yaml``, and the earlier run's files
of the failed stage, which that ``config.yaml`` no longer describes, are removed.
A stage whose results are written and only a figure fails (:class:`acmm_qpp.errors.FigureError`,
exit 4) finishes as above, results and ``config.yaml`` kept.
"""
from __future__ import annotations

import functools
import os
import shutil
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

from acmm_qpp.atomic_write import output_error, write_text
from acmm_qpp.errors import FigureError, OutputError
from acmm_qpp.configio import origin_of
from acmm_qpp.runlock import STAGING, run_lock
from acmm_qpp.signals import interrupts_deferred

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
    out, run_dir = {}, Path(run_dir)
    if run_dir.is_dir():
        for pattern in patterns:
            for p in run_dir.glob(pattern):
                ident = file_identity(p)
                if ident is not None:
                    out[p.name] = ident
    return out


def _remove(run_dir: Path, names) -> None:
    for name in names:
        try:
            (run_dir / name).unlink()
        except OSError:
            pass


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
def staged_outputs(run_dir, patterns: tuple, config=None, config_text: str | None = None):
    """Context of one stage writing its files; see the module docstring.

    Parameters
    ----------
    run_dir : path
        The run folder (``<output.root>/<name>``), which exists (the run lock made it).
    patterns : tuple of str
        Glob patterns (relative to the run folder) of the files the stage owns.
    config : model, optional
        The resolved config (its ``to_yaml()`` and, when loaded from a file, its source and
        overrides go into ``config.yaml``).
    config_text : str, optional
        The resolved config as YAML, when ``config`` has no ``to_yaml``.

    Yields
    ------
    Path
        The folder to write the stage's files in.

    Raises
    ------
    OutputError
        The staging folder cannot be made, or a directory is in the way of a result.
    """
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
    (:func:`acmm_qpp.runlock.run_lock`), then run ``fn`` with ``out``, the folder to write its
    files in, inside :func:`staged_outputs`.

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
                with staged_outputs(run_dir, patterns, cfg) as out:
                    return fn(cfg, *args, out=out, **kwargs)
        return wrapper
    return deco
