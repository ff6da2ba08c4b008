"""The shared CLI plumbing (acmm_qpp.cli.plumbing): --version and completion of both apps, and a
Ctrl-C wrapped in another exception or landing while parsing is still an interrupt."""
from __future__ import annotations

import pytest

from tests.conftest import invoke


def acmm(*args):
    from acmm.cli.app import app

    return invoke(app, *args)


def qpp(*args):
    from qpp.cli import app

    return invoke(app, *args)


# ---------------------------------------------------------------------------------------------
# item 8: CLI conventions and exit codes
# ---------------------------------------------------------------------------------------------
def test_version_and_completion():
    import importlib.metadata as md

    for run in (acmm, qpp):
        r = run("--version")
        assert r.exit_code == 0 and md.version("acmm-qpp") in r.stdout
        assert "--install-completion" in run("--help").stdout


def _interrupting_app():
    import typer

    from acmm_qpp.cli.plumbing import ExitCodeGroup, user_errors

    app = typer.Typer(cls=ExitCodeGroup, add_completion=False)

    def interrupt_while_parsing(value):
        if value == "now":
            raise KeyboardInterrupt
        return value

    @app.command()
    @user_errors
    def wrapped(when: str = typer.Option("later", callback=interrupt_while_parsing)) -> None:
        """Python wraps a Ctrl-C that lands in a class body (``__set_name__``) in a RuntimeError."""
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error calling __set_name__ on '_deprecated_property'") from exc

    @app.command()
    def other() -> None:
        """A second command, so that the first is a subcommand."""

    return app


def test_an_interrupt_wrapped_in_another_exception_is_still_an_interrupt():
    """A Ctrl-C at ~0.3 s of `acmm report` (matplotlib's import) gave a traceback with exit 1."""
    from typer.testing import CliRunner

    res = CliRunner().invoke(_interrupting_app(), ["wrapped"])
    assert res.exit_code == 130 and res.output.strip() == "interrupted", res.output


def test_an_interrupt_while_parsing_reaches_a_non_standalone_caller_as_keyboardinterrupt():
    """ExitCodeGroup runs click's steps itself (typer's main made it a silent exit 130); a caller of
    main(standalone_mode=False) gets the KeyboardInterrupt back (not an Exception its `except
    Exception` would swallow)."""
    from typer.main import get_command

    with pytest.raises(KeyboardInterrupt):
        get_command(_interrupting_app()).main(["wrapped", "--when", "now"], standalone_mode=False)
    with pytest.raises(SystemExit) as stop:
        get_command(_interrupting_app()).main(["wrapped", "--when", "now"])
    assert stop.value.code == 130
