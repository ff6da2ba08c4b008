"""General sector-bounded nonlinearities (qpp.model.nonlin): sector and β3 of expressions against
closed forms, the slope sector of a coupled channel, a zero or denormal φ."""
import numpy as np
import pytest
import scipy.integrate as si

from qpp.io.config import load_config, parse_config

from tests.qpp.conftest import _cfg


def test_sector_beta3_from_expression_against_closed_forms():
    # saturation: phi = (k - k°) sat(y, 0.5), |k - k°| <= 0.2 -> sector ±0.2, slope 0.2
    m = load_config("qpp_saturation").expression_model()
    np.testing.assert_allclose(m.sector_info.sector, [[-0.2, 0.2]], atol=1e-9)
    assert m.sector_info.verified
    # beta3 = 0.2 * ||(1)_T||_2 (the slope bound is constant in t)
    assert m.beta3(2.0) == pytest.approx(0.2 * np.sqrt(2.0), rel=1e-6)
    # cubic on |y1| <= 1, |c - c°| <= 0.1: phi/y = -(c - c°) y^2 in ±0.1, slope 3·0.1·1
    c = load_config("qpp_cubic2").expression_model()
    np.testing.assert_allclose(c.sector_info.sector[0], [-0.1, 0.1], atol=1e-9)
    assert c.sector_info.slope_bound[0] == pytest.approx(0.3, rel=1e-9)
    assert c.beta3(1.5) == pytest.approx(0.3 * np.sqrt(1.5), rel=1e-6)
    # ch. 13 form: phi = dm·y·sin t, |dm| <= 0.05: beta3 = 0.05 ||(sin t)_T||_2 by quadrature
    u = load_config("qpp_unstable").expression_model()
    np.testing.assert_allclose(u.sector_info.sector, [[-0.05, 0.05]], rtol=1e-4)
    T = 1.3
    q = np.sqrt(si.quad(lambda t: np.sin(t) ** 2, 0, T)[0])
    assert u.beta3(T) == pytest.approx(0.05 * q, rel=1e-4)


def test_cross_coupled_channel_gets_the_slope_sector(tmp_path):
    d = _cfg("qpp_cubic2", tmp_path)
    d["nonlinearity"]["f1"] = ["-c*sin(y1 - y2)", "0"]
    m = parse_config(d).expression_model()
    si_ = m.sector_info
    # φ1 = -(c - 1) sin(y1 - y2): Σ_j sup|∂φ1/∂y_j| = 0.1 (1 + 1); φ1 is not a function of y1 alone
    assert not si_.diagonal[0] and si_.slope_bound[0] == pytest.approx(0.2, rel=1e-9)
    np.testing.assert_allclose(si_.sector[0], [-0.2, 0.2], rtol=1e-9)
    # independent: |φ1| ≤ 0.2 max|y| at random points of the range
    rng = np.random.default_rng(0)
    y = rng.uniform(-1, 1, (2, 500))
    c = rng.uniform(0.9, 1.1, 500)
    assert np.all(np.abs((c - 1) * np.sin(y[0] - y[1])) <= 0.2 * np.abs(y).max(axis=0) + 1e-15)


@pytest.mark.slow
@pytest.mark.parametrize("f1, codes", [("k*y1*0", (0,)), ("k*y1*1e-318", (0, 4))])
def test_a_zero_or_denormal_nonlinearity_is_designed_without_a_traceback(tmp_runs, f1, codes):
    """φ ≡ 0 samples to the sector [0, 0], φ = 1e-318·k·y to a denormal one that scales to
    [-0, 0]: both used to end in "ValueError: need alpha < beta" with a traceback.  The flat
    sector is widened by 1e-12 (as a zero sinusoidal one); a scale that underflows is not a
    sector.  The results are written (exit 4 at most: a figure of the denormal case)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    r = CliRunner().invoke(app, ["design", "qpp_saturation", f'nonlinearity.f1=["{f1}"]'])
    assert r.exit_code in codes, r.output
    assert "Traceback" not in r.output and (r.exception is None or isinstance(r.exception, SystemExit))
    assert (tmp_runs / "runs" / "qpp_saturation" / "qpp_design.h5").is_file()


# ----------------------------------------------------------------------------- hostile expressions (issue 33)
_HOSTILE = [
    ("tan(1000*y1)", "nonlinearity.f1.0: singular on the stated range: 'tan(1000*y1)' is not continuous in y1"),
    ("exp(1000*y1)", "nonlinearity.f1.0: overflow: 'exp(1000*y1)' is not a finite number"),
    ("1e308*y1*1e308", "nonlinearity.f1.0: overflow: the constant 1e308"),
    ("max(y1, 1e400)", "nonlinearity.f1.0: overflow: the constant 1e400"),
    ("y1/(y1 - 0.5)", "nonlinearity.f1.0: singular on the stated range: 'y1/(y1 - 0.5)' is not continuous in y1"),
    # a denominator that reaches 0 without changing sign (a review): a double root, an absolute value
    ("k*y1/(y1**2 - 0.62*y1 + 0.0961)", "is not continuous in y1"),
    ("k*y1/abs(y1-0.3)", "is not continuous in y1"),
    # an exact integer beyond floating point (it ended as an OverflowError, exit 3)
    ("9**64*9**64*9**64*9**64*9**64*9**64*k*y1", "overflow: expression"),
]


@pytest.mark.parametrize("expr, message", _HOSTILE)
def test_a_hostile_expression_is_refused_in_one_line_within_seconds(tmp_path, expr, message):
    """Each refusal is one line naming the user's field, exit 2, before any design (tan(100*y1)
    took 54 s in sympy's continuous_domain; tan(1000*y1) hung; exp(1000*y1) and 1e308*y1*1e308
    reached the design; 1e400 was called a division by zero).  The check's work is bounded by
    construction (SINGULARITY_POINTS evaluations per sub-expression); the timeout guards a hang."""
    import subprocess
    import sys

    from tests.conftest import REPO

    cfg = tmp_path / "c.yaml"
    cfg.write_text((REPO / "configs" / "qpp_saturation.yaml").read_text().replace(
        '  f1: [{form: saturation, output: 1, gain: "-k", level: 0.5}]', '  f1: ["-k*sat(y1, 0.5)"]'))
    done = subprocess.run([sys.executable, "-m", "qpp.cli", "design", str(cfg), f"nonlinearity.f1.0={expr}",
                           f"output.root={tmp_path}", "--no-figures"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "qpp_saturation").exists()
