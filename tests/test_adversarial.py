"""Hostile inputs through every command (issue 13): a table of bad configs, bad files, bad
options and bad output places.  Each case must give exit code 2 (bad input) or 4 (output / I/O),
exactly one line on stderr naming the field or cause, no traceback, nothing new on disk, and
finish within 10 s.  All cases run in-process (typer's CliRunner).
"""
from __future__ import annotations

import copy
import os
import re
import time
from pathlib import Path

import pytest
import yaml

from tests.conftest import CONFIGS, REPO

DELETE = object()


def _load(name: str) -> dict:
    return yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())


def _mutate(base: dict, edits: dict) -> dict:
    """Apply {"a.b.0.c": value} edits (``DELETE`` removes the key) to a copy of ``base``."""
    d = copy.deepcopy(base)
    for path, value in edits.items():
        keys = [int(k) if k.isdigit() else k for k in path.split(".")]
        node = d
        for k in keys[:-1]:
            if isinstance(node, dict) and k not in node:
                node[k] = {}
            node = node[k]
        if value is DELETE:
            del node[keys[-1]]
        else:
            node[keys[-1]] = value
    return d


# ---------------------------------------------------------------------------------------------
# the table
# ---------------------------------------------------------------------------------------------
# acmm config edits: (id, edits, regex the error line must match); run through 5 commands
ACMM_BAD = [
    ("inertia_1e308", {"inertia.I11": 1e308, "inertia.I22": 1e308, "inertia.I33": 1e308}, r"inertia\.I11.*plausible"),
    ("inertia_I13_1e300", {"inertia.I13": 1e300}, r"inertia\.I13.*plausible"),
    ("inertia_negative", {"inertia.I22": -1.0e6}, r"inertia.*positive definite"),
    ("inertia_tiny", {"inertia": {"I11": 2e-300, "I22": 1e-300, "I33": 2.5e-300}}, r"inertia.*principal moment"),
    ("inertia_nan", {"inertia.I11": float("nan")}, r"inertia\.I11.*finite"),
    ("inertia_inf", {"inertia.I33": float("inf")}, r"inertia\.I33.*finite"),
    ("inertia_2x2", {"inertia": [[1, 2], [3, 4]]}, r"inertia.*3×3"),
    ("inertia_triangle", {"inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 100]]}, r"inertia.*triangle"),
    ("inertia_asym", {"inertia": [[3, 1, 0], [0, 3, 0], [0, 0, 3]]}, r"inertia.*symmetric"),
    ("inertia_bad_unit", {"inertia.I11": "1e7 kg"}, r"inertia\.I11.*unit"),
    ("inertia_text", {"inertia.I11": "lots"}, r"inertia\.I11"),
    ("inertia_list", {"inertia.I11": [1, 2]}, r"inertia\.I11"),
    ("inertia_missing", {"inertia": DELETE}, r"inertia.*required"),
    ("orbit_rate_zero", {"orbit_rate": 0}, r"orbit_rate"),
    ("orbit_rate_fast", {"orbit_rate": 1.0}, r"orbit_rate"),
    ("orbit_rate_negative", {"orbit_rate": -0.001}, r"orbit_rate"),
    ("bias_two", {"disturbance.bias": [1, 2], "disturbance.bias_from_tea": DELETE}, r"disturbance\.bias.*three"),
    ("bias_1e300", {"disturbance.bias": [1e300, 0, 0], "disturbance.bias_from_tea": DELETE},
     r"disturbance\.bias.*plausible"),
    ("bias_from_tea_90", {"disturbance.bias_from_tea": [0, 90, 0]}, r"89"),
    ("bias_both", {"disturbance.bias": [0, 0, 0]}, r"either"),
    ("harmonic_text", {"disturbance.A": "x"}, r"disturbance\.A"),
    ("torque_limit_zero", {"actuators.torque_limit": 0}, r"actuators\.torque_limit"),
    ("momentum_limit_negative", {"actuators.momentum_limit": -5}, r"actuators\.momentum_limit"),
    ("torque_limit_1e300", {"actuators.torque_limit": 1e300}, r"actuators\.torque_limit.*plausible"),
    ("Q0_1e300", {"design.Q0": 1e300}, r"design\.Q0"),
    ("R_zero", {"design.R": 0}, r"design\.R"),
    ("R_tiny", {"design.R": 1e-300}, r"design\.R"),
    ("R_huge", {"design.R": 1e300}, r"design\.R"),
    ("model_bogus", {"design.model": "bogus"}, r"design\.model"),
    ("sigma_zero", {"design.sector.sigma": 0}, r"design\.sector\.sigma"),
    ("sigma_huge", {"design.sector.sigma": 1e300}, r"design\.sector\.sigma"),
    ("half_angle_90", {"design.sector.half_angle_deg": 90}, r"design\.sector\.half_angle_deg"),
    ("riccati_bogus", {"design.riccati_method": "magic"}, r"design\.riccati_method"),
    ("residual_tol_2", {"design.residual_tol": 2}, r"design\.residual_tol"),
    ("n_points_1", {"schedule": {"n_points": 1}}, r"schedule\.n_points"),
    ("order_9", {"schedule": {"order": 9}}, r"schedule\.order"),
    ("design_points_too_many", {"schedule": {"points": [{"name": f"p{k}", "inertia": {"I11": 2.3e7, "I22": 1.3e6,
                                                                                    "I33": 2.3e7}}
                                                       for k in range(450)]}}, r"ACMM_LIMIT_DESIGN_POINTS"),
    ("orbits_zero", {"simulation.orbits": 0}, r"simulation\.orbits"),
    ("orbits_1e9", {"simulation.orbits": 1e9}, r"simulation\.orbits"),
    ("samples_too_many", {"simulation.sample_interval": 1e-3}, r"sample_interval.*ACMM_LIMIT_SIM_SAMPLES"),
    ("levels_wrong", {"simulation.levels": [1, 2]}, r"simulation\.levels"),
    ("rtol_zero", {"simulation.rtol": 0}, r"simulation\.rtol"),
    ("rtol_below_precision", {"simulation.rtol": 1e-300}, r"simulation\.rtol"),
    ("divergence_negative", {"simulation.divergence_deg": -1}, r"simulation\.divergence_deg"),
    ("offset_1e300", {"simulation.initial_offset": [1e300, 0, 0]}, r"simulation\.initial_offset.*plausible"),
    ("root_nul", {"output.root": "a\x00b"}, r"output\.root"),
    ("figures_maybe", {"output.figures": "maybe"}, r"output\.figures"),
    ("name_empty", {"name": ""}, r"name"),
    ("name_dotdot", {"name": ".."}, r"name"),
    ("name_dot", {"name": "."}, r"name"),
    ("name_slash", {"name": "a/b"}, r"name"),
    ("name_hidden", {"name": ".hidden"}, r"name"),
    ("name_too_long", {"name": "x" * 300}, r"name.*(at most|100)"),
    ("name_int", {"name": 123}, r"name"),
    ("name_missing", {"name": DELETE}, r"name.*required"),
    ("key_newline", {"bad\nkey": 1}, r"bad key: unknown key"),
    ("key_unknown", {"foo": 1}, r"foo: unknown key"),
    ("description_int", {"description": 5}, r"description"),
]
ACMM_COMMANDS = ["validate", "tea", "linearize", "design", "simulate"]
# valid configs refused by a stage after the run lock was taken: the lock and the run directory
# must go again
ACMM_STAGE_BAD = [
    ("no_equilibrium", {"disturbance.bias": [0, 1.0e5, 0], "disturbance.bias_from_tea": DELETE},
     r"no torque-equilibrium attitude"),
]

QPP_BAD = [
    ("name_dotdot", {"name": ".."}, r"name"),
    ("name_dot", {"name": "."}, r"name"),
    ("name_too_long", {"name": "q" * 300}, r"name"),
    ("A_ragged", {"plant.A": [[0, 1], [0]]}, r"plant\.A.*same"),
    ("A_empty", {"plant.A": []}, r"plant\.A"),
    ("A_1e300", {"plant.A": [[0, 1], [0, 1e300]]}, r"plausible"),
    ("B_nan", {"plant.B": [[0], [float("nan")]]}, r"plant\.B"),
    ("A_shape", {"plant.A": [[0, 1, 2], [0, 1, 2]]}, r"plant\.A: shape"),
    ("kind_bogus", {"nonlinearity.kind": "bogus"}, r"nonlinearity"),
    ("F0_shape", {"nonlinearity.F0": [[1, 2]]}, r"nonlinearity\.F0"),
    ("omega_1e12", {"nonlinearity.omega": 1e12}, r"nonlinearity\.omega.*QPP_PERIODS"),
    ("gamma_max_zero", {"nonlinearity.gamma_max": 0}, r"nonlinearity.*gamma_max"),
    ("rho_zero", {"hinf.rho": 0}, r"hinf\.rho"),
    ("a_negative", {"hinf.a": -1}, r"hinf\.a"),
    ("a_overflow", {"hinf.a": 1e9}, r"hinf\.a.*overflow"),
    ("T_zero", {"spheres.T": 0}, r"spheres\.T"),
    ("beta_o_negative", {"spheres.beta_o": -1}, r"spheres\.beta_o"),
    ("published_K1_shape", {"design.gains": "published", "published.K1": [[1, 2, 3]]}, r"published\.K1.*1×2"),
    ("published_K1_ragged", {"design.gains": "published", "published.K1": [[1], [2, 3]]}, r"published\.K1"),
    ("published_H_shape", {"design.gains": "published", "published.H": [[1]]}, r"published\.H.*2×1"),
    ("published_Kc_text", {"design.gains": "published", "published.Kc": "abc"}, r"published\.Kc"),
    ("published_missing", {"design.gains": "published", "published.K1": None}, r"published"),
    ("scenarios_empty", {"simulation.scenarios": []}, r"simulation\.scenarios"),
    ("gamma_1e300", {"simulation.scenarios.0.gamma": 1e300}, r"gamma.*plausible"),
    ("n_samples_5", {"simulation.n_samples": 5}, r"simulation\.n_samples"),
    ("rtol_below_precision", {"simulation.rtol": 1e-300}, r"simulation\.rtol"),
    ("t_final_1e6", {"simulation.t_final": 1e6}, r"simulation\.t_final"),
    ("t_final_1e-300", {"simulation.t_final": 1e-300}, r"simulation\.t_final.*greater than or equal"),
    ("t_final_1e5_samples_2e5", {"simulation.t_final": 1e5, "simulation.n_samples": 200000},
     r"QPP_PERIODS|QPP_WORK|QPP_SAMPLES"),
    ("r_o_channels", {"simulation.r_o": []}, r"simulation\.r_o"),
    ("scenario_name_dotdot", {"simulation.scenarios.0.name": ".."}, r"name"),
    ("signal_omega_1e12", {"simulation.r_o": [[{"kind": "sin", "amplitude": 1.0, "omega": 1e12}]]},
     r"r_o.*QPP_PERIODS"),
    ("sector_shape", {"design.sector": [[1]]}, r"design\.sector"),
    ("sector_inverted", {"design.sector": [[0.5, -0.5]]}, r"design\.sector.*alpha < beta"),
    ("sector_degenerate", {"design.sector": [[0.5, 0.5]]}, r"design\.sector.*alpha < beta"),
    ("scenario_names_duplicate", {"simulation.scenarios": [{"name": "same"}, {"name": "same"}]},
     r"simulation\.scenarios: duplicate name 'same'"),
    ("rho_bracket_inverted", {"design.rho_min": 10.0, "design.rho_max": 1e-3}, r"design\.rho_min.*rho_max"),
    ("a_bracket_inverted", {"design.a_min": 1.0, "design.a_max": 1e-3}, r"design\.a_min.*a_max"),
    ("x0_length", {"plant.x0": [1]}, r"plant\.x0"),
    ("root_empty", {"output.root": ""}, r"output\.root"),
    ("key_newline", {"bad\nkey": 1}, r"bad key: unknown key"),
]
QPP_COMMANDS = ["design", "simulate"]

SWEEP_BAD = [
    ("name_dotdot", {"name": ".."}, r"name"),
    ("n_runs_zero", {"sweep.n_runs": 0}, r"sweep\.n_runs"),
    ("n_runs_huge", {"sweep.n_runs": 10**7}, r"sweep\.n_runs"),
    ("draws_unphysical_huge", {"sweep.monte_carlo": {"dI11": {"uniform": [-3, -2]}}, "sweep.max_draws": 10**12,
                               "sweep.margin": DELETE}, r"sweep\.max_draws.*ACMM_LIMIT_SWEEP_DRAWS"),
    ("base_missing", {"sweep.base": "no_such_config_here"}, r"not found"),
    ("monte_carlo_empty", {"sweep.monte_carlo": {}}, r"monte_carlo"),
    ("parameter_unknown", {"sweep.monte_carlo.wobble": {"percent": 5}}, r"wobble"),
    ("orbits_zero", {"sweep.orbits": 0}, r"sweep\.orbits"),
    ("orbits_budget", {"sweep.orbits": 10000, "sweep.n_runs": 1000}, r"ACMM_LIMIT_SWEEP_ORBITS"),
    # the margin searches' runs count (a review: 1 case + a 100-point scan each way was accepted)
    ("orbits_budget_margin", {"sweep.orbits": 1000, "sweep.n_runs": 1,
                              "sweep.margin": {"low": 0.001, "high": 1000, "scan_points": 100, "rel_tol": 1e-6}},
     r"margin searches.*ACMM_LIMIT_SWEEP_ORBITS"),
    ("grid_huge", {"sweep.monte_carlo": DELETE, "sweep.n_runs": DELETE,
                   "sweep.grid": {"dI11": [0.0] * 200, "dI22": [0.0] * 200, "dI33": [0.0] * 200}},
     r"ACMM_LIMIT_SWEEP_CASES"),
    ("workers_zero", {"sweep.workers": 0}, r"sweep\.workers"),
    ("redesign_budget", {"sweep.design": "redesign", "sweep.n_runs": 60000, "sweep.orbits": 1},
     r"ACMM_LIMIT_SWEEP_DESIGNS"),
    ("margin_low_2", {"sweep.margin.low": 2}, r"sweep\.margin\.low"),
    ("margin_rel_tol_tiny", {"sweep.margin.rel_tol": 1e-300}, r"sweep\.margin\.rel_tol"),
    ("settle_zero", {"sweep.settle_deg": 0}, r"sweep\.settle_deg"),
    ("map_unknown", {"sweep.map": ["x", "y"]}, r"map"),
    ("map_twice", {"sweep.map": ["dI11", "dI11"]}, r"map: the two axes are both 'dI11'"),
    ("seed_negative", {"sweep.seed": -1}, r"sweep\.seed"),
    ("seed_2_64", {"sweep.seed": 2**64}, r"sweep\.seed"),
    ("offset_100", {"sweep.monte_carlo.offset_pitch": {"uniform": [-100, 100]}}, r"89"),
    ("root_nul", {"output.root": "a\x00b"}, r"output\.root"),
    ("no_sweep", {"sweep": DELETE}, r"sweep"),
    # a misspelt base made the sweep an inline one and said "inertia: Field required" (a review)
    ("base_misspelt", {"sweep.bsae": "ac", "sweep.base": DELETE}, r"sweep\.base: missing.*sweep\.bsae.*'base'"),
    ("sweep_list", {"sweep": [1, 2]}, r"sweep: expected a mapping"),
]

# config *files* that are hostile as files: (id, writer(tmp) -> path, regex)


def _w(text: str | bytes, name: str = "c.yaml"):
    def make(tmp: Path) -> Path:
        p = tmp / name
        (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
        return p
    return make


def _fifo(tmp: Path) -> Path:
    p = tmp / "fifo.yaml"
    os.mkfifo(p)
    return p


def _dir(tmp: Path) -> Path:
    p = tmp / "adir.yaml"
    p.mkdir()
    return p


def _deep(n: int) -> str:
    return "name: deep\nx: " + "[" * n + "]" * n + "\n"


def _bomb() -> str:
    lines = ["name: bomb", "a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    for i in range(1, 9):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    return "\n".join(lines) + "\n"


FILE_BAD = [
    ("fifo", _fifo, r"not a regular file"),
    ("dev_zero", lambda tmp: Path("/dev/zero"), r"not a regular file"),
    ("directory", _dir, r"directory"),
    ("missing", lambda tmp: tmp / "nope.yaml", r"not found"),
    ("deep_nesting", _w(_deep(500)), r"nested deeper than 32.*ACMM_LIMIT_YAML_DEPTH"),
    ("alias_bomb", _w(_bomb()), r"more than 20000 values.*ACMM_LIMIT_YAML_NODES"),
    ("recursive_alias", _w("name: r\nx: &x [1, *x]\n"), r"cycle"),
    ("huge_file", _w("name: big\nl: [" + ",".join(["1"] * 1_600_000) + "]\n"), r"too large.*ACMM_LIMIT_CONFIG_BYTES"),
    ("many_values", _w("name: big\nl: [" + ",".join(["1"] * 60_000) + "]\n"), r"ACMM_LIMIT_YAML_NODES"),
    ("not_utf8", _w(b"name: \xff\xfe\n"), r"UTF-8"),
    ("empty", _w(""), r"top level must be a mapping"),
    ("top_list", _w("- 1\n- 2\n"), r"top level must be a mapping"),
    ("duplicate_key", _w("name: a\nname: b\n"), r"duplicate key"),
    ("syntax_error", _w("name: [1, 2\n"), r"not valid YAML"),
    ("python_tag", _w("name: !!python/object:os.system x\n"), r"not valid YAML"),
    ("two_documents", _w("name: a\n---\nname: b\n"), r"not valid YAML"),
    ("long_file_name", lambda tmp: tmp / ("y" * 300 + ".yaml"), r"(name too long|not found)"),
    ("list_as_key", _w("name: k\n? [a, b]\n: 1\n"), r"key must be a plain value"),
    ("integer_5000_digits", _w("name: k\norbit_rate: " + "9" * 5000 + "\n"), r"4300 digits"),
]
FILE_COMMANDS = [("acmm", ["validate"]), ("acmm", ["tea"]), ("qpp", ["design"]), ("acmm", ["sweep"])]


def _cases():
    out = []
    for cid, edits, rx in ACMM_BAD:
        for cmd in ACMM_COMMANDS:
            out.append(pytest.param("acmm", [cmd], ("mb3", edits), 2, rx, id=f"acmm-{cmd}-{cid}"))
    for cid, edits, rx in ACMM_STAGE_BAD:
        for cmd in ACMM_COMMANDS[1:]:
            out.append(pytest.param("acmm", [cmd], ("mb3", edits), 2, rx, id=f"acmm-{cmd}-{cid}"))
    for cid, edits, rx in QPP_BAD:
        for cmd in QPP_COMMANDS:
            out.append(pytest.param("qpp", [cmd], ("qpp_siso", edits), 2, rx, id=f"qpp-{cmd}-{cid}"))
    for cid, edits, rx in SWEEP_BAD:
        out.append(pytest.param("acmm", ["sweep"], ("sweep_smoke", edits), 2, rx, id=f"sweep-{cid}"))
    for cid, make, rx in FILE_BAD:
        for app, cmd in FILE_COMMANDS:
            out.append(pytest.param(app, cmd, make, 2, rx, id=f"file-{app}-{cmd[0]}-{cid}"))
    # command-line values
    for j in ("0", "-1", "5000"):
        out.append(pytest.param("acmm", ["sweep", "-j", j], ("sweep_smoke", {}), 2, r"--workers",
                                id=f"cli-sweep-j{j}"))
    return out


def _snapshot(root: Path) -> set:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def _app(name):
    if name == "acmm":
        from acmm.cli.app import app
    else:
        from qpp.cli import app
    return app


def _invoke(app_name, args, env=None):
    from typer.testing import CliRunner

    t0 = time.monotonic()
    r = CliRunner().invoke(_app(app_name), [str(a) for a in args], env=env)
    return r, time.monotonic() - t0


def check_one_line_refusal(r, dt, code, rx, before, after):
    """The contract of every refusal."""
    import re

    assert r.exit_code == code, (r.exit_code, r.stderr, r.exception)
    assert not isinstance(r.exception, Exception) or isinstance(r.exception, SystemExit), repr(r.exception)
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: ") and "Traceback" not in r.stderr
    assert re.search(rx, lines[0]), lines[0]
    assert after == before, sorted(after ^ before)
    # a hang guard, not a speed target (those live in `make bench`): a refusal takes well under a
    # second alone, but a loaded 2-core CI machine has been seen to stretch it to 40 s
    assert dt < 120.0


@pytest.mark.parametrize("app_name,cmd,config,code,rx", _cases())
def test_hostile_input_refused_in_one_line(tmp_runs, app_name, cmd, config, code, rx):
    if isinstance(config, tuple):
        base, edits = config
        path = tmp_runs / "cfg.yaml"
        path.write_text(yaml.safe_dump(_mutate(_load(base), edits), allow_unicode=True))
    else:
        path = config(tmp_runs)
    before = _snapshot(tmp_runs)
    r, dt = _invoke(app_name, [*cmd[:1], path, *cmd[1:]])
    check_one_line_refusal(r, dt, code, rx, before, _snapshot(tmp_runs))


def test_table_covers_at_least_150_cases():
    assert len(_cases()) >= 150


def test_unreachable_dask_scheduler_writes_nothing(tmp_runs):
    pytest.importorskip("distributed")
    path = tmp_runs / "s.yaml"
    path.write_text(yaml.safe_dump(_mutate(_load("sweep_smoke"), {"sweep.margin": DELETE})))
    before = _snapshot(tmp_runs)
    # in a fresh process, as a user runs it: the refusal must not depend on Dask state (event
    # loops, comm pools) left in the test process by earlier in-process runs
    import subprocess
    import sys
    from types import SimpleNamespace

    t0 = time.monotonic()
    p = subprocess.run([str(Path(sys.executable).parent / "acmm"), "sweep", str(path), "--scheduler",
                        "tcp://127.0.0.1:9"], cwd=tmp_runs, capture_output=True, text=True, timeout=60,
                       env={**os.environ, "ACMM_LIMIT_DASK_CONNECT_SECONDS": "1", "OPENBLAS_NUM_THREADS": "1"})
    r = SimpleNamespace(exit_code=p.returncode, stderr=p.stderr, exception=None)
    check_one_line_refusal(r, time.monotonic() - t0, 2, r"Dask scheduler", before, _snapshot(tmp_runs))


# ---------------------------------------------------------------------------------------------
# output places that cannot be written: exit 4, one line, nothing new
# ---------------------------------------------------------------------------------------------
OUTPUT_COMMANDS = [  # (app, command, base config, file whose place a directory takes)
    ("acmm", "tea", "mb3", "tea.h5"),
    ("acmm", "linearize", "mb3", "linearize.h5"),
    ("acmm", "design", "mb3", "design.h5"),
    ("acmm", "simulate", "mb3", "design.h5"),
    ("qpp", "design", "qpp_siso", "qpp_design.h5"),
    ("qpp", "simulate", "qpp_siso", "qpp_sim.h5"),
    ("acmm", "sweep", "sweep_smoke", "sweep.journal"),
]


def _output_case(tmp: Path, base: str, how: str, target: str) -> tuple[Path, str]:
    cfg = _load(base)
    name = cfg["name"]
    edits = {"output.figures": False}
    if base == "sweep_smoke":
        edits.update({"sweep.margin": DELETE, "sweep.n_runs": 2, "sweep.orbits": 0.5})
    if base == "qpp_siso":
        edits.update({"simulation.n_samples": 201, "simulation.t_final": 2.0})
    if how == "root_is_file":
        (tmp / "afile").write_text("x")
        edits["output.root"] = "afile"
        rx = r"Not a directory"
    elif how in ("target_is_dir", "config_is_dir"):
        # config.yaml is written last: the results already written are then removed again
        (tmp / "runs" / name / (target if how == "target_is_dir" else "config.yaml")).mkdir(parents=True)
        rx = r"(directory|Is a directory)"
    else:  # a root path component longer than the file system allows
        edits["output.root"] = "r" * 300
        rx = r"name too long"
    path = tmp / "cfg.yaml"
    path.write_text(yaml.safe_dump(_mutate(cfg, edits)))
    return path, rx


@pytest.mark.parametrize("how", ["root_is_file", "target_is_dir", "config_is_dir", "name_too_long"])
@pytest.mark.parametrize("app_name,cmd,base,target", OUTPUT_COMMANDS, ids=[f"{a}-{c}" for a, c, *_ in OUTPUT_COMMANDS])
def test_output_place_refused_exit_4(tmp_runs, app_name, cmd, base, target, how):
    path, rx = _output_case(tmp_runs, base, how, target)
    extra = ["-j", "1"] if cmd == "sweep" else []
    before = _snapshot(tmp_runs)
    r, dt = _invoke(app_name, [cmd, path, *extra])
    if cmd == "sweep" and how == "config_is_dir":   # a sweep's journal stays (--resume): a sweep
        # started afresh writes its config.yaml first, so it stops before any case
        before |= {f"runs/{_load(base)['name']}/sweep.journal"}
    check_one_line_refusal(r, dt, 4, rx, before, _snapshot(tmp_runs))


@pytest.mark.parametrize("app_name,base,figure", [("acmm", "mb3", "design_poles.png"),
                                                  ("qpp", "qpp_siso", "qpp_iterations.png")])
def test_figure_place_refused_after_the_results_keeps_them_with_their_config(tmp_runs, app_name, base, figure):
    """The results are written before a figure fails: exit 4 with one line, and the run keeps
    its results beside the config.yaml of this run (not one of an earlier run)."""
    cfg = _load(base)
    edits = {"output.figures": True, "description": "this run"}
    if base == "qpp_siso":
        edits.update({"simulation.n_samples": 201, "simulation.t_final": 2.0})
    run = tmp_runs / "runs" / cfg["name"]
    (run / figure).mkdir(parents=True)
    (run / "config.yaml").write_text("description: an earlier run\n")
    path = tmp_runs / "cfg.yaml"
    path.write_text(yaml.safe_dump(_mutate(cfg, edits)))
    r, dt = _invoke(app_name, ["design", path])
    assert r.exit_code == 4 and r.stderr.count("\n") == 1 and re.search(r"(directory|Is a directory)", r.stderr)
    assert (run / ("design.h5" if app_name == "acmm" else "qpp_design.h5")).is_file()
    assert "description: this run" in (run / "config.yaml").read_text()


@pytest.fixture
def readonly_dir(tmp_path):
    """A read-only tmpfs (also read-only for root); skipped where mounting is not permitted."""
    import subprocess

    d = tmp_path / "ro"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a read-only tmpfs here: {r.stderr.decode().strip() or r.returncode}")
    yield d
    subprocess.run(["umount", str(d)], check=False)


@pytest.mark.parametrize("app_name,cmd,base,target", OUTPUT_COMMANDS, ids=[f"{a}-{c}" for a, c, *_ in OUTPUT_COMMANDS])
def test_read_only_root_refused_exit_4(tmp_runs, readonly_dir, app_name, cmd, base, target):
    cfg = _load(base)
    edits = {"output.root": str(readonly_dir / "runs"), "output.figures": False}
    if base == "sweep_smoke":
        edits.update({"sweep.margin": DELETE, "sweep.n_runs": 2, "sweep.orbits": 0.5})
    path = tmp_runs / "cfg.yaml"
    path.write_text(yaml.safe_dump(_mutate(cfg, edits)))
    extra = ["-j", "1"] if cmd == "sweep" else []
    before = _snapshot(tmp_runs)
    r, dt = _invoke(app_name, [cmd, path, *extra])
    check_one_line_refusal(r, dt, 4, r"Read-only file system", before, _snapshot(tmp_runs))


@pytest.mark.parametrize("app_name,args,rx", [
    ("acmm", ["validate", "mb3", "simulation.orbits=" + "1" * 5000], r"override simulation\.orbits.*4300 digits"),
    ("qpp", ["design", "qpp_siso", "plant.A=[&r [" + ",".join(["0"] * 300) + "], " + ", ".join(["*r"] * 100) + "]"],
     r"override plant\.A.*ACMM_LIMIT_YAML_NODES"),
])
def test_hostile_override_refused_in_one_line(tmp_runs, app_name, args, rx):
    # an override's value is YAML read with the same bounds as a config file
    before = _snapshot(tmp_runs)
    r, dt = _invoke(app_name, args)
    check_one_line_refusal(r, dt, 2, rx, before, _snapshot(tmp_runs))


def _raised_hints(package: str) -> list[str]:
    """The literal text of every hint a package raises an error with: ``hint=`` arguments, names
    ending in ``hint`` assigned, and what functions named ``*_hint`` return (f-strings' literal parts)."""
    import ast

    def texts(node):
        return [n.value for n in ast.walk(node) if isinstance(n, ast.Constant) and isinstance(n.value, str)]

    out = []
    for path in (REPO / package).rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.keyword) and node.arg == "hint":
                out += texts(node.value)
            elif isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id.lower().endswith("hint")
                                                      for t in node.targets):
                out += texts(node.value)
            elif isinstance(node, ast.FunctionDef) and node.name.endswith("_hint"):
                out += [t for r in ast.walk(node) if isinstance(r, ast.Return) and r.value for t in texts(r.value)]
    return out


def test_each_numerical_hint_names_settings_of_its_own_product():
    # a qpp failure must not suggest acmm settings (design.sector.sigma …) and vice versa: every
    # dotted key of a hint a product raises its errors with resolves in that product's config schema
    import re

    import typing

    from pydantic import BaseModel

    from acmm.io.config import Config
    from acmm_qpp.config_model import _union_members as union_members
    from qpp.io.config import QppConfig

    def resolves(model, key: list) -> bool:
        """A dotted config key is a field of ``model`` or of a model it holds (any union member)."""
        if not key:
            return True
        for t in union_members(model):
            while typing.get_origin(t) in (list, tuple, dict):
                t = typing.get_args(t)[-1]
            if isinstance(t, type) and issubclass(t, BaseModel) and key[0] in t.model_fields:
                if resolves(t.model_fields[key[0]].annotation, key[1:]):
                    return True
        return False

    for product, schema in (("acmm", Config), ("qpp", QppConfig)):
        hints = _raised_hints(product)
        assert len(hints) > 10, product
        for hint in hints:
            for key in re.findall(r"\b[a-z_]+(?:\.[A-Za-z_0-9]+)+", hint):
                assert resolves(schema, key.split(".")), (product, key, hint)


def test_design_work_bound_refuses_a_long_horizon(tmp_runs, monkeypatch):
    # each candidate of procedure 12.1 integrates the nominal loop over max(T, t_final): their
    # total work is bounded (t_final = 2500 s on qpp_saturation ran for hours through the wider
    # search); a small limit makes the default horizon "long"
    monkeypatch.setenv("ACMM_LIMIT_QPP_WORK", "20")
    before = _snapshot(tmp_runs)
    r, dt = _invoke("qpp", ["design", "qpp_siso"])
    check_one_line_refusal(r, dt, 2, r"simulation\.t_final.*too long for the design.*ACMM_LIMIT_QPP_WORK",
                           before, _snapshot(tmp_runs))


def test_many_uncertain_parameters_refused_before_sampling(tmp_runs):
    # the sector of an expression is sampled at every parameter corner: 2^k of them; 30
    # parameters took 24 GB before this bound
    cfg = _load("qpp_cubic2")
    params = {f"p{i}": {"min": 0.0, "max": 0.001} for i in range(30)}
    params.update(cfg["nonlinearity"]["parameters"])
    edits = {"nonlinearity.parameters": params,
             "nonlinearity.f1": ["-c*cubic(y1) + y1*(" + "+".join(f"p{i}" for i in range(30)) + ")", "0"]}
    path = tmp_runs / "cfg.yaml"
    path.write_text(yaml.safe_dump(_mutate(cfg, edits)))
    before = _snapshot(tmp_runs)
    r, dt = _invoke("qpp", ["design", path])
    check_one_line_refusal(r, dt, 2, r"nonlinearity: .*31 uncertain parameters.*nonlinearity\.parameters.*ACMM_LIMIT_QPP_SECTOR_POINTS",
                           before, _snapshot(tmp_runs))
    assert dt < 30


@pytest.mark.slow
def test_schedule_blending_a_station_into_itself_is_refused(tmp_runs):
    # schedule.to = the config's own station: every design point has the same TEA, so there is no
    # θ2* to schedule against (the refit divided by the zero TEA span: a NaN failure, exit 3)
    path = tmp_runs / "cfg.yaml"
    path.write_text(yaml.safe_dump(_mutate(_load("staircase"), {"schedule.to": "mb3", "output.figures": False})))
    before = _snapshot(tmp_runs)
    r, dt = _invoke("acmm", ["design", path])
    check_one_line_refusal(r, dt, 2, r"schedule: the 12 design points all have the pitch TEA", before,
                           _snapshot(tmp_runs))
