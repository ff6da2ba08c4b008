"""The sweep journal: one JSON line per finished case, flushed and fsynced (group commit)."""
from __future__ import annotations

import contextlib

import json
import os
import time
from pathlib import Path

from acmm_qpp.errors import ConfigError
from acmm.sweep.journal_records import record_problem
from acmm_qpp.configio import read_regular_file
from acmm_qpp.outputs import output_error


JOURNAL_VERSION = 1


# ---------------------------------------------------------------------------------------------
# journal (append-only, one JSON line per finished task)
# ---------------------------------------------------------------------------------------------
def read_journal(path: Path, key: str, bases: set | None = None) -> list[dict]:
    """Records of a journal written for results key ``key`` (a torn last line is ignored).

    Parameters
    ----------
    path : pathlib.Path
        The journal file.
    key : str
        Results key of the sweep (:meth:`acmm.sweep.config.Sweep.results_key`); the journal's
        header must carry the same.
    bases : set of str, optional
        The sweep's base labels: a record of another base is a corrupt line.

    Returns
    -------
    list of dict
        The records after the header, in order.

    Raises
    ------
    ConfigError
        The journal belongs to a different sweep configuration, or a line (other than a torn
        last one) is not a record the sweep wrote (:func:`acmm.sweep.journal_records.record_problem`).
    """
    records = []
    try:            # a FIFO or a device there (a symlink to /dev/zero) would hang or fill memory
        lines = read_regular_file(path, "sweep journal").split(b"\n")
    except ConfigError as exc:
        raise ConfigError(f"{exc}; delete it or run without --resume") from None
    for k, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except ValueError:
            if k == len(lines) - 1:       # torn final line of a killed writer
                continue
            raise ConfigError(f"{path}: corrupt journal line {k + 1}; delete it or run without --resume") from None
        if k == 0:
            if rec.get("kind") != "header" or rec.get("version") != JOURNAL_VERSION:
                raise ConfigError(f"{path}: not a sweep journal; delete it or run without --resume")
            if rec.get("key") != key:
                raise ConfigError(f"{path}: the journal was written by a different sweep configuration "
                                  "(or by a version of acmm that computed cases differently); "
                                  "run without --resume to start over")
            continue
        why = record_problem(rec, bases)
        if why is not None:
            raise ConfigError(f"{path}: corrupt journal line {k + 1} ({why}); delete it or run without --resume")
        records.append(rec)
    return records


@contextlib.contextmanager
def _journal_errors(path):
    """An OS error while writing the journal at ``path`` as one :class:`OutputError` naming it."""
    try:
        yield
    except OSError as exc:
        raise output_error(exc, "the sweep journal", path) from None


class Journal:
    """Append-only JSON-lines file; each record is flushed and fsynced before returning.

    Parameters
    ----------
    path : pathlib.Path
        The journal file (its folder is created).
    key : str
        Results key of the sweep, written in the header line.
    fresh : bool
        Start a new journal (atomically replacing an old one); otherwise append to an existing
        one after dropping a torn last line.
    """

    def __init__(self, path: Path, key: str, fresh: bool):
        with _journal_errors(path):
            self._open(path, key, fresh)

    def _open(self, path: Path, key: str, fresh: bool) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if fresh or not self.path.exists():
            tmp = self.path.with_name(f".{self.path.name}.tmp")
            try:
                with open(tmp, "w") as f:
                    f.write(json.dumps({"kind": "header", "version": JOURNAL_VERSION, "key": key}) + "\n")
                    f.flush()
                    os.fsync(f.fileno())
                os.replace(tmp, self.path)       # only under the run lock: no sweep is using it
            except BaseException:
                try:
                    os.unlink(tmp)
                except OSError:
                    pass
                raise
        else:
            # drop a torn final line before appending
            data = self.path.read_bytes()
            if data and not data.endswith(b"\n"):
                with open(self.path, "r+b") as f:
                    f.truncate(data.rfind(b"\n") + 1)
        self._f = open(self.path, "a")

    def append(self, record: dict) -> None:
        """Append one record as a JSON line, flushed and fsynced.

        Parameters
        ----------
        record : dict
            JSON-serialisable record.

        Raises
        ------
        OutputError
            When the write fails (exit 4).
        """
        with _journal_errors(self.path):
            self._f.write(json.dumps(record) + "\n")
            self._f.flush()
            os.fsync(self._f.fileno())

    def close(self) -> None:
        """Close the file (every record is already on disk)."""
        try:
            self._f.close()
        except OSError:          # every record was already flushed and fsynced
            pass


class GroupCommitJournal(Journal):
    """A :class:`Journal` that flushes every record at once but fsyncs at most every
    ``sync_interval`` seconds (and on close): group commit (issue 16).

    A flushed line is in the operating system's cache, so a killed sweep (SIGKILL, Ctrl-C) keeps
    every record, as before; only a machine crash can lose the records of the last
    ``sync_interval``, which ``--resume`` recomputes (a torn line is ignored).  An fsync costs
    ~1–6 ms here, as much as a 10-orbit case, so one per record would dominate a sweep.

    Parameters
    ----------
    path : pathlib.Path
        The journal file.
    key : str
        Results key of the sweep.
    fresh : bool
        Start a new journal (see :class:`Journal`).
    """

    sync_interval = 0.5

    def __init__(self, path: Path, key: str, fresh: bool):
        super().__init__(path, key, fresh)
        self._last_sync = time.monotonic()

    def append(self, record: dict) -> None:
        """Append one record (see :meth:`append_many`).

        Parameters
        ----------
        record : dict
            JSON-serialisable record.
        """
        self.append_many([record])

    def append_many(self, records: list) -> None:
        """Append records (one write, one flush; an fsync when the last is older than the interval).

        Parameters
        ----------
        records : list of dict
            JSON-serialisable records.
        """
        if not records:
            return
        with _journal_errors(self.path):     # disk full: name the file (it said "No space left" only)
            self._f.write("".join(json.dumps(r) + "\n" for r in records))
            self._f.flush()
            if time.monotonic() - self._last_sync >= self.sync_interval:
                os.fsync(self._f.fileno())
                self._last_sync = time.monotonic()

    def close(self) -> None:
        """Flush, fsync and close."""
        with _journal_errors(self.path):
            if not self._f.closed:
                self._f.flush()
                os.fsync(self._f.fileno())
        super().close()

