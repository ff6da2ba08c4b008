"""The ``qpp`` command line end to end (qpp.cli): user configs designed and simulated, bad
configs in one line with exit 2, usage exit codes and --strict, scenarios outside the premises."""
from __future__ import annotations

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from acmm_qpp.errors import EXIT_NUMERICAL, EXIT_USAGE, EXIT_VERDICT, ConfigError
from acmm_qpp.results import read_h5
from qpp.cli import app
from qpp.design.family import REPORT_CERTIFIED
from qpp.design.hinf import hinf_gains
from qpp.design.procedure import weighted_plant
from qpp.io.config import load_config, parse_config

from tests.conftest import invoke

runner = CliRunner()


def _random_config(tmp_path, seed=3):
    rng = np.random.default_rng(seed)
    n = 2
    A = rng.normal(size=(n, n))
    A -= (np.linalg.eigvals(A).real.max() + 1.0) * np.eye(n)      # random stable plant
    B = rng.normal(size=(n, 1))
    return {
        "name": "random_lure",
        "plant": {"A": A.tolist(), "B": B.tolist(), "C": rng.normal(size=(1, n)).tolist(),
                  "G": (B * 10).tolist(), "Ac": [[0.0]], "Bc": [[1.0]], "Cc": [[1.0]]},
        "nonlinearity": {"kind": "sinusoidal", "F0": [[0.3]], "F1": [[0.2]], "F_unc": [[1.0]],
                         "omega": 2.0, "gamma_max": 0.02},
        "hinf": {"rho": 0.01, "a": 1e-6},
        "spheres": {"beta_o": 0.5, "beta_ri": 0.1, "T": 1.0},
        "simulation": {"t_final": 5.0, "n_samples": 501,
                       "r_o": [[{"kind": "step", "amplitude": 1.0}]],
                       "scenarios": [{"name": "offset", "gamma": 0.02,
                                      "delta_r": [[{"kind": "sin", "amplitude": 0.1, "omega": 3.0}]]}]},
        "output": {"root": str(tmp_path / "runs"), "figures": True},
    }


def test_user_config_end_to_end(tmp_path):
    path = tmp_path / "random.yaml"
    path.write_text(yaml.safe_dump(_random_config(tmp_path)))
    r = runner.invoke(app, ["design", str(path)])
    assert r.exit_code == 0, r.output
    d = read_h5(tmp_path / "runs" / "random_lure" / "qpp_design.h5")
    assert d["beta1_eq10_7"] > 0 and d["attrs"]["stage"] == "qpp design"
    # independent: the stored A_z is Hurwitz and built from the stored gains
    assert np.linalg.eigvals(d["Az"]).real.max() < 0
    assert list((tmp_path / "runs" / "random_lure").glob("qpp_circle_ch1.png"))
    r = runner.invoke(app, ["simulate", str(path), "--no-figures"])
    assert r.exit_code == 0, r.output
    s = read_h5(tmp_path / "runs" / "random_lure" / "qpp_sim.h5")
    e = s["offset"]
    assert e["error_inf"] == pytest.approx(np.max(np.abs(e["y"] - e["y_o"])))


def test_bad_config_one_line_exit_2(tmp_path):
    cfg = _random_config(tmp_path)
    cfg["hinf"]["rhoo"] = 1.0
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = runner.invoke(app, ["design", str(path)])
    assert r.exit_code == 2
    assert "hinf.rhoo" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "runs").exists()
    assert runner.invoke(app, ["design", str(tmp_path / "missing.yaml")]).exit_code == 2
    (tmp_path / "broken.yaml").write_text("name: [unclosed")
    assert runner.invoke(app, ["design", str(tmp_path / "broken.yaml")]).exit_code == 2
    with pytest.raises(ConfigError, match="plant.B"):
        c = _random_config(tmp_path)
        c["plant"]["B"] = [[float("nan")], [1.0]]
        parse_config(c)


