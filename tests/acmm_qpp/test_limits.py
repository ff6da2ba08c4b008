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

    monkeypatch.setenv("ACMM_LIMIT_CONFIG_BYTES", "5e6")
    assert limit("CONFIG_BYTES") == 5e6
    for bad in ("lots", "0", "-3", "inf", "nan"):
        monkeypatch.setenv("ACMM_LIMIT_CONFIG_BYTES", bad)
        with pytest.raises(ConfigError, match=f"ACMM_LIMIT_CONFIG_BYTES: must be a positive number \\(got '{bad}'\\)"):
            limit("CONFIG_BYTES")
    monkeypatch.setenv("ACMM_LIMIT_CONFIG_BYTES", " ")
    assert limit("CONFIG_BYTES") == DEFAULTS["CONFIG_BYTES"]


def test_a_product_limit_is_read_from_the_products_table(monkeypatch):
    """A product passes its own table; the variable overrides its default the same way."""
    from acmm_qpp.limits import how_to_raise, limit

    table = {"WIDGETS": 7}
    monkeypatch.delenv("ACMM_LIMIT_WIDGETS", raising=False)
    assert limit("WIDGETS", table) == 7
    monkeypatch.setenv("ACMM_LIMIT_WIDGETS", "9")
    assert how_to_raise("WIDGETS", table) == "limit 9; set ACMM_LIMIT_WIDGETS to change it"
