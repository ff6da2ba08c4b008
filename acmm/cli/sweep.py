"""``acmm sweep``: batch sweeps / Monte Carlo robustness studies (issue 7).

Registered on the ``acmm`` app by :func:`register`; the library (numpy, the sweep, numba's note)
is imported inside the command, so that ``acmm --help`` stays fast.
"""
from __future__ import annotations

import contextlib
import logging
from typing import Optional

import typer

from acmm_qpp.errors import EXIT_INPUT
from acmm.cli.command import CONFIGS, FiguresOpt, acmm_command
from acmm_qpp.cli.plumbing import fail, help_command, overrides_arg, strict_exit
from acmm.cli.steps import Steps


class _Bar:
    """Sweep progress on an interactive terminal (rich: bar, cases/s, elapsed, ETA, how many are not
    bounded); silent when stderr is not a terminal."""

    def __init__(self, name: str = "sweep"):
        self.name = name
        self.bad = 0
        self.steps = None

    def __call__(self, done: int, total: int, rec: dict) -> None:
        if rec.get("kind") == "case" and rec.get("verdict") != "bounded":
            self.bad += 1
        if self.steps is None:                     # (silent unless enabled: Steps checks)
            self.steps = Steps(f"{self.name}: {done - 1}/{total} tasks", total, rate=True).__enter__()
            self.steps.advance(n=done - 1)
        self.steps.advance(f"{self.name}: {self.bad} not bounded")
        if done >= total:
            self.close()

    def close(self) -> None:
        if self.steps is not None:
            self.steps.__exit__(None, None, None)
            self.steps = None


def _check_executor_options(workers: Optional[int], scheduler: Optional[str]) -> None:
    """Refuse a bad ``-j``/``--scheduler`` (one line, exit 2); with a scheduler, quiet its
    client's log (a lost scheduler is then the sweep's one line, not distributed's tracebacks)."""
    if workers is not None and not 1 <= workers <= 1024:
        fail(f"--workers: must be between 1 and 1024 (got {workers})", EXIT_INPUT)
    if scheduler is not None and workers is not None:
        fail("--workers and --scheduler: give one (with --scheduler the cluster's workers run the cases)",
             EXIT_INPUT)
    if scheduler is not None and not scheduler.strip():
        fail("--scheduler: an empty address (give host:port of a Dask scheduler, or leave the option out "
             "to run on local processes)", EXIT_INPUT)
    if scheduler is not None:
        # after ``import distributed``, which sets its loggers' levels from its config; without it
        # the sweep reports that --scheduler needs acmm-qpp[dask]
        with contextlib.suppress(ImportError):
            import distributed  # noqa: F401  # deferred: dask start-up, and an optional dependency

            logging.getLogger("distributed.client").setLevel(logging.CRITICAL)


