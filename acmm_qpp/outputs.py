"""What a stage owns in its run folder, and the run's ``config.yaml``.

Policy (docs/howto/results.md, *Run folders*): a rerun **replaces the outputs the stage owns** in ``runs/<name>/``
— no history folders.  Each stage declares glob patterns of the files it writes
(:data:`STAGE_OUTPUTS`); every file written through :func:`acmm_qpp.results.atomic_path` while the
stage runs is recorded, and when the stage finishes successfully

1. its resolved config is written as ``config.yaml`` (a comment names the source file and the
   command-line overrides), and
2. every file matching the stage's patterns that this run did *not* write is removed — a figure
   of a previous run (another scenario name, a schedule that no longer exists, ``--no-figures``)
   cannot be mistaken for a result of this one.

Files of other stages are left alone (``acmm simulate`` does not remove ``design.h5``; the sweep
journal survives for ``--resume``).  A stage that fails or is interrupted, while it runs or while
it writes its ``config.yaml``, rolls its run folder back: the files it wrote are removed and the
files of the earlier run that it replaced are put back (hard links to them are kept in a hidden
``.rollback-<pid>-<n>`` folder while the stage runs, :class:`_Rollback`), so the folder holds
the earlier run's results with their ``config.yaml``, as before the command, and no result of
this run sits beside a ``config.yaml`` of another.  When a stage it ran (``acmm simulate`` →
design) finished first, that stage's files stay with its new ``config.yaml``, and the earlier
run's files of the failed stage, which no longer match it, are removed instead of put back.  A
second Ctrl-C does not interrupt the rollback.
Two exceptions: a stage whose results are written and only a figure fails
(:class:`acmm_qpp.errors.FigureError`, exit 4) finishes as above, results and ``config.yaml`` kept;
and a stage in :data:`KEEPS_PARTIAL_RESULTS` keeps its files: the sweep's tables are snapshots of
its journal that say whether they are complete and hold their config, kept for ``--resume``.
"""
from __future__ import annotations

import contextlib
from pathlib import Path

from acmm_qpp.errors import FigureError
from acmm_qpp.atomic_write import WRITTEN_HOOKS
from acmm_qpp.runlock import remove_stale_temps
from acmm_qpp.signals import hold_interrupts, release_interrupts

#: stage → glob patterns (relative to the run folder) of the files the stage owns.
STAGE_OUTPUTS: dict[str, tuple[str, ...]] = {
    "tea": ("tea.h5",),
    "linearize": ("linearize.h5",),
    "design": ("design.h5", "design_*.png"),
    "simulate": ("sim.h5", "sim_*.png"),
    "sweep": ("sweep.h5", "sweep.csv", "sweep_*.png"),
    "qpp design": ("qpp_design.h5", "qpp_circle*.png", "qpp_iterations.png"),
    "qpp simulate": ("qpp_sim.h5", "qpp_sim_*.png"),
}

CONFIG_FILE = "config.yaml"

#: stages whose files survive a failure (self-describing snapshots: ``sweep.h5`` has ``complete``)
KEEPS_PARTIAL_RESULTS = frozenset({"sweep"})

#: Stack of the recorders of the stages running in this process (nested: simulate → design):
#: (files written while the stage runs, those of them written by nested stages that completed).
_RECORDERS: list[tuple[set, set]] = []


def record_written(path) -> None:
    """Called by :func:`acmm_qpp.results.atomic_path` for each file it completes.

    Parameters
    ----------
    path : path-like
        The completed file; recorded (resolved) by every running stage.
    """
    p = Path(path).resolve()
    for written, _ in list(_RECORDERS):      # a copy: a stage of another thread may end meanwhile
        written.add(p)


WRITTEN_HOOKS.append(record_written)


