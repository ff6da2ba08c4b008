"""What --resume accepts of a journal line (acmm.sweep.journal_records.record_problem)."""
from __future__ import annotations

import json

import pytest

from acmm_qpp.errors import ConfigError
from acmm.sweep.run import run_sweep
from acmm.sweep.config import load_sweep

from tests.acmm.conftest import _sweep_yaml


def test_journal_record_checks(tmp_path):
    # what --resume accepts: the records a sweep writes (NaN and ±inf included); a line that is
    # JSON but not such a record is named, field by field, instead of failing in the table builder
    import json

    from acmm.sweep.journal_records import record_problem

    sw = load_sweep(_sweep_yaml(tmp_path, "rec", n_runs=2, orbits=0.2))
    run_sweep(sw, workers=1)
    lines = (sw.run_dir() / "sweep.journal").read_text().splitlines()[1:]
    recs = [json.loads(x) for x in lines]
    assert recs and all(record_problem(r, {"ac"}) is None for r in recs)
    case = next(r for r in recs if r["kind"] == "case")
    assert record_problem({**case, "time_to_divergence": float("inf")}) is None
    for bad, words in (({**case, "verdict": 123}, "malformed 'verdict'"), ({**case, "verdict": "fine"}, "unknown verdict"),
                       ({k: v for k, v in case.items() if k != "bias"}, "without 'bias'"),
                       ({**case, "inertia": [[1, 2, 3]] * 2}, "malformed 'inertia'"),
                       ({**case, "index": True}, "malformed 'index'"), ({**case, "kind": "x"}, "unknown record kind"),
                       ([1, 2], "not a record")):
        assert words in record_problem(bad, {"ac"})
    assert "base 'ac'" in record_problem(case, {"mb3"})
    # a record of a case the sweep does not have (a review: --resume gave 161 rows of 160)
    with open(sw.run_dir() / "sweep.journal", "a") as f:
        f.write(json.dumps({**case, "index": 99999}) + "\n")
    with pytest.raises(ConfigError, match=r"case 99999 of ac, which this sweep does not have"):
        run_sweep(sw, workers=1, resume=True)