@pytest.mark.parametrize("edit, field", [
    (lambda c: c["spheres"].__setitem__("T", float("inf")), "spheres.T"),
    (lambda c: c["spheres"].__setitem__("T", 1e9), "spheres.T"),
    (lambda c: c["plant"].__setitem__("x0", [float("nan"), 0.0]), "plant.x0"),
    (lambda c: c["simulation"].__setitem__("n_samples", True), "simulation.n_samples"),   # no count
])
def test_non_finite_or_huge_values_rejected_before_any_work(tmp_path, edit, field):
    cfg = _random_config(tmp_path)
    edit(cfg)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(cfg))
    for cmd in ("design", "simulate"):
        r = runner.invoke(app, [cmd, str(path)])
        assert r.exit_code == 2, r.output
        assert field in r.output and "Traceback" not in r.output
    assert not (tmp_path / "runs").exists()


@pytest.mark.slow     # a qpp_saturation design (~12 s)
def test_expression_scenarios_store_their_parameters_not_a_gamma(tmp_runs):
    """An expression's scenario stored ``gamma`` = its first parameter beside ``param_k`` (a
    review: γ = 4.2 for k = 4.2); γ belongs to the sinusoidal kind only."""
    import h5py

    from qpp.cli import app

    r = runner.invoke(app, ["simulate", "qpp_saturation", "--no-figures", "simulation.n_samples=201",
                            "simulation.t_final=4"])
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_runs / "runs" / "qpp_saturation" / "qpp_sim.h5") as f:
        attrs = dict(f["k_max_step/error_inf"].attrs)
    assert "gamma" not in attrs and attrs["param_k"] == pytest.approx(4.2)


def test_the_horizon_too_long_names_the_field_that_set_it(tmp_runs):
    from qpp.cli import app

    r = runner.invoke(app, ["design", "qpp_saturation", "spheres.T=1e4", "spheres.adapt_T=false"])
    assert r.exit_code == 2 and r.output.strip().startswith("error: spheres.T: 10000 s is too long"), r.output


