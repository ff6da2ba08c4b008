"""Issue 14 (items 2, 3, 7, 8, 9): command-line overrides and config.yaml, stale outputs, JSON
schemas of the three config kinds, error hints, exit codes, --strict, help text, progress."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from acmm.io.config import load_config, parse_config
from acmm_qpp.errors import EXIT_INPUT, EXIT_NUMERICAL, EXIT_USAGE, EXIT_VERDICT, ConfigError
from acmm_qpp.results import read_h5

from tests.conftest import CONFIGS, invoke
from tests.conftest import REPO


def acmm(*args):
    from acmm.cli.app import app

    return invoke(app, *args)


def qpp(*args):
    from qpp.cli import app

    return invoke(app, *args)


def one_line(r):
    err = r.stderr.strip()
    return err.count("\n") == 0 and "Traceback" not in r.output


# ---------------------------------------------------------------------------------------------
# item 2: overrides, config.yaml, a rerun replaces the stage's outputs
# ---------------------------------------------------------------------------------------------
def test_override_changes_the_design_and_is_recorded(tmp_runs):
    r = acmm("design", "mb3", "design.sector.sigma=1.2", "design.sector.half_angle_deg=30", "--no-figures")
    assert r.exit_code == 0, r.output
    run = tmp_runs / "runs" / "mb3"
    d = read_h5(run / "design.h5")
    n = load_config("mb3").orbit_rate
    poles = d["points"]["000_mb3"]["poles"]
    # independent check of the overridden sector on the stored poles: Re λ ≤ −1.2 n, |Im| ≤ tan 30°|Re|
    assert np.all(poles.real <= -1.2 * n * (1 - 1e-9))
    assert np.all(np.abs(poles.imag) <= np.tan(np.radians(30)) * np.abs(poles.real) * (1 + 1e-9))
    # the file's own sector (σ = 0.5) gives a slower closed loop: the override changed the result
    r0 = acmm("design", "mb3", "--no-figures")
    assert r0.exit_code == 0
    assert read_h5(run / "design.h5")["points"]["000_mb3"]["poles"].real.max() > -1.2 * n
    # config.yaml: the resolved config headed by the overrides of the run that wrote it
    r = acmm("design", "mb3", "design.sector.sigma=0.9", "--no-figures")
    text = (run / "config.yaml").read_text()
    assert "# command-line overrides: design.sector.sigma=0.9" in text
    resolved = parse_config(yaml.safe_load(text))
    assert resolved.design.sector.sigma == 0.9
    assert resolved == load_config("mb3", ["design.sector.sigma=0.9"])
    assert yaml.safe_load(read_h5(run / "design.h5")["attrs"]["config"])["design"]["sector"]["sigma"] == 0.9


def test_override_simulation_orbits_and_list_values(tmp_runs):
    r = acmm("simulate", "mb3", "simulation.orbits=0.5", "simulation.initial_offset=[0, 2, 0]", "--no-figures")
    assert r.exit_code == 0, r.output
    s = read_h5(tmp_runs / "runs" / "mb3" / "sim.h5")
    assert s["orbits"][-1] == pytest.approx(0.5, rel=1e-9)
    # initial attitude error = the overridden offset (deg), pitch only
    np.testing.assert_allclose(np.degrees(s["attitude_error"][0]), [0, 2, 0], atol=1e-9)
    cfg = yaml.safe_load((tmp_runs / "runs" / "mb3" / "config.yaml").read_text())
    assert cfg["simulation"]["orbits"] == 0.5 and cfg["simulation"]["initial_offset"] == [0.0, 2.0, 0.0]


def test_override_on_the_default_config_and_removal():
    cfg = load_config(None, ["simulation.orbits=3", "~schedule"])
    assert cfg.name == "staircase" and cfg.simulation.orbits == 3 and cfg.schedule is None
    # a unit string is a YAML scalar like any other, converted by the loader
    assert load_config("mb3", ["actuators.torque_limit=203.4 N*m"]).actuators.torque_limit == \
        pytest.approx(150.0, rel=1e-3)


def test_bad_override_key_is_reported_like_the_file(tmp_runs):
    r = acmm("simulate", "mb3", "simulation.orbts=10")
    assert r.exit_code == EXIT_INPUT and one_line(r)
    assert "simulation.orbts: unknown key (did you mean `orbits`?)" in r.stderr
    r = acmm("simulate", "mb3", "simulation.orbits=-1")
    assert r.exit_code == EXIT_INPUT and "simulation.orbits" in r.stderr and one_line(r)
    r = acmm("simulate", "mb3", "orbits10")            # not key=value: a usage error
    assert r.exit_code == EXIT_USAGE and one_line(r) and "orbits10" in r.stderr
    assert not (tmp_runs / "runs").exists()


def test_overrides_for_qpp_and_sweep(tmp_runs):
    from acmm.sweep.config import load_sweep
    from qpp.io.config import load_config as load_qpp

    assert load_qpp("qpp_siso", ["hinf.rho=2e-4"]).hinf.rho == 2e-4
    sw = load_sweep("sweep_smoke", ["sweep.n_runs=3", "sweep.orbits=1"])
    assert sw.spec.n_cases() == 3 and sw.spec.orbits == 1
    with pytest.raises(ConfigError, match=r"sweep\.n_run: unknown key \(did you mean `n_runs`\?\)"):
        load_sweep("sweep_smoke", ["sweep.n_run=3"])
    r = qpp("validate", "qpp_siso", "spheres.beta_o=0.3", "--show")
    assert r.exit_code == 0 and "beta_o: 0.3" in r.stdout


def test_rerun_replaces_the_stage_outputs_only(tmp_runs):
    run = tmp_runs / "runs" / "mb3"
    r = acmm("simulate", "mb3", "simulation.orbits=0.3")
    assert r.exit_code == 0, r.output
    assert {"sim_axes.png", "sim_summary.png", "design_poles.png"} <= {p.name for p in run.iterdir()}
    (run / "notes.txt").write_text("mine")
    r = acmm("simulate", "mb3", "simulation.orbits=0.4", "--no-figures")
    assert r.exit_code == 0, r.output
    names = {p.name for p in run.iterdir()}
    assert not any(n.startswith("sim_") for n in names), names     # no stale simulation figures
    assert {"sim.h5", "design.h5", "design_poles.png", "notes.txt", "config.yaml"} <= names
    # a failing rerun removes nothing and leaves the previous config.yaml
    before = (run / "config.yaml").read_text()
    assert acmm("simulate", "mb3", "design.residual_tol=1e-40").exit_code == EXIT_NUMERICAL
    assert (run / "sim.h5").exists() and (run / "config.yaml").read_text() == before


# ---------------------------------------------------------------------------------------------
# item 3: JSON schemas
# ---------------------------------------------------------------------------------------------
def _schema(kind):
    r = acmm("schema", "--kind", kind)
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def schemas():
    import jsonschema

    out = {}
    for kind in ("acmm", "sweep", "qpp"):
        s = _schema(kind)
        jsonschema.Draft202012Validator.check_schema(s)
        out[kind] = jsonschema.Draft202012Validator(s)
    r = qpp("schema")
    assert json.loads(r.stdout) == out["qpp"].schema
    return out


def test_every_packaged_config_validates_against_its_schema(schemas):
    from acmm.cli.configkinds import load_any
    from acmm_qpp.configio import detect_kind

    paths = sorted(CONFIGS.glob("*.yaml"))
    assert len(paths) >= 9
    for p in paths:
        data = yaml.safe_load(p.read_text())
        kind = detect_kind(data)
        errors = [e.message for e in schemas[kind].iter_errors(data)]
        assert errors == [], (p.name, errors)
        assert load_any(p)[0] == kind


def _mb3():
    return yaml.safe_load((CONFIGS / "mb3.yaml").read_text())


def _variants_ok():
    a = _mb3()
    a["inertia"] = {"I11": "31.48e6 kg*m^2", "I22": "1.76e6 kg*m^2", "I33": "31.5e6 kg*m^2"}
    a["actuators"] = {"torque_limit": "200 N*m", "momentum_limit": 20000}
    a["disturbance"]["A"] = ["1 N*m", 2.0, "1.5 ft*lbf"]
    a["orbit_rate"] = "0.063 deg/s"
    b = _mb3()
    m = [[23.22e6, -0.023e6, 0.477e6], [-0.023e6, 1.30e6, -0.011e6], [0.477e6, -0.011e6, 23.23e6]]
    b["inertia"] = m
    c = _mb3()
    c["sweep"] = {"grid": {"inertia_scale": [0.9, 1.1]}, "tea_estimate": True}
    return [("acmm", a), ("acmm", b), ("sweep", c)]


def _variants_bad():
    out = []
    for edit in (lambda d: d["simulation"].__setitem__("orbit", 3),            # unknown key
                 lambda d: d.__setitem__("inertia", {"Ixx": 1.0, "I22": 2.0, "I33": 2.0}),
                 lambda d: d["design"].__setitem__("riccati_method", "newton"),   # not an enum value
                 lambda d: d["actuators"].__setitem__("torque_limit", "lots"),    # not a quantity
                 lambda d: d["simulation"].__setitem__("initial_offset", [0, 1]),  # two values
                 lambda d: d["design"]["sector"].__setitem__("sigma", -1),        # bound
                 lambda d: d.pop("name")):                                       # required
        d = _mb3()
        edit(d)
        out.append(("acmm", d))
    s = yaml.safe_load((CONFIGS / "sweep_smoke.yaml").read_text())
    s["sweep"]["n_runz"] = 3
    out.append(("sweep", s))
    s = _mb3()
    s["sweep"] = {"base": "ac", "grid": {"inertia_scale": [1.0]}}       # inline section with a base
    out.append(("sweep", s))
    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["hinf"]["rhoo"] = 1
    out.append(("qpp", q))
    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["nonlinearity"]["kind"] = "cubic"
    out.append(("qpp", q))
    return out


def test_schema_accepts_what_the_loader_accepts(schemas, tmp_path):
    from acmm.cli.configkinds import load_any

    for k, (kind, data) in enumerate(_variants_ok()):
        assert [e.message for e in schemas[kind].iter_errors(data)] == [], (k, kind)
        p = tmp_path / f"ok{k}.yaml"
        p.write_text(yaml.safe_dump(data))
        assert load_any(p)[0] == kind
    for k, (kind, data) in enumerate(_variants_bad()):
        assert list(schemas[kind].iter_errors(data)), (k, kind, data)
        p = tmp_path / f"bad{k}.yaml"
        p.write_text(yaml.safe_dump(data))
        with pytest.raises(ConfigError):
            load_any(p)


def test_validate_detects_every_kind(tmp_runs):
    for name, kind in (("mb3", "acmm"), ("sweep_smoke", "sweep"), ("qpp_siso", "qpp")):
        r = acmm("validate", name)
        assert r.exit_code == 0, r.output
        assert f"valid ({kind} config)" in r.stdout
    r = qpp("validate", "qpp_siso")
    assert r.exit_code == 0 and "valid (qpp config)" in r.stdout, r.output
    for name, kind in (("mb3", "acmm"), ("sweep_smoke", "sweep")):   # qpp imports nothing of acmm
        r = qpp("validate", name)
        assert r.exit_code == EXIT_INPUT and f"an {kind} config" in r.stderr and "acmm validate" in r.stderr
    r = acmm("validate", CONFIGS / "sweep_smoke.yaml", "sweep.map=[dI11]")
    assert r.exit_code == EXIT_INPUT and "sweep.map" in r.stderr and one_line(r)


# ---------------------------------------------------------------------------------------------
# item 7: hints
# ---------------------------------------------------------------------------------------------
def test_unknown_key_hints(tmp_path):
    d = _mb3()
    d["inertia"] = {"Ixx": 23.22e6, "I22": 1.30e6, "I33": 23.23e6}
    with pytest.raises(ConfigError, match=r"inertia\.Ixx: unknown key \(valid keys: I11, I22"):
        parse_config(d)
    d = _mb3()
    d["simulaton"] = {"orbits": 2}
    with pytest.raises(ConfigError, match=r"simulaton: unknown key \(did you mean `simulation`\?\)"):
        parse_config(d)
    from qpp.io.config import parse_config as parse_qpp

    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["nonlinearity"]["omgea"] = 1.0
    with pytest.raises(ConfigError, match=r"did you mean `omega`"):
        parse_qpp(q)


def test_missing_packaged_name_lists_the_packaged_configs(tmp_runs):
    r = acmm("tea", "mb4")
    assert r.exit_code == EXIT_INPUT and one_line(r)
    assert "did you mean `mb3`" in r.stderr
    for name in ("ac", "mb3", "staircase", "qpp_siso", "sweep_smoke"):
        assert name in r.stderr


def test_a_typed_path_is_never_taken_for_a_packaged_name(tmp_runs):
    """``./mb3`` next to a run folder ``mb3`` is that folder (one line, exit 2, nothing written),
    for every command taking a config; the bare ``mb3`` is the packaged config."""
    (tmp_runs / "mb3").mkdir()
    for run, args in ((acmm, ("design", "./mb3", "--no-figures")), (acmm, ("validate", "./mb3")),
                      (qpp, ("design", "./mb3")), (acmm, ("sweep", "./mb3"))):
        r = run(*args)
        assert r.exit_code == EXIT_INPUT and one_line(r), (args, r.output)
        assert "directory, not a file: ./mb3" in r.stderr
    assert not (tmp_runs / "runs").exists()
    assert acmm("tea", "mb3").exit_code == 0


def test_an_empty_config_path_or_report_folder_is_one_line(tmp_runs):
    """``acmm tea ""`` said "config path is a directory, not a file:" and nothing more;
    ``acmm report --out ""`` wrote the report into the working directory."""
    r = acmm("tea", "")
    assert r.exit_code == EXIT_INPUT and one_line(r) and "config path is empty" in r.stderr
    r = acmm("report", "--out", "")
    assert r.exit_code == EXIT_INPUT and one_line(r) and "--out: empty" in r.stderr
    assert sorted(p.name for p in tmp_runs.iterdir()) == []


def test_an_override_with_a_line_break_keeps_config_yaml_valid(tmp_runs):
    """The overrides are echoed in config.yaml's comment header: a line break inside one used to
    end the comment and break the file."""
    r = acmm("tea", "mb3", 'description="x\n  name: evil"')
    assert r.exit_code == 0, r.output
    cfg = load_config(str(tmp_runs / "runs" / "mb3" / "config.yaml"))
    assert cfg.name == "mb3" and cfg.description == "x name: evil"


def test_validate_reads_schedule_to_from_the_configs_folder(tmp_runs):
    """``schedule.to: ends/acv.yaml`` is relative to the config's folder for ``acmm validate`` as
    for the stages (validate read it from the working directory: a good config refused)."""
    folder = tmp_runs / "x"
    (folder / "ends").mkdir(parents=True)
    (folder / "ends" / "acv.yaml").write_text((CONFIGS / "ac.yaml").read_text())
    data = yaml.safe_load((CONFIGS / "staircase.yaml").read_text())
    data["schedule"]["to"] = "ends/acv.yaml"
    (folder / "sub.yaml").write_text(yaml.safe_dump(data))
    r = acmm("validate", str(folder / "sub.yaml"))
    assert r.exit_code == 0, r.output
    assert acmm("tea", str(folder / "sub.yaml")).exit_code == 0


def test_numerical_failure_says_which_setting_to_change(tmp_runs):
    r = acmm("design", "mb3", "design.residual_tol=1e-40", "--no-figures")
    assert r.exit_code == EXIT_NUMERICAL and one_line(r)
    assert "hint:" in r.stderr and "design.residual_tol" in r.stderr
    r = acmm("design", "mb3", "design.sector.sigma=50", "--no-figures")
    assert r.exit_code == EXIT_NUMERICAL and one_line(r) and "hint: lower design.sector.sigma" in r.stderr
    r = acmm("tea", "mb3", "disturbance.bias=[0, 4, 0]", "~disturbance.bias_from_tea")
    assert r.exit_code == EXIT_INPUT and one_line(r)
    assert "hint:" in r.stderr and "disturbance.bias" in r.stderr


# ---------------------------------------------------------------------------------------------
# item 8: CLI conventions and exit codes
# ---------------------------------------------------------------------------------------------
def test_version_and_completion():
    import importlib.metadata as md

    for run in (acmm, qpp):
        r = run("--version")
        assert r.exit_code == 0 and md.version("acmm-qpp") in r.stdout
        assert "--install-completion" in run("--help").stdout


def test_help_renders_extras_literally():
    r = acmm("sweep", "--help")
    assert r.exit_code == 0 and "acmm-qpp[dask]" in r.stdout


@pytest.mark.parametrize("args, code", [
    (("simulate", "mb3", "--bogus"), EXIT_USAGE),          # unknown option
    (("nosuchcommand",), EXIT_USAGE),                      # unknown command
    (("sweep",), EXIT_USAGE),                              # missing argument
    (("tea", "mb3", "stray"), EXIT_USAGE),                 # stray positional word
    (("sweep", "sweep_smoke", "-j", "0"), EXIT_INPUT),    # bad option value
    (("schema", "--kind", "yaml"), EXIT_INPUT),           # bad option value
    (("validate", "missing_file.yaml"), EXIT_INPUT),      # config error
])
def test_exit_codes_one_line(tmp_runs, args, code):
    r = acmm(*args)
    assert r.exit_code == code, (r.exit_code, r.output)
    assert one_line(r) and r.stderr.startswith("error: ")


def test_qpp_usage_exit_codes():
    r = qpp("design")
    assert r.exit_code == EXIT_USAGE and one_line(r)
    r = qpp("design", "qpp_siso", "--nope")
    assert r.exit_code == EXIT_USAGE and one_line(r)


def test_strict_diverged_verdict(tmp_runs):
    args = ("simulate", "mb3_decoupled", "simulation.orbits=0.2", "--no-figures")
    r = acmm(*args)
    assert r.exit_code == 0 and "DIVERGED" in r.stdout
    r = acmm(*args, "--strict")
    assert r.exit_code == EXIT_VERDICT and "DIVERGED" in r.stdout and one_line(r)
    assert (tmp_runs / "runs" / "mb3_decoupled" / "sim.h5").exists()     # the result is still written
    r = acmm("simulate", "mb3", "simulation.orbits=0.3", "--no-figures", "--strict")
    assert r.exit_code == 0, r.output


def test_strict_sector_violation(tmp_runs):
    # the shipped 4th-order schedule leaves some scheduled poles outside the sector (README)
    args = ("design", "staircase", "schedule.n_points=6", "--no-figures")
    r = acmm(*args)
    assert r.exit_code == 0 and "NOT all in the sector" in r.stdout
    r = acmm(*args, "--strict")
    assert r.exit_code == EXIT_VERDICT and one_line(r) and "sector" in r.stderr
    r = acmm("design", "mb3", "--no-figures", "--strict")        # one LQR point: in the sector by design
    assert r.exit_code == 0, r.output


@pytest.mark.slow
def test_strict_sphere_violation(tmp_runs):
    args = ("simulate", "qpp_siso", "spheres.beta_o=0.03", "simulation.t_final=2",
            "simulation.n_samples=401", f"output.root={tmp_runs / 'runs'}", "--no-figures")
    r = qpp(*args)
    assert r.exit_code == 0 and "OUTSIDE the output sphere" in r.stdout
    r = qpp(*args, "--strict")
    assert r.exit_code == EXIT_VERDICT and one_line(r) and "outside the output sphere" in r.stderr


# ---------------------------------------------------------------------------------------------
# item 9: progress only on a terminal
# ---------------------------------------------------------------------------------------------
def test_progress_silent_without_terminal_and_shown_when_forced(tmp_runs, monkeypatch):
    quiet = acmm("design", "staircase", "schedule.n_points=4", "--no-figures")
    assert quiet.exit_code == 0 and quiet.stderr == ""
    monkeypatch.setenv("ACMM_PROGRESS", "1")
    loud = acmm("design", "staircase", "schedule.n_points=4", "--no-figures")
    assert loud.exit_code == 0
    assert "designed" in loud.stderr or "fitting the schedule" in loud.stderr
    # stdout (the results) is the same with and without progress, up to the wall time
    strip = lambda s: [x for x in s.splitlines() if "design point(s)" not in x]  # noqa: E731
    assert strip(loud.stdout) == strip(quiet.stdout)


def test_numba_compile_detection_does_not_fail():
    from acmm.cli.compile_note import numba_needs_compile

    assert numba_needs_compile() in (True, False)


def test_override_paths_and_errors():
    from acmm_qpp.overrides import OverrideSyntaxError, apply_overrides

    data = {"a": {"b": [1, 2, 3]}, "c": 1}
    out = apply_overrides(data, ["a.b.1=5", "d.e=x", "~c", "~no.such", "a.f="])
    assert out == {"a": {"b": [1, 5, 3], "f": None}, "d": {"e": "x"}}
    assert data == {"a": {"b": [1, 2, 3]}, "c": 1}                 # the input is not modified
    for bad, match in ((["a.b.7=1"], "no such list element"), (["c.x=1"], "cannot go inside"),
                       (["z.0=1"], "give the whole list"), (["c=[1"], "not valid YAML")):
        with pytest.raises(ConfigError, match=match):
            apply_overrides(data, bad)
    with pytest.raises(OverrideSyntaxError):
        apply_overrides(data, ["a..b=1"])


@pytest.mark.parametrize("closed,args,code", [
    (">&-", ["tea", "mb3"], 0),                       # stdout closed: the result still counts
    ("2>&-", ["tea", "no_such_config.yaml"], EXIT_INPUT),
    (">&- 2>/dev/null", ["tea", "no_such_config.yaml"], EXIT_INPUT),
])
def test_console_entry_point_keeps_the_exit_code_with_closed_streams(tmp_path, closed, args, code):
    """The ``acmm`` console script leaves by ``os._exit`` after flushing; a closed stdout or
    stderr (``sys.stdout is None``) must neither change the exit code nor print a traceback."""
    import shlex
    import subprocess
    import sys

    exe = Path(sys.executable).parent / "acmm"
    cmd = f"{shlex.quote(str(exe))} {' '.join(shlex.quote(a) for a in args)} {closed}"
    p = subprocess.run(["sh", "-c", cmd], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                       env={**__import__("os").environ, "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"})
    assert p.returncode == code, (p.returncode, p.stderr)
    assert "Traceback" not in p.stderr


def test_a_riccati_hint_never_suggests_the_method_that_failed():
    from acmm_qpp.hints import numerical_hint

    for used in ("scipy", "sign", "slycot"):
        for msg in (f"Riccati solve (method='{used}') residual 3e-6 above design.residual_tol",
                    f"sector LQR: Riccati solve (method='{used}') failed",
                    f"Riccati solve (method='{used}') did not converge"):
            hint = numerical_hint(msg)
            assert "riccati_method" in hint and used not in hint.split("riccati_method", 1)[1].split(")")[0], hint
    assert "scipy or sign or slycot" in numerical_hint("Riccati solve failed")


def test_hints_for_an_uncontrollable_pole_at_zero_and_a_narrow_sector_can_help():
    """'lower design.sector.sigma' cannot help an uncontrollable pole at 0 (no sector σ > 0 holds
    it), nor 'uncontrollable?' a controllable plant in a 1° sector (review)."""
    from acmm_qpp.hints import numerical_hint

    at0 = numerical_hint("sector LQR: open-loop pole λ/n = 0+0j lies outside the sector and is uncontrollable "
                         "(PBH ratio 3.2e-18); no feedback can move it")
    assert "sigma" not in at0 and "design.drf_mode" in at0
    away = numerical_hint("sector LQR: open-loop pole λ/n = 0.2+0j lies outside the sector and is uncontrollable")
    assert "lower design.sector.sigma" in away
    narrow = numerical_hint("sector LQR (shift): cannot shift the poles λ/n = [(-2.3+0.8j)] (uncontrollable?): "
                            "Riccati solve (method='scipy'): relative residual 1.2e-07 exceeds tolerance 1.0e-09")
    assert narrow.startswith("widen design.sector.half_angle_deg")


@pytest.mark.parametrize("backend", ["nonexistent", "module://matplotlib_inline.backend_inline", "TkAgg"])
def test_any_mplbackend_still_writes_the_figures(tmp_path, backend):
    """The commands draw into files only: an invalid or interactive MPLBACKEND (Jupyter's) made
    ``import matplotlib`` fail, a traceback in the sweep and the report (a review)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": backend,
           "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-m", "acmm.cli.app", "sweep", "sweep_smoke", "sweep.n_runs=2",
                           "sweep.orbits=0.5"], cwd=tmp_path, capture_output=True, text=True, env=env,
                          timeout=300, check=False)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert list((tmp_path / "runs").glob("*/sweep_*.png")), sorted((tmp_path / "runs").rglob("*"))


