"""Sector and slope bounds proved by interval branch and bound (issue 43): enclosures checked
against numpy at random points, suprema of functions known in closed form, and nonlinearities
whose sector or slope leaves the sampled bound in a window narrower than any grid."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
import yaml
from mpmath import iv
from typer.testing import CliRunner

from acmm_qpp.errors import EXIT_NUMERICAL
from qpp.cli import app
from qpp.model.interval_bounds import NotEnclosable, compile_interval, maximize
from qpp.model.nonlin import ExpressionModel

y, k, t = sp.symbols("y k t", real=True)
EXPRS = [k * sp.Max(-0.5, sp.Min(0.5, y)) - 4 * sp.Max(-0.5, sp.Min(0.5, y)), (1 - k) * y ** 3,
         sp.tanh(3 * y) * k + sp.atan(y * t), sp.sqrt(y ** 2 + 1) * sp.exp(-t) * sp.sin(k * y),
         sp.Abs(y - 0.3) * sp.sign(y) + sp.log(2 + sp.cos(t * y)), sp.diff(sp.Max(-1, sp.Min(1, k * y)), y)]


@pytest.mark.parametrize("expr", EXPRS, ids=range(len(EXPRS)))
def test_an_enclosure_contains_every_value_on_its_box(expr):
    f = compile_interval(expr, [y, k, t])
    g = sp.lambdify([y, k, t], expr, modules="numpy")
    rng = np.random.default_rng(7)
    for _ in range(30):
        c = rng.uniform(-2, 2, 3)
        w = rng.uniform(0, 1, 3)
        enc = f(*(iv.mpf([float(x - h), float(x + h)]) for x, h in zip(c, w)))
        pts = c[:, None] + w[:, None] * rng.uniform(-1, 1, (3, 200))
        with np.errstate(all="ignore"):
            v = np.broadcast_to(np.asarray(g(*pts), float), (200,))
        v = v[np.isfinite(v)]
        assert np.all(v >= float(enc.a) - 1e-12) and np.all(v <= float(enc.b) + 1e-12)


def test_a_jump_has_no_enclosure_of_its_slope():
    with pytest.raises(NotEnclosable, match="DiracDelta"):
        compile_interval(sp.diff(sp.sign(y - 0.3) * k, y), [y, k])


def test_the_branch_and_bound_proves_a_supremum_known_in_closed_form_or_refutes_below_it():
    f = compile_interval(y * (1 - y) + k * sp.sin(t) ** 2, [y, k, t])     # sup 1/4 + 1/2 on the box
    box = [(0, 1), (-0.5, 0.5), (0, 3)]
    # an interior maximum: the naive enclosure over-estimates by O(width), so 1e-3 here
    got = maximize(f, box, target=0.75 + 1e-3, deadline=time.monotonic() + 30)
    assert got.status == "proved" and 0.74 <= got.lower <= 0.75 <= got.upper <= 0.75 + 1e-3
    got = maximize(f, box, target=0.75 - 1e-4, deadline=time.monotonic() + 30)
    assert got.status == "refuted" and got.lower > 0.75 - 1e-4
    y0, k0, t0 = got.at
    assert y0 * (1 - y0) + k0 * np.sin(t0) ** 2 > 0.75 - 1e-4
    got = maximize(f, box, tol=1e-3, deadline=time.monotonic() + 30)
    assert got.status == "proved" and got.upper - got.lower <= 1e-3 and got.lower <= 0.75 <= got.upper


def _model(text, lo=0.95, hi=1.05):
    return ExpressionModel([text], 1, {"k": (lo, hi, 0.5 * (lo + hi))}, [[-2.0, 2.0]], [[1.0]], 5.0)


#: φ/y = (k − 1)(1 + tent): the ratio doubles in a window of width 1e-7 about y = 0.31415926
WINDOW = "k*y1 + k*y1*max(0, 1 - abs(y1 - 0.31415926)*2e7)"
#: slope (k − 1)(1 + 0.5) on [0.31415926, 0.31415926 + 1e-9], (k − 1) elsewhere; the sector is intact
SPIKE = "k*y1 + 0.5*k*min(max(y1 - 0.31415926, 0), 1e-9)"


def test_the_packaged_forms_are_proved_within_a_relative_gap():
    M = _model("-k*sat(y1, 0.5)", 3.8, 4.2)
    assert np.allclose(M.sector_info.sector, [[-0.2, 0.2]], rtol=1e-9)
    pr = M.proof
    assert pr.sector_ok and pr.slope_ok, (pr.sector_text, pr.slope_text)
    assert np.allclose(pr.sector, [[-0.2, 0.2]], rtol=2e-6) and np.all(np.abs(pr.sector) >= 0.2)
    assert "proved" in pr.sector_text


def test_a_sector_violation_narrower_than_the_grid_is_refused_with_the_point():
    M = _model(WINDOW)
    assert np.allclose(M.sector_info.sector, [[-0.05, 0.05]], rtol=1e-6)     # the sampling misses it
    t0 = time.monotonic()
    pr = M.proof
    assert time.monotonic() - t0 < 60
    assert not pr.sector_ok and "outside the sampled sector" in pr.sector_text
    y_at = float(pr.sector_text.split("y1 = ")[1].split(";")[0])
    assert abs(y_at - 0.31415926) < 5e-8
    assert not pr.slope_ok


def test_a_slope_spike_narrower_than_the_grid_is_refused_and_the_sector_still_proved():
    M = _model(SPIKE)
    assert M.sector_info.slope_bound[0] < 0.0500001                # the sampling misses it
    pr = M.proof
    assert pr.sector_ok, pr.sector_text
    assert not pr.slope_ok and "0.075" in pr.slope_text


@pytest.mark.parametrize("text, premise", [(WINDOW, "sector"), (SPIKE, "slope")], ids=["window", "spike"])
def test_qpp_design_refuses_a_feature_narrower_than_the_grid(tmp_path, text, premise):
    cfg = yaml.safe_load(Path(__file__).parents[3].joinpath("configs", "qpp_unstable.yaml").read_text())
    cfg["nonlinearity"]["f1"] = [text]
    cfg["nonlinearity"]["parameters"] = {"k": {"min": 0.95, "max": 1.05, "nominal": 1.0}}
    for s in cfg["simulation"].get("scenarios", []):
        s["parameters"] = {"k": 1.05}
    cfg["output"] = {"root": str(tmp_path / "runs"), "figures": False}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    t0 = time.monotonic()
    r = CliRunner().invoke(app, ["design", str(path)])
    assert time.monotonic() - t0 < 60
    assert r.exit_code == EXIT_NUMERICAL, r.output          # exit 3: no certified design
    assert f"[FAILS] {premise}: " in r.output and "not proved" in r.output
