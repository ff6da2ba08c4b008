"""The ledger of printed numbers (acmm.report.ledger): the rule of a printed number's precision."""
from __future__ import annotations

import pytest

from acmm.report import ledger as ledger_mod

pytestmark = pytest.mark.slow      # a whole `acmm report --fast` per session: `make test-slow`


def test_matches_printed_precision_rule():
    assert ledger_mod.matches_printed("-44.7", -44.7499)
    assert not ledger_mod.matches_printed("-44.7", -44.7501)
    assert ledger_mod.matches_printed("1005.9", 1005.855)
    assert not ledger_mod.matches_printed("0.02727", 0.0272922)
    assert ledger_mod.check_printed("s", "q", "0.094", 0.09189, bound="upper").status == ledger_mod.STATUS_BOUND
    assert ledger_mod.check_printed("s", "q", "0.094", 0.1, bound="upper").status == ledger_mod.STATUS_UNEXPLAINED
