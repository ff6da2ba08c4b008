"""``qpp`` command line (Part III of CR-185644).

Commands parse arguments, call the ``qpp`` library, print, and write results; user errors print
one line and exit with code 2.
"""
from __future__ import annotations

import contextlib
import json
from typing import Optional

# first: acmm_qpp.cli sets the BLAS thread defaults, which must precede the first import of numpy
from acmm_qpp.cli.plumbing import (ConfigKinds, OutOpt, StrictOpt, help_command, overrides_arg, product_app,
                                   redraw_command, run_app, strict_exit, user_errors)
from qpp import CONFIG_SECTIONS, PACKAGED_CONFIGS

import numpy as np  # noqa: E402
import typer  # noqa: E402

from acmm_qpp.cli.progress import console, enabled  # noqa: E402
from acmm_qpp.errors import ConfigError, DesignError  # noqa: E402


#: The packaged configs and the one kind of config ``qpp`` reads.
CONFIGS = ConfigKinds(PACKAGED_CONFIGS, (("qpp", CONFIG_SECTIONS),),
                      "A config path is relative to the working directory; a bare name that is no file there "
                      "(qpp_siso, qpp_siso.yaml) is a packaged config.")


@contextlib.contextmanager
def _status(message: str):
    """A transient spinner with ``message`` while the block runs; yields ``update(text)`` (a no-op
    when progress is disabled)."""
    if not enabled():
        yield lambda text: None
        return
    with console().status(message) as st:
        yield lambda text: st.update(text)


app = product_app("Quantitative pole placement for Lure systems (CR-185644 Part III).",
                  ("qpp design qpp_unstable              # an unstable plant: gains and a certificate (exit 0)",
                   "qpp design qpp_siso                  # ch. 13: the report's gains; no consistent certificate (exit 3)",
                   "qpp simulate qpp_unstable            # the spheres checked in simulation",
                   "qpp plot runs/qpp_unstable           # redraw a run's figures from its .h5 files",
                   "qpp COMMAND --help                   # each command's options and examples"),
                  CONFIGS, ("qpp",))

ConfigArg = typer.Argument(..., help="YAML config file (or the name of a packaged config, listed below)")
FigOpt = typer.Option(None, "--figures/--no-figures", help="override output.figures")


def _load(config, overrides):
    from qpp.io.config import load_config  # deferred: --help needs no scipy, pydantic

    return load_config(config, overrides)


@app.command(short_help="Check a qpp config.",
             cls=help_command(["qpp validate qpp_siso", "qpp validate my_plant.yaml --show"], ("qpp",), CONFIGS))
@user_errors
def validate(config: str = ConfigArg, overrides: Optional[list[str]] = overrides_arg("spheres.beta_o=0.3"),
             show: bool = typer.Option(False, "--show", help="print the resolved config")) -> None:
    """Check a qpp config (an acmm run or sweep config is named as such: ``acmm validate`` checks it)."""
    from acmm_qpp.configio import read_yaml  # deferred: --help needs no pydantic, yaml

    data, path = read_yaml(config, PACKAGED_CONFIGS)
    kind = CONFIGS.kind_of(data)
    if kind != "qpp":
        raise ConfigError(f"{path}: not a qpp config (it has none of the sections {', '.join(CONFIG_SECTIONS)}): "
                          "an acmm run or sweep config is checked by `acmm validate`")
    cfg = _load(config, overrides)
    typer.echo(f"{cfg.name}: valid ({kind} config)")
    if show:
        typer.echo(cfg.to_yaml())


@app.command(short_help="Print the JSON schema of the qpp config format.",
             cls=help_command(["qpp schema > qpp.schema.json"]))
@user_errors
def schema() -> None:
    """Print the JSON schema of the qpp config format (`acmm schema --kind ...` for the others)."""
    from qpp.io.config import qpp_schema  # deferred: --help needs no scipy, pydantic

    typer.echo(json.dumps(qpp_schema(), indent=2, ensure_ascii=False))


def _mat(a) -> str:
    return np.array2string(np.asarray(a), precision=4, suppress_small=True, max_line_width=120)


@app.command(short_help="H-infinity gains, thresholds and the circle criterion.",
             cls=help_command(["qpp design qpp_unstable", "qpp design qpp_saturation spheres.beta_o=0.4 --strict",
                               "qpp design my_plant.yaml --no-figures"], ("qpp",), CONFIGS))
