"""Work and size limits (acmm_qpp.limits): an ACMM_LIMIT_* variable that is no positive number
is refused."""
from __future__ import annotations

import os

import pytest

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="worker processes are forked")


def test_a_work_limit_variable_that_is_no_number_is_refused(monkeypatch):
    """ACMM_LIMIT_* set to a non-number, zero, a negative or infinity was ignored without a word."""
    from acmm_qpp.errors import ConfigError
    from acmm_qpp.limits import DEFAULTS, limit

    monkeypatch.setenv("ACMM_LIMIT_SIM_SAMPLES", "5e6")
    assert limit("SIM_SAMPLES") == 5e6
    for bad in ("lots", "0", "-3", "inf", "nan"):
        monkeypatch.setenv("ACMM_LIMIT_SIM_SAMPLES", bad)
        with pytest.raises(ConfigError, match=f"ACMM_LIMIT_SIM_SAMPLES: must be a positive number \\(got '{bad}'\\)"):
            limit("SIM_SAMPLES")
    monkeypatch.setenv("ACMM_LIMIT_SIM_SAMPLES", " ")
    assert limit("SIM_SAMPLES") == DEFAULTS["SIM_SAMPLES"]