@pytest.mark.slow
def test_a_nonlinearity_faster_than_the_work_bound_can_see_is_stopped(tmp_runs, monkeypatch):
    """A t inside an expression nonlinearity (sin(1e6·t)) escaped the static work bound
    (t_final × the loop's rates): the simulation ran on for minutes (a review).  The integration
    now counts its right-hand-side evaluations against QPP_RHS_EVALS (here lowered to 40 000;
    the example itself takes ~15 000, so it still runs under it)."""
    from qpp.cli import app

    monkeypatch.setenv("ACMM_LIMIT_QPP_RHS_EVALS", "40000")
    r = runner.invoke(app, ["simulate", "qpp_cubic2", "--no-figures"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["simulate", "qpp_cubic2", "name=fast_t", "--no-figures",
                            'nonlinearity.f1=["-c*y1*sin(1e6*t)", "0"]'])
    assert r.exit_code == 2, r.output
    assert r.output.strip().startswith("error: simulation.t_final: the integration reached t =")
    assert "ACMM_LIMIT_QPP_RHS_EVALS" in r.output and len(r.output.strip().splitlines()) == 1
    assert not (tmp_runs / "runs" / "fast_t").exists()


def test_the_apps_run_as_modules(tmp_path):
    import subprocess
    import sys

    for mod, conf in (("acmm.cli.app", "mb3"), ("qpp.cli", "qpp_siso")):
        p = subprocess.run([sys.executable, "-m", mod, "validate", conf], capture_output=True, text=True,
                           cwd=tmp_path, timeout=120)
        assert p.returncode == 0 and "valid" in p.stdout, (mod, p.stdout, p.stderr)


@pytest.mark.slow
def test_a_scenario_outside_the_premises_says_so(tmp_runs):
    """‖δr‖∞ = 5 ≫ β_ri and y beyond y_range: the run leaves the sphere, and the output says
    the certificate never spoke about it (it read like a broken certificate; review)."""
    import h5py

    from qpp.cli import app

    big = "simulation.scenarios=[{name: big, parameters: {k: 4.2}, delta_r: [[{kind: step, amplitude: 5.0, t_on: 3.0}]]}]"
    r = runner.invoke(app, ["simulate", "qpp_saturation", "--no-figures", "simulation.n_samples=401", big])
    assert r.exit_code == 0, r.output
    line = next(ln for ln in r.output.splitlines() if ln.strip().startswith("big"))
    assert "OUTSIDE the output sphere (outside the certificate's premises: ||r - r_o||inf = 5 > beta_ri = 0.05" in line
    assert "y1 leaves y_range [-3, 3]" in line
    with h5py.File(tmp_runs / "runs" / "qpp_saturation" / "qpp_sim.h5") as f:
        assert f["big/error_inf"].attrs["premises_held"] == 0
    r = runner.invoke(app, ["simulate", "qpp_saturation", "--no-figures", "simulation.n_samples=401"])
    assert "premises" not in r.output
    with h5py.File(tmp_runs / "runs" / "qpp_saturation" / "qpp_sim.h5") as f:
        assert all(f[k]["error_inf"].attrs["premises_held"] == 1 for k in f if isinstance(f[k], h5py.Group))
        # one kind of flag in every file (they were numpy bools, int64 and HDF5 enums): int8 0/1
        flags = [f[k]["error_inf"].attrs[a] for k in f if isinstance(f[k], h5py.Group) for a in ("passed", "premises_held")]
    assert runner.invoke(app, ["design", "qpp_saturation", "--no-figures"]).exit_code == 0
    with h5py.File(tmp_runs / "runs" / "qpp_saturation" / "qpp_design.h5") as f:
        flags += [f.attrs[a] for a in f.attrs if a in ("certified", "circle_passed") or a.startswith("beta1_le_m")]
        # tables of mixed columns: units per column that pint parses (they said "mixed", "bool")
        from acmm_qpp.units import parse_unit

        for name in ("iterations", "hinf_search"):
            if name in f:
                d = f[name]
                units = d.attrs["column_units"]
                units = (units.decode() if isinstance(units, bytes) else units).split(",")
                assert d.attrs["units"] == "column_units[j]" and len(units) == d.shape[1]
                [parse_unit(u) for u in units]
    assert len(flags) > 4 and all(np.asarray(v).dtype == np.int8 for v in flags), [np.asarray(v).dtype for v in flags]


def test_gains_that_destabilize_the_loop_are_named_as_such(tmp_runs):
    """Published gains K1 = [1, 1], Kc = [1, 1], H = [1; 1] on the ch. 13 plant: the verdict blamed
    'the circle criterion for every a tried' (one a was tried) and a loop that 'does not settle'
    (review); the cause is a closed loop with a pole in the right half plane."""
    from qpp.cli import app

    r = runner.invoke(app, ["design", "qpp_siso", "design.gains=published", "published.K1=[[1,1]]",
                            "published.Kc=[[1,1]]", "published.H=[[1],[1]]"])
    assert r.exit_code == 3, r.output
    assert "limiting factor: the closed loop of these gains is unstable (largest Re λ(A_z) = " in r.output
    assert "does not settle" not in r.output
    assert "hint: these gains do not stabilize the plant" in r.output      # exit 3 ends with a hint


def qpp(*args):
    from qpp.cli import app

    return invoke(app, *args)


def one_line(r):
    err = r.stderr.strip()
    return err.count("\n") == 0 and "Traceback" not in r.output


def test_qpp_usage_exit_codes():
    r = qpp("design")
    assert r.exit_code == EXIT_USAGE and one_line(r)
    r = qpp("design", "qpp_siso", "--nope")
    assert r.exit_code == EXIT_USAGE and one_line(r)


@pytest.mark.slow
def test_strict_sphere_violation(tmp_runs):
    args = ("simulate", "qpp_siso", "spheres.beta_o=0.03", "simulation.t_final=2",
            "simulation.n_samples=401", f"output.root={tmp_runs / 'runs'}", "--no-figures")
    r = qpp(*args)
    assert r.exit_code == 0 and "OUTSIDE the output sphere" in r.stdout
    r = qpp(*args, "--strict")
    assert r.exit_code == EXIT_VERDICT and one_line(r) and "outside the output sphere" in r.stderr


def test_a_printed_H_of_zeros_is_no_difference_to_report(tmp_path):
    from typer.testing import CliRunner

    from qpp.cli import app

    r = CliRunner().invoke(app, ["design", "qpp_siso", f"output.root={tmp_path}", "--no-figures",
                                 "published.H=[[0],[0]]"])
    assert r.exit_code in (0, 3), r.output
    assert "Traceback" not in r.output and (r.exception is None or isinstance(r.exception, SystemExit))
    assert (tmp_path / "qpp_siso" / "qpp_design.h5").is_file()
    assert yaml.safe_load((tmp_path / "qpp_siso" / "config.yaml").read_text())["name"] == "qpp_siso"


# ---------------------------------------------------------------------------------------------
# issue 34: help with examples and the packaged configs; qpp plot
# ---------------------------------------------------------------------------------------------
QPP_COMMANDS = ("validate", "schema", "design", "simulate", "plot")


@pytest.mark.parametrize("command", ("",) + QPP_COMMANDS)
def test_every_help_has_an_example_and_no_truncated_summary(command):
    from tests.conftest import CONFIGS

    r = invoke(app, *([command] if command else []), "--help")
    assert r.exit_code == 0, r.output
    assert r.output.split("Examples:")[1].strip().startswith(f"qpp {command}".strip())
    assert "…" not in r.output
    if command in ("", "validate", "design", "simulate"):
        listed = " ".join(r.output.split("Packaged configs")[1].split(":", 1)[1].split("\n\n")[0].split())
        assert [x.strip() for x in listed.split(",")] == sorted(p.stem for p in CONFIGS.glob("qpp_*.yaml"))
    if not command:
        summaries = r.output.split("Commands:")[1].split("Examples:")[0].strip().splitlines()
        assert sorted(x.split()[0] for x in summaries) == sorted(QPP_COMMANDS)
        assert not any(x.rstrip().endswith("...") for x in summaries)
    if command in ("validate", "design", "simulate"):       # the override example is valid for it
        from qpp.io.config import load_config

        example = " ".join(r.output.split("e.g.")[1].split("(validated")[0].split()).split()
        assert "simulation.orbits=10" not in example
        load_config("qpp_siso", example)


@pytest.mark.slow     # a qpp_unstable design and simulation (~12 s); acmm plot's pixel test stays fast
def test_plot_redraws_the_design_and_simulation_figures_pixel_for_pixel(tmp_path):
    import matplotlib.image as mpimg

    root = tmp_path / "runs"
    for stage in ("design", "simulate"):
        r = invoke(app, stage, "qpp_unstable", f"output.root={root}", "simulation.t_final=2", "--figures")
        assert r.exit_code == 0, r.output
    run = root / "qpp_unstable"
    made = sorted(p.name for p in run.glob("*.png"))
    assert {"qpp_circle_ch1.png", "qpp_iterations.png"} <= set(made) and len(made) >= 4
    r = invoke(app, "plot", run, "--out", tmp_path / "again")
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "again").glob("*.png")) == made
    for name in made:
        a, b = mpimg.imread(run / name), mpimg.imread(tmp_path / "again" / name)
        assert a.shape == b.shape and np.abs(a - b).max() == 0.0, name
    for bad in (tmp_path / "nowhere", run / "config.yaml", tmp_path):
        r = invoke(app, "plot", bad)
        assert r.exit_code == 2 and r.stderr.strip().count("\n") == 0 and r.stderr.startswith("error: ")


