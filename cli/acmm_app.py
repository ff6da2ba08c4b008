"""``acmm`` command line: one command per stage (CR-185644 Part II).

Commands parse arguments, call the ``acmm`` library, print, and write results; no
mathematics lives here.  User errors print one line and exit with code 2.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from cli.common import user_errors

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Space Station attitude control / momentum management (CR-185644 Part II).")

ConfigArg = typer.Argument(None, help="YAML config file (or the name of a packaged config); "
                                      "default: the packaged stair-case config")


def _fmt(v, fmt="{:+.4f}"):
    return "[" + ", ".join(fmt.format(x) for x in v) + "]"


@app.command()
@user_errors
def validate(config: Optional[Path] = ConfigArg) -> None:
    """Check a config file and print the resolved values."""
    from acmm.config import load_config

    cfg = load_config(config)
    typer.echo(f"{cfg.name}: valid")


@app.command()
@user_errors
def schema() -> None:
    """Print the JSON schema of the config format."""
    from acmm.config import Config

    typer.echo(json.dumps(Config.model_json_schema(), indent=2))


@app.command()
@user_errors
def tea(config: Optional[Path] = ConfigArg,
        all_roots: bool = typer.Option(False, "--all", help="also list every other equilibrium found")) -> None:
    """Torque-equilibrium attitude (eqs 4.1–4.3); writes runs/<name>/tea.h5."""
    from acmm.stages import run_tea

    result, path = run_tea(config, all_roots=all_roots)
    t = result.tea
    typer.echo(f"{result.config.name}: torque-equilibrium attitude (eqs 4.1-4.3)")
    typer.echo(f"  theta* [roll, pitch, yaw]  = {_fmt(t.theta_deg)} deg")
    typer.echo(f"  omega*                     = {_fmt(t.omega, '{:+.6e}')} rad/s")
    typer.echo(f"  bias used                  = {_fmt(t.bias, '{:+.5f}')} ft*lbf")
    typer.echo(f"  residual max|eq 4.1|       = {t.residual:.2e} ft*lbf")
    for k, other in enumerate(result.others):
        typer.echo(f"  other root {k + 1}: theta = {_fmt(other.theta_deg)} deg (residual {other.residual:.1e})")
    typer.echo(f"  wrote {path}")


def main() -> None:
    app()
