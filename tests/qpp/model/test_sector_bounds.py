"""The sampled sector bounds made tight and checked (qpp.model.sector_bounds): climbed to the
supremum between grid points, from a random check point, and in a basin the grid does not lead to."""
import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from acmm_qpp.errors import EXIT_NUMERICAL, ConfigError
from qpp.cli import app
from qpp.io.config import parse_config

from tests.qpp.conftest import _base, _cfg

runner = CliRunner()


def test_sampled_sector_climbs_to_the_supremum_between_grid_points():
    # a sector too small by any amount is no certificate: the grid's best points are refined to
    # the local extrema (qpp.model.sector_bounds.refine), in t and in the parameters
    from qpp.model.nonlin import ExpressionModel

    m = ExpressionModel(["dm*y*sin(2*t)"], 1, {"dm": (-0.1, 0.1, 0.0)}, [[-2, 2]], [[1.0]], 100.0)
    assert np.max(np.abs(np.sin(2 * m._t_grid()))) < 1 - 1e-6        # the grid alone: ±0.0999998
    np.testing.assert_allclose(m.sector_info.sector, [[-0.1, 0.1]], rtol=1e-12)
    assert m.sector_info.slope_bound[0] == pytest.approx(0.1, rel=1e-12)
    # extremum inside the parameter range: φ = y·(sin k − sin 0), k ∈ [0, 3] sampled at 0, 1.5, 3
    m = ExpressionModel(["y*sin(k)"], 1, {"k": (0.0, 3.0, 0.0)}, [[-1, 1]], [[1.0]], 1.0)
    lo, hi = m.sector_info.sector[0]
    assert lo == pytest.approx(0.0, abs=1e-12) and hi == pytest.approx(1.0, rel=1e-12)
    assert m.beta3(1.0) == pytest.approx(1.0, rel=1e-12)        # φ independent of t: the slope bound


@pytest.mark.slow
def test_extremum_missed_by_the_grid_is_climbed_from_the_random_check(tmp_path):
    """A bump narrower than the grid's spacing: a random check point lands near it, and the
    sector is climbed from there to the bump's peak (the 1 % widening alone stayed at 0.209
    where the ratio reaches 0.291), the slope (β3) to its flank; the design says so, in its
    output and in qpp_design.h5."""
    import h5py

    from qpp.model.nonlin import ExpressionModel

    bump = "-c*y1**3 + (c - 1)*y1*3*exp(-((y1 - 0.3)/0.002)**2)"
    m = ExpressionModel([bump], 1, {"c": (0.9, 1.1, 1.0)}, [[-1, 1]], [[1.0]], 1.0, n_grid=5)
    y = np.linspace(-1, 1, 2_000_001)                     # brute force: (c − 1)(−y² + 3e^…), |c − 1| ≤ 0.1
    peak = 0.1 * np.max(np.abs(-y ** 2 + 3 * np.exp(-((y - 0.3) / 0.002) ** 2)))
    assert not m.sector_info.verified
    lo, hi = m.sector_info.sector[0]            # contains the brute force's peak, and is tight
    assert -peak * (1 + 1e-6) <= lo <= -peak and peak <= hi <= peak * (1 + 1e-6)
    cfg = _cfg("qpp_cubic2", tmp_path)
    cfg["nonlinearity"].update(f1=[bump, "0"], n_grid=5)
    path = tmp_path / "bump.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = runner.invoke(app, ["design", str(path)])
    # β3 is now the bump's slope (~37, was the grid's 0.5): no certificate (it was "certified")
    assert r.exit_code == EXIT_NUMERICAL and "no certified design" in r.output, r.output
    assert "sector of φ: random check points" in r.output
    with h5py.File(tmp_path / "runs" / "qpp_cubic2" / "qpp_design.h5") as f:
        assert f["sector_verified"][()] == 0
        # the stored sector is the proved enclosure (interval branch and bound, issue 43): it
        # contains the sampled one and exceeds it by less than the proof's relative gap
        stored = f["sector"][0]
        assert stored[0] <= lo and stored[1] >= hi
        np.testing.assert_allclose(stored, [lo, hi], rtol=1e-3)


