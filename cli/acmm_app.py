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


@app.command()
@user_errors
def linearize(config: Optional[Path] = ConfigArg) -> None:
    """24-state linearization about the TEA (eqs 4.4-4.50); writes runs/<name>/linearize.h5."""
    import numpy as np

    from acmm.stages import run_linearize

    r, path = run_linearize(config)
    m, c = r.model, r.controllability
    typer.echo(f"{r.config.name}: {m.variant} model, {m.drf_mode}, about theta* = "
               f"{_fmt(np.degrees(m.theta_star), '{:+.3f}')} deg")
    eig = np.linalg.eigvals(m.A) / m.n
    eig = eig[np.lexsort((eig.imag, eig.real))]
    typer.echo("  open-loop eigenvalues / n:")
    for k in range(0, len(eig), 4):
        typer.echo("    " + "  ".join(f"{e.real:+9.4f}{e.imag:+9.4f}j" for e in eig[k:k + 4]))
    typer.echo(f"  controllability (PBH, scaled): rank {c.rank}/{c.order} at tol {c.tol:g}; "
               f"smallest sigma ratio {c.min_ratio:.2e} at s = {c.worst_s.real / m.n:+.3f}{c.worst_s.imag / m.n:+.3f}j n")
    if c.min_ratio < 1e-6:
        typer.echo(f"  warning: the model is nearly uncontrollable (sigma ratio {c.min_ratio:.1e} < 1e-6);"
                   " expect poor Riccati residuals", err=True)
    typer.echo(f"  wrote {path}")


def main() -> None:
    app()
