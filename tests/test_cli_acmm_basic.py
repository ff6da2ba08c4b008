"""The ``acmm`` command line: help, validate, schema, tea."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from acmm_qpp.results import read_h5

from tests.conftest import CONFIGS


def _numbers(line):
    return [float(x) for x in re.findall(r"[-+]?\d+\.\d+(?:e[-+]?\d+)?", line)]


def test_help(run_acmm):
    r = run_acmm("--help")
    assert r.exit_code == 0
    for command in ("validate", "schema", "tea"):
        assert command in r.output


def test_installed_console_script_help():
    exe = shutil.which("acmm", path=str(Path(sys.executable).parent)) or shutil.which("acmm")
    if exe is None:
        pytest.skip("console script 'acmm' not installed")
    r = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "tea" in r.stdout


def test_validate_ok(tmp_runs, run_acmm):
    r = run_acmm("validate", CONFIGS / "mb3.yaml")
    assert r.exit_code == 0, r.output
    assert "mb3: valid" in r.stdout
    assert list(tmp_runs.iterdir()) == []  # validate writes nothing


def test_validate_packaged_default(tmp_runs, run_acmm):
    r = run_acmm("validate")
    assert r.exit_code == 0, r.output
    assert "staircase: valid" in r.stdout


def test_schema_is_json(run_acmm):
    r = run_acmm("schema")
    assert r.exit_code == 0
    schema = json.loads(r.stdout)
    assert {"name", "inertia", "orbit_rate", "disturbance", "actuators"} <= set(schema["properties"])
    assert schema["additionalProperties"] is False


def test_tea_prints_and_writes(tmp_runs, run_acmm):
    r = run_acmm("tea", CONFIGS / "mb3.yaml")
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    theta_line = next(line for line in lines if "theta*" in line)
    np.testing.assert_allclose(_numbers(theta_line), [1.3, -44.7, 2.1], atol=0.01)
    omega_line = next(line for line in lines if "omega*" in line)
    h5 = read_h5(tmp_runs / "runs" / "mb3" / "tea.h5")
    np.testing.assert_allclose(_numbers(omega_line), h5["omega"], rtol=1e-6)
    res_line = next(line for line in lines if "residual" in line)
    assert float(re.search(r"=\s*([0-9.e+-]+)", res_line).group(1)) < 1e-10


def test_tea_by_packaged_name_from_empty_directory(tmp_runs, run_acmm):
    r = run_acmm("tea", "ac")
    assert r.exit_code == 0, r.output
    assert (tmp_runs / "runs" / "ac" / "tea.h5").is_file()
    np.testing.assert_allclose(_numbers(next(x for x in r.stdout.splitlines() if "theta*" in x)),
                               [0.19, -5.0, 0.56], atol=0.01)


def test_tea_all_lists_other_root(tmp_runs, run_acmm, tmp_path):
    cfg = tmp_path / "zero.yaml"
    cfg.write_text((CONFIGS / "mb3.yaml").read_text()
                   .replace("name: mb3", "name: mb3zero")
                   .replace("bias_from_tea: [1.3, -44.7, 2.1]", "bias: [0, 0, 0]"))
    r = run_acmm("tea", cfg, "--all")
    assert r.exit_code == 0, r.output
    theta = _numbers(next(x for x in r.stdout.splitlines() if "theta*" in x))
    assert theta[1] == pytest.approx(-44.70, abs=0.005)
    others = [_numbers(x.split("theta =")[1])[:3] for x in r.stdout.splitlines() if "other root" in x]
    assert any(abs(o[1] - 45.30) < 0.005 for o in others), r.stdout
    h5 = read_h5(tmp_runs / "runs" / "mb3zero" / "tea.h5")
    assert any(abs(np.degrees(o[1]) - 45.30) < 0.005 for o in h5["other_roots"])


def test_tea_no_equilibrium_is_user_error(tmp_runs, run_acmm, tmp_path):
    cfg = tmp_path / "wie.yaml"
    cfg.write_text((CONFIGS / "mb3.yaml").read_text()
                   .replace("name: mb3", "name: wie")
                   .replace("bias_from_tea: [1.3, -44.7, 2.1]", "bias: [0, 4, 0]"))
    assert run_acmm("validate", cfg).exit_code == 0  # a valid config...
    r = run_acmm("tea", cfg)  # ...without an equilibrium
    assert r.exit_code == 2
    assert isinstance(r.exception, SystemExit)
    err = r.stderr.strip()
    assert "\n" not in err and "Traceback" not in r.output
    assert "no torque-equilibrium attitude" in err and "1.73" in err
    assert not (tmp_runs / "runs").exists()


def test_tea_output_root_is_a_file_is_user_error(tmp_runs, run_acmm):
    (tmp_runs / "blocker").write_text("not a directory")
    (tmp_runs / "c.yaml").write_text(
        "name: t\ninertia: {I11: 23.22e6, I22: 1.30e6, I33: 23.23e6}\noutput: {root: blocker}\n")
    r = run_acmm("tea", "c.yaml")
    assert r.exit_code == 4, (r.exit_code, repr(r.exception))
    assert "\n" not in r.stderr.strip() and "Traceback" not in r.output