@user_errors
def design(config: str = ConfigArg, overrides: Optional[list[str]] = overrides_arg("hinf.rho=0.02 spheres.beta_o=0.3"),
           figures: bool = FigOpt,
           strict: bool = StrictOpt) -> None:
    """H∞ gains (ch. 11), β1, thresholds m and the circle criterion (ch. 12.1) → qpp_design.h5.
    Exit 3 when a premise of the certificate (one sector, the Euclidean norm) fails (the best design
    is still written, labelled uncertified); with --strict, a computed sector of φ that its random
    check had to widen exits 1."""
    from qpp.io.stages import printed_H_difference, run_design, sector_verified  # deferred: --help needs no scipy, pydantic

    cfg = _load(config, overrides)
    with _status(f"{cfg.name}: designing (ch. 12.1: H∞ gains, β1, thresholds, circle criterion) ..."):
        cfg, r, path = run_design(cfg, figures)
    typer.echo(f"{cfg.name}: gains from {r.gains_source} (a = {r.a:g} 1/s, T = {r.T:g} s)")
    typer.echo(f"  K1 = {_mat(r.K1)}\n  Kc = {_mat(r.Kc)}\n  H  = {_mat(r.H.T)}ᵀ")
    h_diff = printed_H_difference(cfg, r)
    if h_diff is not None:
        typer.echo(f"  H vs printed: max relative difference {h_diff:.2%}")
    for rd, b in r.beta1.items():
        typer.echo(f"  beta1 [{rd:8s}] = {b['value']:.6f} exact (peak at {b['omega_peak']:.4g} rad/s; "
                   f"grid {b['grid_value']:.6f})")
    verdicts = r.verdicts()
    typer.echo("  report's bookkeeping — reproduction, not a certificate:")
    for t in r.thresholds:
        v = ", ".join(f"{rd}: {'beta1 <= m' if verdicts[(rd, t.name)] else 'beta1 > m'}" for rd in r.beta1)
        typer.echo(f"    m [{t.name:10s}] = {t.m:.5f} (beta3 {t.beta3:.5g}, beta4 {t.beta4:.5g}) -> {v}")
    cc = r.consistent
    typer.echo(f"  certificate (one sector: the circle criterion's; norm: {r.norm}):")
    typer.echo(f"    m = beta_o/(beta_i + beta_o*beta3 + beta4) = {cc.m:.6g} (beta_i {cc.beta_i:.5g}, "
               f"beta3 {cc.beta3:.5g}, beta4 {cc.beta4:.5g}; a lower bound for every T' <= T, least at T' <= "
               f"{cc.T_worst:.4g} s); "
               f"gamma_inf = {r.gamma_inf:.6g}, max E/m <= {cc.E_over_m:.5g}")
    for k, (ok, txt) in r.premises.items():
        typer.echo(f"    [{'holds' if ok else 'FAILS'}] {k}: {txt}")
    c = r.circle
    form = ("lemma 1" if c.method == "gershgorin" else
            f"small-gain form for a coupled phi: rho = {c.gain_bound:.4g}, sup sigma(H_c) = {c.peak_gain:.4g}")
    typer.echo(f"  circle criterion ({form}) on H(-a+jw), sector {np.round(r.sector, 6).tolist()}: "
               f"{'PASS' if c.passed else 'FAIL'}; margins {np.round(c.margins, 4).tolist()}; "
               f"P0 = {c.P0}; largest admissible scale {c.max_scale:.4g}"
               + (f", smallest {c.min_scale:.4g}" if c.min_scale > 0 else ""))
    widened = sector_verified(cfg) is False
    if widened:
        typer.echo("  sector of φ: random check points lay beyond the grid's bounds; the sector was widened to "
                   "the extremum climbed from them (a finer nonlinearity.n_grid samples φ more closely)")
    if r.published is not None:
        pb = r.published
        typer.echo("  printed gains (report's bookkeeping): beta1 " + ", ".join(f"[{rd}] {b['value']:.6f}" for rd, b in pb.beta1.items())
                   + "; " + "; ".join(f"m [{t.name}] = {t.m:.5f} (beta3 {t.beta3:.5g}, beta4 {t.beta4:.5g})"
                                      for t in pb.thresholds))
    typer.echo(f"  procedure 12.1: {len(r.iterations)} evaluations, rho = {r.hinf.rho if r.hinf else float('nan'):g}, "
               f"W_s scale {r.ws_scale or [1.0]}, T settle {r.T_settle:.4g} s")
    if r.late_slope is not None:
        typer.echo(f"  warning: the nonlinearity is stiffer after T = {r.T:.4g} s (slope bound {r.late_slope[1]:.4g}) "
                   f"than within it ({r.late_slope[0]:.4g}): beta3 and beta4 see it only up to T (eqs 10.53-10.54), "
                   f"so the certificate says nothing of the simulation beyond T")
    if r.horizon_note:
        typer.echo(f"  note: {r.horizon_note}")
    if not r.settled and np.isfinite(r.beta1_ref):    # (an unstable loop is named by the verdict)
        cause = (f"the loop's slowest mode settles in {r.T_modal:.4g} s (r_o leaves it unexcited): lengthen "
                 f"simulation.t_final or speed the loop up" if r.T_modal is not None
                 else "does the servo-compensator (plant.Ac) model r_o?")
        typer.echo(f"  warning: the nominal loop does not settle within {r.T_settle:.4g} s (max(spheres.T, "
                   f"simulation.t_final)): T adapts to that horizon, so the certificate depends on t_final; "
                   f"{cause}")
    typer.echo(f"  {r.verdict}")
    typer.echo(f"  wrote {path}")
    if not r.certified:
        raise DesignError(r.verdict + " (best design written, labelled uncertified)", hint=r.hint)
    strict_exit(strict, widened, f"{cfg.name}: the sector of φ rests on a grid its random check found too coarse")


