"""``acmm report`` on the command line (acmm.cli.report): registered, and a user error in one line."""
from __future__ import annotations

import pytest

pytestmark = pytest.mark.slow      # a whole `acmm report --fast` per session: `make test-slow`


def test_cli_report_command_registered_and_user_error(tmp_path):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    res = CliRunner().invoke(app, ["report", "--help"])
    assert res.exit_code == 0 and "--out" in res.output and "--fast" in res.output
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = CliRunner().invoke(app, ["report", "--out", str(blocker / "report"), "--root", str(tmp_path)])
    assert res.exit_code == 4  # EXIT_OUTPUT
    assert res.output.strip().startswith("error:") and len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "mb3").exists()        # nothing was run
