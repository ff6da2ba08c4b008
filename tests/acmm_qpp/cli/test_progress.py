"""Terminal progress (acmm_qpp.cli.progress, issue 14 item 9): silent without a terminal, shown
when forced, the results on stdout the same."""
from __future__ import annotations

from tests.conftest import LQR_ROUTE, invoke


def acmm(*args):
    from acmm.cli.app import app

    return invoke(app, *args)


# ---------------------------------------------------------------------------------------------
# item 9: progress only on a terminal
# ---------------------------------------------------------------------------------------------
def test_progress_silent_without_terminal_and_shown_when_forced(tmp_runs, monkeypatch):
    quiet = acmm("design", "staircase", *LQR_ROUTE, "schedule.n_points=4", "--no-figures")
    # no progress; only the warning that this 4-point schedule is unstable somewhere (issue 34)
    assert quiet.exit_code == 0 and [x[:9] for x in quiet.stderr.splitlines()] == ["warning: "]
    monkeypatch.setenv("ACMM_PROGRESS", "1")
    loud = acmm("design", "staircase", *LQR_ROUTE, "schedule.n_points=4", "--no-figures")
    assert loud.exit_code == 0
    assert "designed" in loud.stderr or "fitting the schedule" in loud.stderr
    # stdout (the results) is the same with and without progress, up to the wall time
    strip = lambda s: [x for x in s.splitlines() if "design point(s)" not in x]  # noqa: E731
    assert strip(loud.stdout) == strip(quiet.stdout)