def test_the_verdict_names_what_is_proved_and_what_is_assumed(tmp_runs):
    """A certified verdict ends with what is proved (for t in [0, T]) and what is assumed (issue 43:
    'certified' read like a proof of everything); the same words in qpp_design.h5.  An uncertified
    verdict claims no proof (qpp_cubic2 ~5 s, qpp_siso ~1 s)."""
    import h5py

    from qpp.cli import app

    r = runner.invoke(app, ["design", "qpp_cubic2", "--no-figures"])
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_runs / "runs" / "qpp_cubic2" / "qpp_design.h5") as f:
        a = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    assert a["certified"] == 1
    assert a["proved"] == ("sector and slope (interval branch and bound); y_o +- beta_o inside y_range (enclosure); "
                           "circle criterion (KYP lemma); beta4 and m for every T' in (0, T] (the nominal loop "
                           "enclosed on cells)")
    assert "trapezoid" not in a["assumed"] and "trapezoid" not in a["proved"]
    assert a["assumed"] == ("floating-point evaluation (eigenvalues, H-infinity norm, Gramian, the nominal loop's "
                            "matrix exponential)")
    assert a["scope"].startswith("proved for t in [0, T]: sector and slope") and "; assumed: " in a["scope"]
    assert a["verdict"].startswith("certified") and a["verdict"].endswith(a["scope"])
    verdict = next(ln.strip() for ln in r.output.splitlines() if ln.strip().startswith("certified"))
    assert verdict == a["verdict"]
    # T (1 s) ends before the nominal loop settles: the output says the certificate covers [0, T] only
    d = read_h5(tmp_runs / "runs" / "qpp_cubic2" / "qpp_design.h5")
    T, Ts = float(d["T"]), float(d["certificate"]["T_settle"])
    assert T == 1.0 and Ts > 1.1 * T
    assert (f"note: T = {T:.4g} s ends before the nominal loop settles ({Ts:.4g} s): the certificate covers "
            f"[0, T] only") in r.output, r.output
    r = runner.invoke(app, ["design", "qpp_siso", "--no-figures"])
    assert r.exit_code == EXIT_NUMERICAL, r.output
    with h5py.File(tmp_runs / "runs" / "qpp_siso" / "qpp_design.h5") as f:
        verdict = f.attrs["verdict"]
        verdict = verdict.decode() if isinstance(verdict, bytes) else verdict
        assert f.attrs["certified"] == 0
    assert verdict.startswith("no certified design") and "proved for" not in verdict
    assert "assumed:" not in verdict and "proved for" not in r.output
    # no certificate: the note says what was evaluated, not what a certificate covers
    assert "ends before the nominal loop settles" in r.output and "the premises were evaluated on [0, T] only" in r.output
    assert "the certificate covers" not in r.output


