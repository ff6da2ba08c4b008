"""``acmm`` command line: one command per stage (CR-185644 Part II).

Commands parse arguments, call the ``acmm`` library, print, and write results; no
mathematics lives here.  User errors print one line and exit with code 2.
"""
from __future__ import annotations

import math
from typing import Optional

import enum

import typer

from acmm_qpp.cli.plumbing import (OutOpt, StrictOpt, help_command, overrides_arg, product_app, redraw_command,
                                   run_app, strict_exit)
from acmm.cli import report, sweep
from acmm.cli.command import CONFIGS, FiguresOpt, acmm_command
from acmm.cli.steps import Steps
from acmm.model.unit_systems import shown

app = product_app("Space Station attitude control / momentum management (CR-185644 Part II).",
                  ("acmm design mb3                      # sector LQR of MB3, writes runs/mb3/design.h5 + figures",
                   "acmm simulate                        # the packaged stair-case (130 orbits)",
                   "acmm simulate mb3 simulation.orbits=2",
                   "acmm sweep sweep_smoke --workers 2",
                   "acmm plot runs/staircase             # redraw a run's figures from its .h5 files",
                   "acmm COMMAND --help                  # each command's options and examples"),
                  CONFIGS, ("acmm", "sweep", "qpp"))


def _load(config, overrides):
    """The validated acmm config of CONFIG plus KEY=VALUE overrides (a CONFIG that is itself an
    override means: the packaged default with that override)."""
    from acmm.io.config import load_config, split_overrides  # deferred: --help needs no numpy, scipy, pydantic

    return load_config(*split_overrides(config, overrides))

ConfigArg = typer.Argument(None, help="YAML config file (or the name of a packaged config, listed below); "
                                      "default: the packaged stair-case config")


def _fmt(v, fmt="{:+.4f}"):
    return "[" + ", ".join(fmt.format(x) for x in v) + "]"


@app.command(short_help="Check a config of any kind (acmm run, sweep or qpp).",
             cls=help_command(["acmm validate mb3", "acmm validate my_station.yaml --show",
                               "acmm validate staircase schedule.n_points=6"], ("acmm", "sweep", "qpp"), CONFIGS))
@acmm_command
def validate(config: Optional[str] = ConfigArg,
             overrides: Optional[list[str]] = overrides_arg("design.sector.sigma=0.6 schedule.n_points=6"),
             show: bool = typer.Option(False, "--show", help="print the resolved config (all defaults, canonical units)")) -> None:
    """Check a config of any kind (acmm run, sweep or qpp; detected from its sections); exit 2
    naming the offending field when it is invalid."""
    from acmm.cli.configkinds import load_any  # deferred: --help needs no numpy, scipy, pydantic

    kind, cfg = load_any(config, overrides)
    typer.echo(f"{cfg.name}: valid ({kind} config)")
    if show:
        typer.echo(cfg.to_yaml())


class ConfigKind(str, enum.Enum):
    """The three config kinds."""

    acmm = "acmm"
    sweep = "sweep"
    qpp = "qpp"


@app.command(short_help="Print the JSON schema of a config kind.",
             cls=help_command(["acmm schema > acmm.schema.json", "acmm schema --kind sweep", "acmm schema --kind qpp"]))
@acmm_command
def schema(kind: ConfigKind = typer.Option(ConfigKind.acmm, "--kind", help="config kind")) -> None:
    """Print the JSON schema of a config kind (for editors: see the guide's config page, Reference → Config)."""
    from acmm.cli.configkinds import schema_json  # deferred: --help needs no numpy, scipy, pydantic

    typer.echo(schema_json(kind.value))


@app.command(short_help="Torque-equilibrium attitude (eqs 4.1-4.3); writes tea.h5.",
             cls=help_command(["acmm tea mb3", "acmm tea ac --all", "acmm tea mb3 inertia.I22=1.5e6"], ("acmm",), CONFIGS))