def register(app: typer.Typer) -> None:
    """Add the ``sweep`` command to ``app``.

    Parameters
    ----------
    app : typer.Typer
        The ``acmm`` app.
    """

    @app.command(short_help="Monte Carlo / grid sweep of closed-loop runs; writes sweep.h5.",
                 cls=help_command(["acmm sweep sweep_smoke --workers 2",
                                   "acmm sweep sweep_inertia30 sweep.n_runs=20 sweep.orbits=2",
                                   "acmm sweep my_sweep.yaml --resume --no-figures"], ("sweep",), CONFIGS))
    @acmm_command
    def sweep(config: str = typer.Argument(..., help="sweep config YAML or the name of a packaged sweep config "
                                                     "(listed below)"),
              overrides: Optional[list[str]] = overrides_arg("sweep.n_runs=20 sweep.orbits=2"),
              workers: Optional[int] = typer.Option(None, "--workers", "-j",
                                                    help="local worker processes (1: in-process; "
                                                         "default: sweep.workers or the CPU count)"),
              scheduler: Optional[str] = typer.Option(None, "--scheduler",
                                                      help="Dask scheduler address (needs acmm-qpp[dask])"),
              resume: bool = typer.Option(False, "--resume", help="skip the cases already in the journal"),
              figures: Optional[bool] = FiguresOpt,
              strict: bool = typer.Option(False, "--strict", help="exit 1 when any case is not bounded (for CI)")
              ) -> None:
        """Monte Carlo / grid sweep of closed-loop runs; writes runs/<name>/sweep.h5, sweep.csv, figures.

        KEY=VALUE overrides apply to the sweep file (its sweep and output sections), not to
        the base configs it names."""
        import numpy as np  # deferred: --help needs no numpy

        from acmm.cli.compile_note import announce_numba_compile  # deferred: --help needs no numba
        from acmm.sweep.config import load_sweep  # deferred: --help needs no numpy, scipy
        from acmm.sweep.run import run_sweep  # deferred: --help needs no numpy, scipy

        _check_executor_options(workers, scheduler)
        sw = load_sweep(config, overrides)
        no_journal = resume and not (sw.run_dir() / "sweep.journal").exists()
        announce_numba_compile()
        bar = _Bar(sw.name)
        try:
            r = run_sweep(sw, workers=workers, scheduler=scheduler, resume=resume, progress=bar, figures=figures)
        finally:
            bar.close()
        if no_journal and r.n_resumed == 0:     # after the run: a refused run prints one line only
            typer.echo(f"note: no journal in {sw.run_dir()}; started from the first case", err=True)
        spec = sw.spec
        how = (f"grid of {spec.n_cases()}" if spec.grid is not None else
               f"Monte Carlo, {spec.n_cases()} runs, seed {spec.seed}")
        typer.echo(f"{sw.name}: {how} per base; {spec.design} design"
                   + (f", {spec.tea_estimate} TEA estimate" if spec.design == "fixed" else "")
                   + f"; {r.n_new} task(s) run, {r.n_resumed} resumed, {r.wall_time:.1f} s")
        for lab, counts in r.summary().items():
            rows = [x for x in r.rows if x["base"] == lab]
            others = ", ".join(f"{v} {c}" for v, c in counts.items() if c and v not in ("bounded", "total"))
            line = f"  {lab}: {counts['bounded']}/{counts['total']} bounded" + (f" ({others})" if others else "")
            ok = [x for x in rows if x["verdict"] == "bounded"]
            if ok:
                peak = np.array([x["peak_attitude_error"] for x in ok])
                line += ("; bounded: median/max peak |err| r/p/y "
                         + "/".join(f"{v:.1f}" for v in np.median(peak, axis=0)) + " / "
                         + "/".join(f"{v:.1f}" for v in peak.max(axis=0)) + " deg")
            draws = sum(x["n_draws"] for x in rows)
            if draws > len(rows):
                line += f"; {draws} draws for {len(rows)} cases ({draws - len(rows)} unphysical draws discarded)"
            typer.echo(line)
        for m in r.margins:
            word = "largest" if m["direction"] == "up" else "smallest"
            if m["limit"] != m["limit"]:
                typer.echo(f"  {m['base']} margin: the nominal case itself is not bounded")
            elif m["reached_end"]:
                typer.echo(f"  {m['base']} margin: bounded over the whole searched range to s = {m['search_end']:g}")
            else:
                typer.echo(f"  {m['base']} margin: {word} uniform inertia scaling tolerated s = {m['limit']:.3f} "
                           f"(fails at {m['first_failure']:.3f}: {m['failure_verdict']})")
        typer.echo(f"  wrote {r.path} and {r.path.with_suffix('.csv').name}"
                   + (f", {len(r.figures)} figure(s)" if r.figures else ""))
        bad = [x for x in r.rows if x["verdict"] != "bounded"]
        strict_exit(strict, bool(bad), f"{sw.name}: {len(bad)} of {len(r.rows)} case(s) not bounded")