@contextlib.contextmanager
def stage_outputs(run_dir, stage: str, config=None, config_text: str | None = None):
    """Context of one stage writing into ``run_dir``; see the module docstring.

    Parameters
    ----------
    run_dir : path
        The run folder (``<output.root>/<name>``).
    stage : str
        A key of :data:`STAGE_OUTPUTS`.
    config : model, optional
        The resolved config (its ``to_yaml()`` and, when loaded from a file, its source and
        overrides go into ``config.yaml``).
    config_text : str, optional
        The resolved config as YAML, when ``config`` has no ``to_yaml``.
    """
    entry = written, kept = set(), set()
    run_dir = Path(run_dir)
    held = hold_interrupts()        # Ctrl-C, SIGTERM, SIGHUP: delivered inside the try below
    try:
        before = _stage_files(run_dir, stage)
        rollback = _Rollback(run_dir, [*before, run_dir / CONFIG_FILE]) if stage not in KEEPS_PARTIAL_RESULTS else None
        _RECORDERS.append(entry)
    except BaseException:
        release_interrupts(held)
        raise
    try:
        try:
            release_interrupts(held)
            yield written
        except FigureError as exc:
            if getattr(exc, "finished_stage", None) is not None:   # a nested stage's figure failed
                raise
            _finish(run_dir, stage, written, config, config_text)  # the results stay, with config.yaml
            remove_stale_temps(run_dir)     # of a writer killed mid-figure; the others have ended
            exc.finished_stage = entry
            raise
        _finish(run_dir, stage, written, config, config_text)
    except BaseException as exc:
        with _no_interrupts():
            if getattr(exc, "finished_stage", None) is entry:
                _keep_in_outer_stages(written)
            elif rollback is not None:
                now = _stage_files(run_dir, stage)          # with those a figure writer completed unrecorded
                _discard((written | {p for p, sig in now.items() if before.get(p) != sig}) - kept, run_dir)
                rollback.restore(skip=kept, stale=bool(kept))
                _forget_in_outer_stages(entry, written)
                # a figure writer killed with its worker (abort) mid-write left its temporary
                # file; every stage holds the run lock, so no live writer owns one
                remove_stale_temps(run_dir)
            if rollback is not None:
                rollback.drop()
        raise
    finally:
        del _RECORDERS[next(i for i, r in enumerate(_RECORDERS) if r is entry)]
    held = hold_interrupts()        # the finished stage's rollback folder goes whole
    try:
        if rollback is not None:
            rollback.drop()
        _keep_in_outer_stages(written)
    finally:
        release_interrupts(held)


class _Rollback:
    """Hard links to the files a stage may replace (its files and ``config.yaml`` in the run
    folder), in a hidden folder of the run folder, so that a failed stage can put them back.

    A hard link costs no copy; where the file system has none, the file is copied.  A folder left
    by a killed process is removed by the next stage that starts there.
    """

    _count = 0

    def __init__(self, run_dir: Path, paths: list) -> None:
        import os
        import shutil

        _Rollback._count += 1
        self.dir = run_dir / f".rollback-{os.getpid()}-{_Rollback._count}"
        self.saved: list[Path] = []
        if not run_dir.is_dir():
            return
        _remove_stale_rollbacks(run_dir)
        for p in paths:
            p = Path(p)
            if not p.is_file():
                continue
            try:
                self.dir.mkdir(exist_ok=True)
                try:
                    os.link(p, self.dir / p.name)
                except OSError:
                    shutil.copy2(p, self.dir / p.name)
                self.saved.append(p.resolve())
            except OSError:         # no room for the copy: that file is not restored on failure
                pass

    def restore(self, skip: set, stale: bool) -> None:
        """Put the saved files back (except ``skip``); with ``stale`` (a stage run by this one
        finished and wrote its ``config.yaml``) remove them instead: they belong to the earlier
        run of this stage, which the new config.yaml no longer describes."""
        import os

        for p in self.saved:
            if p in skip or p.name == CONFIG_FILE and stale:
                continue
            try:
                if stale:
                    p.unlink(missing_ok=True)
                else:
                    os.replace(self.dir / p.name, p)
            except OSError:
                pass

    def drop(self) -> None:
        """Remove the hidden folder (the stage finished, or its files are restored)."""
        import shutil

        shutil.rmtree(self.dir, ignore_errors=True)


def _remove_stale_rollbacks(run_dir: Path) -> None:
    """Remove ``.rollback-<pid>-*`` folders of processes that no longer run (killed by ``kill -9``)."""
    import os
    import shutil

    for d in run_dir.glob(".rollback-*-*"):
        try:
            pid = int(d.name.split("-")[1])
            if pid != os.getpid():
                os.kill(pid, 0)
        except ProcessLookupError:
            shutil.rmtree(d, ignore_errors=True)
        except (ValueError, OSError):
            pass