@acmm_command
def tea(config: Optional[str] = ConfigArg, overrides: Optional[list[str]] = overrides_arg("inertia.I22=1.5e6"),
        all_roots: bool = typer.Option(False, "--all", help="also list every other equilibrium found")) -> None:
    """Torque-equilibrium attitude (eqs 4.1–4.3); writes runs/<name>/tea.h5."""
    from acmm.stages.runners import run_tea  # deferred: --help needs no numpy, scipy, pydantic

    result, path = run_tea(_load(config, overrides), all_roots=all_roots)
    t = result.tea
    typer.echo(f"{result.config.name}: torque-equilibrium attitude (eqs 4.1-4.3)")
    typer.echo(f"  theta* [roll, pitch, yaw]  = {_fmt(t.theta_deg)} deg")
    typer.echo(f"  omega*                     = {_fmt(t.omega, '{:+.6e}')} rad/s")
    sys_ = result.config.output.units
    bias, tu = shown(t.bias, "ft*lbf", sys_)
    typer.echo(f"  bias used                  = {_fmt(bias, '{:+.6g}')} {tu}")
    typer.echo(f"  residual max|eq 4.1|       = {shown(t.residual, 'ft*lbf', sys_)[0]:.2e} {tu}")
    for k, other in enumerate(result.others):
        typer.echo(f"  other root {k + 1}: theta = {_fmt(other.theta_deg)} deg (residual {other.residual:.1e})")
    typer.echo(f"  wrote {path}")


@app.command(short_help="24-state linearization about the TEA (eqs 4.4-4.50).",
             cls=help_command(["acmm linearize mb3", "acmm linearize ac design.drf_mode=attitude_hold"], ("acmm",), CONFIGS))
@acmm_command
def linearize(config: Optional[str] = ConfigArg,
              overrides: Optional[list[str]] = overrides_arg("orbit_rate=0.0011")) -> None:
    """24-state linearization about the TEA (eqs 4.4-4.50); writes runs/<name>/linearize.h5."""
    from acmm.stages.runners import run_linearize  # deferred: --help needs no numpy, scipy, pydantic

    r, path = run_linearize(_load(config, overrides))
    m, c = r.model, r.controllability
    typer.echo(f"{r.config.name}: {m.variant} model, {m.drf_mode}, about theta* = "
               f"{_fmt([math.degrees(x) for x in m.theta_star], '{:+.3f}')} deg")
    eig = r.eigenvalues_over_n()
    typer.echo("  open-loop eigenvalues / n:")
    for k in range(0, len(eig), 4):
        typer.echo("    " + "  ".join(f"{e.real:+9.4f}{e.imag:+9.4f}j" for e in eig[k:k + 4]))
    typer.echo(f"  controllability (PBH, scaled): rank {c.rank}/{c.order} at tol {c.tol:g}; "
               f"smallest sigma ratio {c.min_ratio:.2e} at s = {c.worst_s.real / m.n:+.3f}{c.worst_s.imag / m.n:+.3f}j n")
    if c.min_ratio < 1e-6:
        typer.echo(f"  warning: the model is nearly uncontrollable (sigma ratio {c.min_ratio:.1e} < 1e-6);"
                   " expect poor Riccati residuals", err=True)
    typer.echo(f"  wrote {path}")


def _run_with_progress(runner, cfg, figures, what: str):
    """Call a stage runner with terminal progress (acmm_qpp.cli.progress: a bar over the design points,
    then the remaining work; silent when stderr is not a terminal)."""
    from acmm.cli.compile_note import announce_numba_compile  # deferred: --help needs no numba

    total = cfg.n_design_points()
    if what == "simulate":
        announce_numba_compile()
    with_figures = cfg.output.figures if figures is None else figures
    after = ("simulating, writing results" if what == "simulate" else
             "fitting the schedule, checking it, writing results") + (" and figures" if with_figures else "")
    # redrawn at each step, not from rich's thread: the LMI points are designed on a forked pool,
    # which is not forked beside other threads (acmm.stages.design._point_workers)
    with Steps(f"{cfg.name}: designing", total, refresh_thread=False) as bar:
        count = [0]

        def tick(name):
            count[0] += 1
            bar.advance(f"{cfg.name}: designed {name}" if count[0] < total else f"{cfg.name}: {after}")

        if what == "simulate":
            bar.describe(f"{cfg.name}: design (or reuse), {after}")
        return runner(cfg, progress=tick, figures=figures, warn=_warn)


def _warn(message: str) -> None:
    """A warning of a stage (e.g. an unstable schedule, before it is written), on stderr."""
    typer.echo(f"warning: {message}", err=True)


def _design_line(name: str, note: str) -> str:
    """The line saying where a command's design came from (``note`` of
    :func:`acmm.stages.design.design_for`: ``reused <path>`` or ``designed, wrote <path>``)."""
    if note.startswith("reused "):
        return f"{name}: design reused from {note[len('reused '):]} (same config)"
    if note.startswith("designed, wrote "):
        return f"{name}: no stored design for this config; designed it and wrote {note[len('designed, wrote '):]}"
    return f"{name}: design {note}"


@app.command(short_help="Sector LQR or regional LMI per design point and the gain schedule.",
             cls=help_command(["acmm design mb3", "acmm design staircase schedule.n_points=7 --strict",
                               "acmm design my_station.yaml design.sector.sigma=0.6 --no-figures"], ("acmm",), CONFIGS))