@pytest.mark.parametrize("global_search", [False, True])
def test_random_check_climbs_both_bounds_and_the_slope_of_a_missed_feature(global_search, monkeypatch):
    """From the random point that found a feature the grid missed: the other bound of the same
    bump (at the other parameter corner), the slope (β3 ≥ the steepest flank), and for a coupled
    channel the slope of a narrow step; brute-force references on fine grids.  Without the global
    search (the random check's own climb) and with it (which finds the features before the random
    check: then nothing is left for it to find)."""
    import qpp.model.nonlin
    from qpp.model.nonlin import ExpressionModel

    if not global_search:
        monkeypatch.setattr(qpp.model.nonlin, "global_search", lambda model, i, kinds, bounds: dict(bounds))

    y = np.linspace(-1, 1, 2_000_001)
    bump = lambda v: v * (1 + 3 * np.exp(-((v - 0.7071) / 0.001) ** 2))      # noqa: E731
    m = ExpressionModel(["c*y*(1 + 3*exp(-((y - 0.7071)/0.001)**2))"], 1, {"c": (0.9, 1.1, 1.0)}, [[-1, 1]],
                        [[1.0]], 1.0)
    assert m.sector_info.verified is global_search
    peak = 0.1 * np.max(bump(y[y != 0]) / y[y != 0])                     # (c − 1) ∈ [−0.1, 0.1]
    lo, hi = m.sector_info.sector[0]
    assert lo <= -peak * (1 - 1e-9) and hi >= peak * (1 - 1e-9)          # both sides of the bump
    # the slope is climbed on the flank next to the random point: the bump's other flank is 0.1 %
    # steeper (a sampled bound; the design says so: sector_verified = 0, --strict fails)
    steepest = 0.1 * np.max(np.abs(np.gradient(bump(y), y)))
    assert m.sector_info.slope_bound[0] >= steepest * (1 - 1e-2)
    assert m.beta3(1.0) >= steepest * (1 - 1e-2)
    # a coupled channel with a step 0.0005 wide in y1: its slope is the step's, 60
    step = "c*(y2 + 0.3*tanh((y1 - 0.325)/0.0005) + 0.3*tanh(0.325/0.0005))"
    m = ExpressionModel([step, "0"], 2, {"c": (0.9, 1.1, 1.0)}, [[-1, 1], [-1, 1]], np.eye(2), 1.0)
    assert not m.sector_info.diagonal[0] and (global_search or not m.sector_info.verified)
    want = 0.1 * 0.3 / 0.0005 + 0.1                       # |c − 1|·(∂/∂y1 at the step + ∂/∂y2)
    assert m.sector_info.slope_bound[0] >= want * (1 - 1e-6)
    np.testing.assert_array_equal(m.sector_info.sector[0], [-m.sector_info.slope_bound[0],
                                                            m.sector_info.slope_bound[0]])


def test_a_saturation_on_a_wide_output_range_is_sector_bounded():
    """k·sat(y, 0.5) on |y| ≤ 1e6: φ/y steps from 0.3 (|y| < 0.5) down between the grid's points
    near 0; that is a corner, not growth without bound (√|y| still is refused)."""
    info = parse_config(_base(**{"nonlinearity.y_range": [[-1e6, 1e6]]})).expression_model().sector_info
    np.testing.assert_allclose(info.sector, [[-0.3, 0.3]], atol=1e-9)
    for rng in ([[-2, 2]], [[-1e6, 1e6]]):
        with pytest.raises(ConfigError, match="not sector-bounded near y = 0"):
            parse_config(_base(**{"nonlinearity.y_range": rng, "nonlinearity.f1": ["k*sign(y1)*abs(y1)**0.5"]}))


def test_a_supremum_in_a_basin_the_grid_does_not_lead_to_is_found():
    """φ/y = −(c − 1)y² + (sin wt − sin 2t)/2 (f1 = −c y³ + y sin(wt)/2, nominal c = 1, w = 2):
    its supremum 1.125 + 1 = 2.125 at y = ±1.5, c = 0.5, sin wt = 1 = −sin 2t (w = 10/7,
    t = 7π/4) lies among many local maxima in (w, t); the grid's best point climbed to 2.078."""
    data = _base(**{"plant.A": [[0, 1], [-1, -0.5]], "plant.C": [[1, 0]],
                    "nonlinearity.f1": ["-c*y1**3 + 0.5*y1*sin(w*t)"],
                    "nonlinearity.parameters": {"c": {"min": 0.5, "max": 1.5, "nominal": 1.0},
                                                "w": {"min": 1.0, "max": 3.0, "nominal": 2.0}},
                    "nonlinearity.y_range": [[-1.5, 1.5]], "nonlinearity.t_range": 10.0,
                    "simulation.scenarios": [{"name": "c05", "parameters": {"c": 0.5, "w": 1.4285714}}]})
    info = parse_config(data).expression_model().sector_info
    exact = 0.5 * 1.5 ** 2 + 1.0
    np.testing.assert_allclose(info.sector, [[-exact, exact]], rtol=1e-7)