def test_the_packaged_certified_ch13_design_is_certified_on_its_horizon(tmp_runs):
    """qpp_siso_certified (issue 43): ch. 13's procedure at ρ = 3.5e-4 with T = 0.25 s fixed,
    certified (exit 0), its gains those of hinf_gains at the config's ρ, a; the output and
    qpp_design.h5 say that T ends before the loop settles, and that φ = 10 Δm y sin t is stiffer
    after T (slope 0.5·sin(0.25) within, 0.5 after).  ``hinf.w`` reaches the design: the
    family's stiff design of qpp.design.family.REPORT_CERTIFIED through the same config."""
    r = runner.invoke(app, ["design", "qpp_siso_certified", "--no-figures"])
    assert r.exit_code == 0, r.output
    d = read_h5(tmp_runs / "runs" / "qpp_siso_certified" / "qpp_design.h5")
    assert d["attrs"]["certified"] == 1 and float(d["T"]) == 0.25
    cfg = load_config("qpp_siso_certified")
    assert (cfg.hinf.rho, cfg.hinf.w, cfg.hinf.a) == (3.5e-4, 1.0, 1e-8)
    g = hinf_gains(cfg.lure_plant(), rho=3.5e-4, a=1e-8)
    for k, v in (("K1", g.K1), ("Kc", g.Kc), ("H", g.H)):
        assert np.asarray(d[k]) == pytest.approx(np.asarray(v), rel=1e-9), k
    Ts = float(d["certificate"]["T_settle"])
    note = (f"T = 0.25 s ends before the nominal loop settles ({Ts:.4g} s): the certificate covers [0, T] "
            f"only, not the settling")
    assert Ts > 2 * 0.25 and note in r.output and d["attrs"]["horizon_note"].startswith(note), r.output
    assert (f"stiffer after T = 0.25 s (slope bound 0.5) than within it ({0.5 * np.sin(0.25):.4g})"
            in r.output), r.output
    rho, w, a = REPORT_CERTIFIED["qpp_siso"]
    r = runner.invoke(app, ["design", "qpp_siso_certified", f"hinf.rho={rho}", f"hinf.w={w}", f"hinf.a={a}",
                            "spheres.T=0.0125", "simulation.t_final=1", "name=stiff", "--no-figures"])
    assert r.exit_code == 0, r.output
    g = hinf_gains(weighted_plant(cfg.lure_plant(), w), rho=rho, a=a)
    d = read_h5(tmp_runs / "runs" / "stiff" / "qpp_design.h5")
    assert np.asarray(d["Kc"]) == pytest.approx(np.asarray(g.Kc), rel=1e-9)
