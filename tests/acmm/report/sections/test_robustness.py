"""The report's robustness section (acmm.report.sections.robustness) when the sweep fails."""
from __future__ import annotations

import pytest

from acmm_qpp.errors import ConfigError
from acmm.report.context import SectionWriter
from acmm.report import document as document_mod
from acmm.report import gather as gather_mod
from acmm.report import ledger as ledger_mod

from tests.acmm.report.conftest import PageParser

pytestmark = pytest.mark.slow      # a whole `acmm report --fast` per session: `make test-slow`


class _Robustness(SectionWriter):
    """A writer that runs the robustness section alone (it needs no other section's output)."""

    def robustness(self):
        from acmm.report.sections import robustness

        robustness._build(self)


def test_robustness_absent_renders_not_available(tmp_path, monkeypatch):
    """A sweep that fails with an AcmmError: the section says "Not available", with the reason."""
    def refuse(root, **kwargs):
        raise ConfigError("sweep.bases: a refused sweep")

    monkeypatch.setattr(gather_mod, "_robustness_from_sweep", refuse)
    res, note = gather_mod.robustness_result(tmp_path)
    assert res is None and note == "the sweep failed: ConfigError: sweep.bases: a refused sweep"
    g = gather_mod.Gathered(configs={}, runs={}, robustness=None, robustness_note=note)
    rep = _Robustness(g, tmp_path, fast=True)
    rep.robustness()
    md = document_mod.render_markdown(rep.doc, "t")
    assert "Not available in this run" in md and "## ±30 % inertia robustness" in md
    assert rep.ledger[-1].status == ledger_mod.STATUS_EXPLAINED
    html = document_mod.render_html(rep.doc, "t", tmp_path)
    p = PageParser()
    p.feed(html)
    assert "robustness" in p.ids
