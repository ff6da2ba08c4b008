"""The sweep journal: one JSON line per finished case, flushed at once and fsynced at most every
0.5 s (group commit), and what a record must hold when a sweep is resumed from it.

A journal line that is valid JSON but not a record the sweep wrote (edited, or from another
version) would otherwise fail later, deep in the table builder, with a traceback.
:func:`_record_problem` names the first missing or mistyped field instead.
"""
from __future__ import annotations

import contextlib
import functools
import json
import os
import time
from pathlib import Path

import numpy as np

from acmm_qpp.errors import ConfigError
from acmm_qpp.configio import read_regular_file
from acmm_qpp.outputs import output_error, write_bytes
from acmm.sweep.case import empty_row
from acmm.sweep.cases import VERDICTS


JOURNAL_VERSION = 1

#: the fields a case record adds to its metrics row (:func:`acmm.sweep.case.empty_row`)
CASE_KEYS = {"base": ("str", ()), "index": ("int", ()), "n_draws": ("int", ())}


@functools.cache
def _case_fields() -> dict:
    """Case record fields: name → (kind, shape), kind "num" (a number, NaN or ±inf), "int" or
    "str": :data:`CASE_KEYS` and the metrics row's fields, read off its empty row."""
    return {**CASE_KEYS, **{k: ("str" if isinstance(v, str) else "int" if isinstance(v, int) else "num", np.shape(v))
                            for k, v in empty_row().items()}}


#: margin-search record fields, as :func:`_case_fields` ("bool": true/false; shape None: a list)
MARGIN_FIELDS = {
    "base": ("str", ()), "direction": ("str", ()), "limit": ("num", ()), "first_failure": ("num", ()),
    "failure_verdict": ("str", ()), "failure_reason": ("str", ()), "reached_end": ("bool", ()),
    "search_end": ("num", ()), "evaluated_s": ("num", None), "evaluated_verdict": ("str", None),
}


def _shaped(kind: str, v, shape) -> bool:
    if shape is None:
        return isinstance(v, list) and all(_shaped(kind, x, ()) for x in v)
    if shape:
        return isinstance(v, list) and len(v) == shape[0] and all(_shaped(kind, x, shape[1:]) for x in v)
    if kind == "num":            # any float the sweep writes: finite, NaN or ±inf
        return isinstance(v, (int, float)) and not isinstance(v, bool)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool) and v >= 0
    if kind == "bool":
        return isinstance(v, bool)
    return isinstance(v, str)


def _record_problem(rec: object, bases: set | None = None) -> str | None:
    """The first problem of a parsed journal record ``rec`` (a missing or mistyped field, an unknown
    verdict, kind or base not in ``bases``), or None when it is one the sweep wrote."""
    if not isinstance(rec, dict):
        return "not a record (a JSON object)"
    kind = rec.get("kind")
    fields = _case_fields() if kind == "case" else MARGIN_FIELDS if kind == "margin" else None
    if fields is None:
        return f"unknown record kind {kind!r}"
    for name, (k, shape) in fields.items():
        if name not in rec:
            return f"{kind} record without {name!r}"
        if not _shaped(k, rec[name], shape):
            return f"{kind} record with a malformed {name!r}"
    if kind == "case":
        if rec["verdict"] not in VERDICTS:
            return f"unknown verdict {rec['verdict']!r}"
        values = rec.get("values")
        if not isinstance(values, dict) or not all(_shaped("num", v, ()) for v in values.values()):
            return "case record with a malformed 'values'"
    elif rec["direction"] not in ("up", "down"):
        return f"unknown margin direction {rec['direction']!r}"
    if bases is not None and rec["base"] not in bases:
        return f"record of base {rec['base']!r}, which the sweep does not have"
    return None


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
        last one) is not a record the sweep wrote (:func:`_record_problem`).
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
        why = _record_problem(rec, bases)
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
    """Append-only JSON-lines file with group commit (issue 16): every record is flushed at once,
    fsynced at most every ``sync_interval`` seconds and on close.

    A flushed line is in the operating system's cache, so a killed sweep (SIGKILL, Ctrl-C) keeps
    every record; only a machine crash can lose the records of the last ``sync_interval``, which
    ``--resume`` recomputes (a torn line is ignored).  An fsync costs ~1–6 ms here, as much as a
    10-orbit case, so one per record would dominate a sweep.

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

    sync_interval = 0.5

    def __init__(self, path: Path, key: str, fresh: bool):
        self.path = Path(path)
        with _journal_errors(path):
            self.path.parent.mkdir(parents=True, exist_ok=True)
            if fresh or not self.path.exists():      # replaced only under the run lock: no sweep is using it
                header = json.dumps({"kind": "header", "version": JOURNAL_VERSION, "key": key}) + "\n"
                write_bytes(self.path, header.encode(), "the sweep journal")
            else:
                # drop a torn final line before appending
                data = self.path.read_bytes()
                if data and not data.endswith(b"\n"):
                    with open(self.path, "r+b") as f:
                        f.truncate(data.rfind(b"\n") + 1)
            self._f = open(self.path, "a")
        self._last_sync = time.monotonic()

    def append(self, records: list) -> None:
        """Append records (one write, one flush; an fsync when the last is older than the interval).

        Parameters
        ----------
        records : list of dict
            JSON-serialisable records.

        Raises
        ------
        OutputError
            When the write fails (exit 4).
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
        with contextlib.suppress(OSError):          # every record was already flushed and fsynced
            self._f.close()
