"""The progress bar of acmm's commands (acmm.cli.steps, issue 14 item 9)."""
from __future__ import annotations

import threading

from acmm.cli.steps import Steps


def test_the_design_bar_runs_no_thread_beside_the_design_pool(monkeypatch):
    """The design stage forks its LMI pool only when no other thread runs (a fork beside one can
    deadlock the child): the design's bar redraws at each step instead of from rich's thread."""
    monkeypatch.setenv("ACMM_PROGRESS", "1")
    before = threading.active_count()
    with Steps("designing", 3, refresh_thread=False) as bar:
        bar.advance("designed one")
        assert threading.active_count() == before
    with Steps("sweeping", 3) as bar:               # the default: rich's refresh thread
        assert threading.active_count() == before + 1
