"""The sweep journal (acmm.sweep.journal): a journal that is no regular file is one line, not a
hang; a full disk under it names it; what --resume accepts of a journal line (_record_problem)."""
from __future__ import annotations

import json
import os

import pytest

from acmm_qpp.errors import ConfigError
from acmm.sweep.run import run_sweep
from acmm.sweep.config import load_sweep

from tests.acmm.conftest import _sweep_yaml


@pytest.mark.parametrize("kind", ["fifo", "dev_zero"])
def test_a_journal_that_is_not_a_regular_file_is_one_line_not_a_hang(tmp_path, kind):
    """--resume reads the journal: a FIFO there hung for ever, a symlink to /dev/zero filled the
    memory; both are one ConfigError now, the sweep's files as they were."""
    from acmm.sweep.journal import read_journal

    journal = tmp_path / "sweep.journal"
    if kind == "fifo":
        os.mkfifo(journal)
    else:
        journal.symlink_to("/dev/zero")
    with pytest.raises(ConfigError, match="not a regular file"):
        read_journal(journal, "key")


def test_a_full_disk_under_the_journal_names_the_journal(tmp_path):
    """A full disk gave "I/O error: No space left on device" without a file (a review, on a
    20 kB tmpfs)."""
    import errno

    from acmm.sweep.journal import Journal
    from acmm_qpp.errors import OutputError

    class _Full:
        closed = False

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        flush = close = lambda self: None

    j = Journal(tmp_path / "sweep.journal", "key", fresh=True)
    j._f.close()
    j._f = _Full()
    with pytest.raises(OutputError, match=r"cannot write the sweep journal .*sweep\.journal: No space left"):
        j.append([{"kind": "case"}])


def test_journal_record_checks(tmp_path):
    # what --resume accepts: the records a sweep writes (NaN and ±inf included); a line that is
    # JSON but not such a record is named, field by field, instead of failing in the table builder
    from acmm.sweep.journal import _record_problem

    sw = load_sweep(_sweep_yaml(tmp_path, "rec", n_runs=2, orbits=0.2))
    run_sweep(sw, workers=1)
    lines = (sw.run_dir() / "sweep.journal").read_text().splitlines()[1:]
    recs = [json.loads(x) for x in lines]
    assert recs and all(_record_problem(r, {"ac"}) is None for r in recs)
    case = next(r for r in recs if r["kind"] == "case")
    assert _record_problem({**case, "time_to_divergence": float("inf")}) is None
    for bad, words in (({**case, "verdict": 123}, "malformed 'verdict'"), ({**case, "verdict": "fine"}, "unknown verdict"),
                       ({k: v for k, v in case.items() if k != "bias"}, "without 'bias'"),
                       ({**case, "inertia": [[1, 2, 3]] * 2}, "malformed 'inertia'"),
                       ({**case, "index": True}, "malformed 'index'"), ({**case, "kind": "x"}, "unknown record kind"),
                       ([1, 2], "not a record")):
        assert words in _record_problem(bad, {"ac"})
    assert "base 'ac'" in _record_problem(case, {"mb3"})
    # a record of a case the sweep does not have (a review: --resume gave 161 rows of 160)
    with open(sw.run_dir() / "sweep.journal", "a") as f:
        f.write(json.dumps({**case, "index": 99999}) + "\n")
    with pytest.raises(ConfigError, match=r"case 99999 of ac, which this sweep does not have"):
        run_sweep(sw, workers=1, resume=True)