@acmm_command
def design(config: Optional[str] = ConfigArg,
           overrides: Optional[list[str]] = overrides_arg("design.sector.sigma=0.6 schedule.n_points=7"),
           figures: Optional[bool] = FiguresOpt, strict: bool = StrictOpt) -> None:
    """TEA -> linearize -> sector LQR or LMI per point -> schedule; writes runs/<name>/design.h5 + figures.
    With --strict, a scheduled gain with poles outside the sector, a blend whose end lies on
    another branch of equilibria, or a robust gain not proved stable for every plant of its
    family (design.robust), exits 1."""

    from acmm.stages.design import run_design  # deferred: --help needs no numpy, scipy, pydantic

    r, path = _run_with_progress(run_design, _load(config, overrides), figures, "design")
    cfg = r.config
    typer.echo(f"{cfg.name}: {len(r.points)} design point(s), {cfg.design.model} model, "
               f"sector Re <= -{cfg.design.sector.sigma}n, {cfg.design.sector.half_angle_deg:g} deg "
               f"({r.wall_time:.2f} s)")
    lmis = [p.gain.lmi for p in r.points if p.gain.lmi is not None]
    if lmis:
        typer.echo("  regional LMI gains; 'residual' is that of the reference sector LQR (the LMI's pre-conditioner)")
    typer.echo(f"  {'point':<14} {'TEA r/p/y (deg)':<28} {'margin (n)':>10} {'residual':>9} {'fastest/n':>9}")
    for p, fastest in zip(r.points, r.fastest_over_n()):
        typer.echo(f"  {p.spec.name:<14} {_fmt(p.tea.theta_deg, '{:+.2f}'):<28} {p.gain.margin:>10.3f} "
                   f"{p.gain.riccati.residual:>9.1e} {fastest:>9.2f}")
    if lmis:
        fallbacks = sum(bool(x.rejected) for x in lmis)
        typer.echo(f"  regional LMI: solved by {', '.join(sorted({x.solver for x in lmis}))}; margin certified by X "
                   f">= {min(x.certified_margin for x in lmis):.4f} n at every point; "
                   f"{fallbacks} point(s) needed the fallback solver; {sum(x.solve_time for x in lmis):.1f} s of solves")
    for p in r.points:
        if p.gain.robust is not None:
            _echo_robust(p.spec.name, p.gain.robust)
    if r.fit is not None and r.fit.form == "table":
        nodes = sum(not p.spec.level for p in r.points)
        added = (f" ({len(r.points) - nodes} levels and {nodes} node(s) added where a path TEA's sector margin "
                 f"was below {r.config.schedule.refine_margin:g} n)") if nodes else ""
        typer.echo(f"  schedule: table, K linear in theta2* between the {len(r.points)} design points{added}")
    elif r.fit is not None:
        typer.echo(f"  schedule: order {r.fit.order} in theta2*; worst relative fit residual "
                   f"{r.fit.rel_residual.max():.2e}")
        info = r.fit.refit_info
        if "decay" in info:                            # the converged quadratic's refit ran
            typer.echo(f"  shifted-LQR refit (Re(pole) < -{info['decay']:g} n, {info['cone_deg']:g} deg cone, at "
                       f"{info['n_tea']} TEAs; from the least-squares fit's {info['max_real_before']:+.3f} n): "
                       + (info["message"] if info["accepted"] else f"NOT done, {info['message']}; the least-squares "
                          "fit is kept"))
    if r.fit is not None and r.fit.form == "polynomial" and r.config.schedule.refine_points:
        typer.echo("  note: schedule.refine_points adds nodes to a table; a polynomial has none (not used)")
    if r.refinement is not None and not r.refinement.met:
        typer.echo(f"  warning: the table's refinement stopped after {r.refinement.added} of at most "
                   f"{r.refinement.limit} node(s) with the margin {r.refinement.margin:g} n not met at every path TEA "
                   "(raise schedule.refine_points)")
    if r.fit is not None and r.check is not None:      # either form: what --strict judges
        c = r.check
        worst = r.worst_check_index()
        verdict = "all in the sector" if c.worst > 0 else "NOT all in the sector"
        typer.echo(f"  scheduled gain ({r.fit.form}) on the local models ({len(c.names)} checks): {verdict}; "
                   f"worst margin {c.worst:+.3f} n at {c.names[worst]} ({c.kind[worst]})")
        stable = "stable at every check" if c.max_real.max() < 0 else "UNSTABLE at some checks"
        typer.echo(f"  scheduled closed loops: {stable}; largest Re(pole) = {c.max_real.max():+.3f} n")
    pc = r.path_check
    if pc is not None:
        inside = int((pc.margin >= 0).sum())
        typer.echo(f"  along the path ({pc.margin.size} TEAs): every pole in the sector at {inside} of "
                   f"{pc.margin.size}; worst margin {pc.margin.min():+.3f} n; largest Re(pole) "
                   f"{pc.max_real.max():+.3f} n")
    jump = r.off_branch()
    if jump is not None:
        typer.echo("  warning: " + _branch_jump_text(jump))
    typer.echo(f"  wrote {path}")
    strict_exit(strict, jump is not None, f"{cfg.name}: the blend's design point {jump.name if jump else ''} "
                "is on another branch of equilibria")
    if r.check is not None:
        strict_exit(strict, r.check.worst <= 0,
                    f"{cfg.name}: the scheduled gain puts poles outside the sector "
                    f"(worst margin {r.check.worst:+.3f} n)")
    strict_exit(strict, r.unstable() is not None, f"{cfg.name}: {r.unstable()}")
    unproved = [f"{p.spec.name}: {', '.join(p.gain.robust.unproved())}" for p in r.points
                if p.gain.robust is not None and p.gain.robust.unproved()]
    strict_exit(strict, bool(unproved), f"{cfg.name}: the robust gain is not proved stable for " + "; ".join(unproved))


