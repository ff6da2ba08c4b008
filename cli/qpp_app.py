"""``qpp`` command line (Part III of CR-185644)."""
from __future__ import annotations

import typer

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Quantitative pole placement for Lure systems (CR-185644 Part III).")


@app.callback()
def _root() -> None:
    """Quantitative pole placement for Lure systems (CR-185644 Part III)."""


def main() -> None:
    app()
