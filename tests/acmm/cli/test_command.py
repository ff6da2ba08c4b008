"""The wrapper of the acmm commands (acmm.cli.command): one ``error:`` line with the hint the
error was raised with, the error's exit code, and the return value of a command that succeeds."""
from __future__ import annotations

import pytest
import typer

from acmm.cli.command import _compiled_cache_notes as compiled_cache_notes, acmm_command
from acmm_qpp.errors import EXIT_NUMERICAL, ConvergenceError


def test_an_error_prints_its_own_hint_once(capsys):
    def fails():
        raise ConvergenceError("sector LQR: Riccati solve (method='sign') failed", hint="lower design.sector.sigma")

    with pytest.raises(typer.Exit) as exc:
        acmm_command(fails)()
    assert exc.value.exit_code == EXIT_NUMERICAL
    assert capsys.readouterr().err == ("error: sector LQR: Riccati solve (method='sign') failed; "
                                       "hint: lower design.sector.sigma\n")
    assert acmm_command(lambda: 1)() == 1 and isinstance(compiled_cache_notes(), list)