def _echo_robust(name: str, rd) -> None:
    """The per-plant verdicts of a robust design (acmm.design.robust.RobustDesign)."""
    fam = rd.family
    held = rd.sector_held()
    scalings = sum(lab.startswith("scale") for lab in fam.labels)
    folded_scalings = (f", {len(fam.scalings_folded)} scaling(s) whose design branch folds"
                       if fam.scalings_folded else "")
    typer.echo(f"  robust gain at {name}: {len(fam.labels)} plants (nominal, {len(fam.labels) - 1 - scalings} "
               f"of {fam.draws} draws: {fam.unphysical} unphysical, {fam.folded} whose design branch folds; "
               f"{scalings} uniform scalings{folded_scalings}); worst pole real part "
               f"{rd.start_abscissa:+.3f} n -> {rd.worst_abscissa:+.3f} n ({rd.restarts} BFGS restart(s): {rd.stop}; "
               f"{rd.solve_time:.1f} s)")
    typer.echo(f"    {'plant':<12} {'pitch TEA (deg)':>15} {'decay (n)':>10} {'cone (deg)':>10}  verdict (certified by X)")
    for lab, th, c, h in zip(fam.labels, fam.theta, rd.certificates, held):
        if not c.decay > 0:
            typer.echo(f"    {lab:<12} {math.degrees(th[1]):>15.2f} {'-':>10} {'-':>10}  NOT proved stable "
                       f"(largest Re(pole) {c.max_real:+.4f} n)")
            continue
        verdict = "in the sector" if h else "stable, not in the sector"
        typer.echo(f"    {lab:<12} {math.degrees(th[1]):>15.2f} {c.decay:>10.4f} {c.cone_deg:>10.2f}  {verdict}")
    sigma, phi = rd.sector
    unproved = rd.unproved()
    if unproved:
        typer.echo(f"  warning: the robust gain at {name} is NOT proved stable for {len(unproved)} of "
                   f"{len(fam.labels)} plants ({', '.join(unproved)}): no region is certified for the family")
    else:
        typer.echo(f"  every plant is certified in Re <= {-rd.decay:+.4f}n, |arg(-pole)| <= {rd.cone_deg:.2f} deg; "
                   f"the sector (Re <= -{sigma:g}n, {phi:g} deg) holds for {int(held.sum())} of {held.size}")


def _branch_jump_text(jump) -> str:
    """The warning for a blend point off the start's branch of equilibria (a BranchJump)."""
    who = ("the end station's TEA" if jump.s == 1.0 else f"the TEA of design point {jump.name} (s = {jump.s:.3g})")
    tea = _fmt([math.degrees(x) for x in jump.theta], "{:+.2f}") + " deg" + (" (as asked)" if jump.asked else "")
    if jump.branch is None:
        where = "which folds (ends) before reaching it"
    else:
        where = f"which reaches {_fmt([math.degrees(x) for x in jump.branch], '{:+.2f}')} deg there"
    return (f"{who} {tea} is not on the branch of equilibria continued from the start, {where}: "
            "the blend crosses a fold and the schedule is fitted across the jump")


@app.command(short_help="Dwell-time stability certificate of the stair-case.",
             cls=help_command(["acmm certify", "acmm certify staircase schedule.n_points=8 --strict"], ("acmm",), CONFIGS))
