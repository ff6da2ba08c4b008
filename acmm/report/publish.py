"""Put a finished report in place all at once: its figures and pages, staged in a folder of
``--out``, replace the previous report's files together or not at all (a half-published report
would leave new figures beside an old page, and the next determinism check would compare against
a manifest of a report never written).  Every file is written in the staging folder first, every
target is checked, and only renames within one file system remain; if one fails, those done are
undone.
"""
from __future__ import annotations

import os
from pathlib import Path

from acmm_qpp.errors import OutputError


def publish(pairs: list[tuple[Path, Path]], backup: Path) -> None:
    """Move each staged file onto its target, all of them or none.

    Parameters
    ----------
    pairs : list of (Path, Path)
        ``(staged file, target)``; the staged files and the targets lie on one file system.
    backup : Path
        A folder (created here, on the same file system) that holds the replaced files until
        every move has succeeded; the caller removes it.

    Raises
    ------
    OutputError
        A target cannot be replaced (a directory in its place, a read-only folder…); nothing was
        changed.
    """
    for _, target in pairs:
        if target.is_dir() and not target.is_symlink():
            raise OutputError(f"cannot write {target}: a directory of that name is in the way; nothing was "
                              "written")
    try:
        backup.mkdir()
    except OSError as exc:
        raise OutputError(f"cannot write the report in {backup.parent}: {exc.strerror or exc}; nothing was "
                          "written") from None
    done: list[tuple[Path, Path | None]] = []       # (target, its previous file in the backup)
    for i, (staged, target) in enumerate(pairs):
        old = backup / str(i) if os.path.lexists(target) else None
        try:
            if old is not None:
                os.replace(target, old)
                done.append((target, old))      # restored over the new file, placed or not
            os.replace(staged, target)
        except OSError as exc:
            if _undo(done):
                raise OutputError(f"cannot write {target}: {exc.strerror or exc}; the report folder was left "
                                  "as it was") from None
            kept = backup.parent.parent / f".previous-report-{os.getpid()}"
            try:                        # out of the staging folder, which the caller removes
                os.replace(backup, kept)
            except OSError:
                kept = backup
            raise OutputError(f"cannot write {target}: {exc.strerror or exc}; and not every file of the previous "
                              f"report could be put back: they are in {kept}") from None
        if old is None:
            done.append((target, None))         # a new file where there was none: removed


def _undo(done: list[tuple[Path, Path | None]]) -> bool:
    """Put the replaced files back (newest first); a new file whose target had none is removed.
    Returns False when a previous file could not be put back (it stays in the backup folder)."""
    whole = True
    for target, old in reversed(done):
        try:
            if old is not None:
                os.replace(old, target)
            else:
                os.unlink(target)
        except OSError:
            whole = whole and old is None
    return whole