def test_without_a_writable_home_matplotlib_leaves_no_folder_per_run(tmp_path):
    """matplotlib made a /tmp/matplotlib-* folder in every run (the forked figure processes
    leave without its cleanup) and warned twice; one private folder per user is used instead."""
    import os
    import subprocess
    import sys

    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env.update({"PYTHONPATH": str(REPO), "HOME": "/proc/nonexistent",
                "TMPDIR": str(tmp), "OPENBLAS_NUM_THREADS": "1"})
    for name in ("a", "b"):
        done = subprocess.run([sys.executable, "-m", "acmm.cli.app", "design", "mb3", f"name={name}"], cwd=tmp_path,
                              capture_output=True, text=True, env=env, timeout=300, check=False)
        assert done.returncode == 0 and done.stderr == "", done.stderr
        assert (tmp_path / "runs" / name / "design_poles.png").exists()
    assert [p.name for p in tmp.iterdir()] == [f"acmm-matplotlib-{os.getuid()}"]


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
    """ExitCodeGroup carries it past typer as _Interrupted; a caller of main(standalone_mode=False)
    gets the KeyboardInterrupt back (not an Exception its `except Exception` would swallow)."""
    from typer.main import get_command

    with pytest.raises(KeyboardInterrupt):
        get_command(_interrupting_app()).main(["wrapped", "--when", "now"], standalone_mode=False)
    with pytest.raises(SystemExit) as stop:
        get_command(_interrupting_app()).main(["wrapped", "--when", "now"])
    assert stop.value.code == 130