@acmm_command
def certify(config: Optional[str] = ConfigArg, overrides: Optional[list[str]] = overrides_arg("schedule.n_points=8"),
            strict: bool = StrictOpt) -> None:
    """Dwell-time stability certificate of the stair-case: per-level Lyapunov functions of the
    frozen closed loops found by LMIs (Geromel-Colaneri, switches both ways), the certified minimum
    dwell against each level's dwell, and the bound on each TEA step's transient against the torque
    and momentum limits (designs first if needed; `acmm design` stores it in design.h5).
    With --strict, a stair-case that is not certified exits 1."""
    from acmm.stages.certify import certificate_lines, compute_certificate  # deferred: --help needs no numpy, scipy, pydantic
    from acmm.stages.design import design_for  # deferred: --help needs no numpy, scipy, pydantic

    cfg = _load(config, overrides)
    table, note = design_for(cfg, warn=_warn)
    sc = compute_certificate(cfg, table, cfg.run_dir() / "design.h5")
    typer.echo(_design_line(cfg.name, note))
    for line in certificate_lines(sc):
        typer.echo(line)
    strict_exit(strict, not sc.certificate.certified,
                f"{cfg.name}: the stair-case is not certified by a dwell time")


@app.command(short_help="Nonlinear closed-loop simulation (ch 6); writes sim.h5.",
             cls=help_command(["acmm simulate                         # the stair-case, 130 orbits",
                               "acmm simulate mb3 simulation.orbits=2",
                               "acmm simulate ac output.units=si --strict"], ("acmm",), CONFIGS))
@acmm_command
def simulate(config: Optional[str] = ConfigArg, overrides: Optional[list[str]] = overrides_arg("simulation.orbits=10"),
             figures: Optional[bool] = FiguresOpt, strict: bool = StrictOpt) -> None:
    """Nonlinear closed-loop simulation (ch. 6); designs first if needed; writes runs/<name>/sim.h5 + figures.
    With --strict, a DIVERGED verdict exits 1."""

    from acmm.stages.simulate import run_simulate  # deferred: --help needs no numpy, scipy, pydantic

    r, path = _run_with_progress(run_simulate, _load(config, overrides), figures, "simulate")
    cfg, s = r.config, r.sim
    typer.echo(_design_line(cfg.name, r.design_note))
    typer.echo(f"  simulated {r.orbits_simulated:.2f} of {cfg.simulation.orbits:g} orbits in "
               f"{r.wall_time:.2f} s ({s.n_steps} steps, {s.n_rejected} rejected)")
    typer.echo(f"  verdict: {s.verdict.upper()} ({s.reason}" +
               (f" at {r.stop_orbit:.3f} orbit)" if s.diverged else ")"))
    for st in r.stats:
        typer.echo(f"  level {st['level']:>2} from orbit {st['start_orbit']:6.1f}: theta2* {st['theta2_deg']:+7.2f} deg, "
                   f"steady |err| {_fmt(st['steady_error_deg'], '{:.3f}')} deg, peak |h| "
                   "{:.0f} {}".format(*shown(st['peak_momentum'], "ft*lbf*s", cfg.output.units)))
    typer.echo(f"  wrote {path}")
    strict_exit(strict, s.verdict != "bounded", f"{cfg.name}: verdict {s.verdict.upper()} ({s.reason})")


@app.command(short_help="Redraw a run's figures from its stored results (.h5).",
             cls=help_command(["acmm plot runs/staircase", "acmm plot runs/mb3/sim.h5 --out figures/mb3",
                               "acmm plot runs/sweep_smoke"]))
@acmm_command
def plot(target: str = typer.Argument(..., metavar="RUN_DIR_OR_H5",
                                      help="a run folder (runs/<name>) or one of its results files: design.h5, "
                                           "sim.h5, sweep.h5, qpp_design.h5, qpp_sim.h5"),
         out: Optional[str] = OutOpt) -> None:
    """Redraw the figures of a run from its stored results alone (nothing is designed or
    simulated again): the same files, with the same names, as the stage that wrote them.
    Exit 2 when RUN_DIR_OR_H5 is missing or holds no results file of this project."""
    from acmm.cli.redraw import redraw_figures  # deferred: --help needs no numpy, scipy, pydantic

    redraw_command(redraw_figures, target, out)


def main() -> None:
    """Console entry point (``acmm``): :func:`acmm_qpp.cli.plumbing.run_app` of the app."""
    run_app(app)


sweep.register(app)      # the commands in their own modules, after the others in the help
report.register(app)


if __name__ == "__main__":     # python -m acmm.cli.app
    main()