@app.command(short_help="Nonlinear closed loop per scenario and the sphere check.",
             cls=help_command(["qpp simulate qpp_unstable", "qpp simulate qpp_unstable simulation.t_final=5 --strict"], ("qpp",), CONFIGS))
@user_errors
def simulate(config: str = ConfigArg, overrides: Optional[list[str]] = overrides_arg("simulation.t_final=5"),
             figures: bool = FigOpt,
             strict: bool = StrictOpt) -> None:
    """Nonlinear closed loop per scenario and the sphere check ‖y − y_o‖∞ ≤ β_o → qpp_sim.h5.
    The gains are those `qpp design` wrote for this config, else designed first. With --strict, an
    output outside the sphere, or an uncertified design, exits 1."""
    from qpp.io.stages import run_simulate  # deferred: --help needs no scipy, pydantic

    cfg = _load(config, overrides)
    n = len(cfg.simulation.scenarios)
    with _status(f"{cfg.name}: designing (or reusing) the gains (ch. 12.1), then simulating the nominal loop and "
                f"{n} scenario(s) over {cfg.simulation.t_final:g} s ...") as update:
        def tick(done, total, name):
            update(f"{cfg.name}: simulated {done}/{total} scenario(s) (last: {name}) ...")

        cfg, r, sims, path = run_simulate(cfg, figures, progress=tick)
    typer.echo(f"{cfg.name}: beta_o = {cfg.spheres.beta_o:g}; design {r.verdict}")
    if r.horizon_note:
        typer.echo(f"  note: {r.horizon_note}")
    if not r.certified:
        typer.echo("  these are simulations of an UNCERTIFIED design: staying inside the sphere here is "
                   "measured on these scenarios only, not guaranteed")
    y_range = getattr(cfg.nonlinearity, "y_range", None)
    for s in sims:
        g = (", ".join(f"{k} = {v:g}" for k, v in s.parameters.items()) if s.parameters
             else f"gamma = {s.gamma:<8g}")
        broken = s.broken_premises(cfg.spheres.beta_ri, y_range)
        note = f" (outside the certificate's premises: {'; '.join(broken)})" if broken else ""
        if s.diverged_at is not None:
            typer.echo(f"  {s.name:12s} {g} DIVERGED at t = {s.diverged_at:.4g} s: OUTSIDE the output sphere{note}")
            continue
        typer.echo(f"  {s.name:12s} {g} ||y - y_o||inf = {s.error_inf:.5g} "
                   f"(per output {[float(f'{e:.5g}') for e in s.error_per_output]}) "
                   f"{'within' if s.passed else 'OUTSIDE'} the output sphere{note}")
    typer.echo(f"  wrote {path}")
    out = [s.name for s in sims if not s.passed]
    strict_exit(strict, bool(out), f"{cfg.name}: outside the output sphere in {', '.join(out)}")
    strict_exit(strict, not r.certified, f"{cfg.name}: the design is not certified ({r.verdict})")


@app.command(short_help="Redraw a run's figures from its stored results (.h5).",
             cls=help_command(["qpp plot runs/qpp_unstable", "qpp plot runs/qpp_saturation/qpp_sim.h5 --out figures"]))
@user_errors
def plot(target: str = typer.Argument(..., metavar="RUN_DIR_OR_H5",
                                      help="a run folder (runs/<name>) or its qpp_design.h5 / qpp_sim.h5"),
         out: Optional[str] = OutOpt) -> None:
    """Redraw the figures of a qpp run from its stored results alone (nothing is designed or
    simulated again): the same files, with the same names, as the stage that wrote them.
    Exit 2 when RUN_DIR_OR_H5 is missing or holds no qpp results file."""
    from qpp.io.stages import redraw_figures  # deferred: --help needs no scipy, pydantic

    redraw_command(redraw_figures, target, out)


def main() -> None:
    """Console entry point (``qpp``): :func:`acmm_qpp.cli.plumbing.run_app` of the app."""
    run_app(app)


if __name__ == "__main__":     # python -m qpp.cli
    main()