@contextlib.contextmanager
def _no_interrupts():
    """SIGINT ignored while a failed stage rolls its folder back (in the main thread; a second
    Ctrl-C would leave the folder half restored); SIGTERM and SIGHUP held until it is done."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    held = hold_interrupts()
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
        release_interrupts(held)


def _forget_in_outer_stages(entry: tuple, written: set) -> None:
    """A nested stage that failed has removed its files and put back those it replaced: the
    stages that ran it must not remove them again (the earlier run's restored files)."""
    for rec in list(_RECORDERS):
        if rec is not entry:
            rec[0].difference_update(written)


def _keep_in_outer_stages(written: set) -> None:
    """A stage that finished (its ``config.yaml`` written): if a stage that ran it fails, these
    files stay."""
    for _, outer_kept in list(_RECORDERS):
        outer_kept |= written


def _finish(run_dir: Path, stage: str, written: set, config, config_text) -> None:
    """A stage's end: its ``config.yaml``, then its files of earlier runs removed."""
    if config is not None or config_text is not None:
        write_config_yaml(run_dir, config, config_text)
    prune(run_dir, stage, written)


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
    import os
    import stat

    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size) if stat.S_ISREG(st.st_mode) else None


def _stage_files(run_dir: Path, stage: str) -> dict:
    """The stage's files in ``run_dir`` (its patterns), each with its :func:`file_identity`: a
    file the stage writes differs from the one there before."""
    out = {}
    if run_dir.is_dir():
        for pattern in STAGE_OUTPUTS[stage]:
            for p in run_dir.glob(pattern):
                ident = file_identity(p)
                if ident is not None:
                    out[p.resolve()] = ident
    return out


def _discard(paths: set, run_dir: Path) -> None:
    """Remove the files among ``paths`` (resolved) that lie in ``run_dir`` (a stage running in
    another thread records its files here too; they are not this stage's to remove)."""
    root = run_dir.resolve()
    for p in paths:
        try:
            if p.is_relative_to(root) and p.is_file():
                p.unlink()
        except OSError:
            pass


def write_config_yaml(run_dir, config=None, config_text: str | None = None) -> Path:
    """Write ``<run_dir>/config.yaml``: the resolved config headed by its source and overrides.

    Parameters
    ----------
    run_dir : path-like
        The run folder.
    config : model, optional
        The resolved config (its ``to_yaml()`` and its recorded origin are used).
    config_text : str, optional
        The resolved config as YAML; takes precedence over ``config.to_yaml()``.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    from acmm_qpp.overrides import header, origin_of
    from acmm_qpp.atomic_write import write_text

    text = config_text if config_text is not None else config.to_yaml()
    source, overrides = origin_of(config) if config is not None else (None, [])
    return write_text(Path(run_dir) / CONFIG_FILE, header(source, overrides) + text)


def prune(run_dir, stage: str, written: set) -> list[Path]:
    """Remove the files of ``stage`` in ``run_dir`` that are not in ``written``; returns them.

    Parameters
    ----------
    run_dir : path-like
        The run folder (nothing happens when it does not exist).
    stage : str
        A key of :data:`STAGE_OUTPUTS`.
    written : set of pathlib.Path
        Resolved paths written by this run of the stage (kept).

    Returns
    -------
    list of pathlib.Path
        The files removed (a file that cannot be removed is skipped).
    """
    removed = []
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        return removed
    for pattern in STAGE_OUTPUTS[stage]:
        for p in sorted(run_dir.glob(pattern)):
            if p.is_file() and p.resolve() not in written:
                try:
                    p.unlink()
                    removed.append(p)
                except OSError:
                    pass
    return removed


def owns_outputs(stage: str, load):
    """Decorator of a stage runner ``fn(config, ...)``: resolve ``config`` with ``load`` (path →
    validated config; a config passes through), then run ``fn`` inside :func:`stage_outputs`.

    Parameters
    ----------
    stage : str
        A key of :data:`STAGE_OUTPUTS`.
    load : callable
        ``load(config)`` → validated config (with ``run_dir()``).

    Returns
    -------
    callable
        The decorator.
    """
    import functools

    def deco(fn):
        @functools.wraps(fn)
        def wrapper(config=None, *args, **kwargs):
            cfg = load(config)
            with stage_outputs(cfg.run_dir(), stage, cfg):
                return fn(cfg, *args, **kwargs)
        return wrapper
    return deco
