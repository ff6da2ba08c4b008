"""The sweep journal (acmm.sweep.journal): a journal that is no regular file is one line, not a
hang; a full disk under it names it."""
from __future__ import annotations

import os

import pytest

from acmm_qpp.errors import ConfigError


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

    from acmm.sweep.journal import GroupCommitJournal
    from acmm_qpp.errors import OutputError

    class _Full:
        closed = False

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        flush = close = lambda self: None

    j = GroupCommitJournal(tmp_path / "sweep.journal", "key", fresh=True)
    j._f.close()
    j._f = _Full()
    with pytest.raises(OutputError, match=r"cannot write the sweep journal .*sweep\.journal: No space left"):
        j.append({"kind": "case"})
