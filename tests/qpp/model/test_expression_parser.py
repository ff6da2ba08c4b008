"""Expressions of a user's nonlinearity, parsed without eval (qpp.model.expression_parser): a bad
one is one line with exit 2 and nothing written."""
import pytest
import yaml
from typer.testing import CliRunner

from acmm_qpp.errors import EXIT_INPUT
from qpp.cli import app

from tests.qpp.conftest import _cfg

runner = CliRunner()


# ---------------------------------------------------------------------- expressions
@pytest.mark.parametrize("expr, words", [
    ("2*y2*k", "unknown symbol 'y2'"),
    ("k*y1/0", "singular"),
    ("k*log(y1)", "singular"),
    ("k*tan(y1)", "not continuous in y1"),                     # pole at pi/2 between grid points
    ("y1/(k - 4.1)", "not continuous in k"),
    ("k*sqrt(abs(y1))", "not sector-bounded"),
    ("k + y1", "not sector-bounded"),
    ("__import__('os').system('true')", "unknown function \"__import__('os').system\""),
    ("__import__('os')", "unknown function '__import__'"),
    ("y1.real*k", "Attribute not allowed"),
    ("k*y1**99999", "exponent"),
    ("(((((9**64)**64)**64)**64)**64)*y1", "beyond floating point"),
    ("k*[y1][0]", "not allowed"),
    ("k*max()", "max() needs at least one argument"),          # sympy's Max() is −∞: no "division by zero"
    ("k*y1^3", "powers are written **"),
    ("k*sat(y1, -1)", "the level L must be ≥ 0"),                 # it read as φ(0) = 0.2 ≠ 0
    ("k*deadzone(y1, -0.5)", "the half-width w must be ≥ 0"),      # silently y − w
])
def test_bad_expression_one_line_exit_2_nothing_written(tmp_path, expr, words):
    d = _cfg("qpp_saturation", tmp_path)
    d["nonlinearity"]["f1"] = [expr]
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(d))
    r = runner.invoke(app, ["design", str(path)])
    assert r.exit_code == EXIT_INPUT, r.output
    assert words in r.output and "nonlinearity.f1" in r.output
    assert "Traceback" not in r.output and len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "runs").exists()
