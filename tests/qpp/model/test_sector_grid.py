"""Plants with many outputs.  The sector of an expression nonlinearity is sampled per channel,
over the outputs that channel depends on (qpp.model.sector_grid): a 12-output plant with one
nonlinearity per channel validates, with the bounds of an independent brute-force evaluation or
of the same φ in a one-output model; its scenario figure keeps a legend one can read."""
import numpy as np
import pytest
import yaml

from qpp.model.nonlin import ExpressionModel

from tests.conftest import CONFIGS


def _brute_ratio(fn, y_range, n=2001):
    """min/max of φ(y)/y on a fine 1-D grid (independent of the model's grid and refinement)."""
    y = np.linspace(*y_range, n)
    y = y[y != 0]
    r = fn(y) / y
    return r.min(), r.max()


def test_decoupled_channels_each_get_their_own_one_output_grid():
    p = 8
    exprs = [f"c*sat(y{i + 1})" if i % 2 == 0 else f"0.1*c*sin(y{i + 1})" for i in range(p)]
    m = ExpressionModel(exprs, p, {"c": (0.8, 1.2, 1.0)}, [[-2.0, 2.0]] * p, np.eye(p), 1.0, n_grid=41)
    assert all(m.channel_outputs(i) == [i] for i in range(p))
    # 8 one-output grids, not one 8-output grid ((41 + extras)^8 ≈ 1e13 points)
    assert m.sector_points() == m.theta_sample_count() * sum(m.sector_grid_size(i) for i in range(p))
    assert m.sector_points() < 10_000
    si = m.sector_info
    assert si.diagonal.all()
    for i in range(p):
        # φ_i = (c − 1)·f(y_i), c − 1 ∈ [−0.2, 0.2]: the ratio's extremes by brute force
        f = (lambda y: np.clip(y, -1, 1)) if i % 2 == 0 else (lambda y: 0.1 * np.sin(y))
        lo, hi = _brute_ratio(f, (-2.0, 2.0))
        want = max(abs(lo), abs(hi)) * 0.2
        assert si.sector[i, 0] <= -want * (1 - 1e-9) and si.sector[i, 1] >= want * (1 - 1e-9)
        assert si.sector[i, 1] <= want * (1 + 1e-6)


def test_partial_dependence_matches_the_joint_grid():
    """A channel of y1 alone in a 3-output plant: its bounds equal those of the same φ in a
    one-output model (the other outputs cannot change φ_1)."""
    three = ExpressionModel(["c*y1**3", "0.2*c*sin(y2 + y3)", "0"], 3, {"c": (0.9, 1.1, 1.0)},
                            [[-1.0, 1.0], [-0.5, 0.5], [-0.5, 0.5]], np.eye(3), 1.0, n_grid=21)
    one = ExpressionModel(["c*y1**3"], 1, {"c": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]], [[1.0]], 1.0, n_grid=21)
    assert three.channel_outputs(0) == [0] and three.channel_outputs(1) == [1, 2]
    assert three.channel_outputs(2) == [2]         # a ratio channel keeps its own output (the divisor)
    np.testing.assert_array_equal(three.sector_info.sector[0], one.sector_info.sector[0])
    # the coupled channel: ±sup(|∂φ/∂y2| + |∂φ/∂y3|) = ±0.2·0.1·2 = ±0.04
    np.testing.assert_allclose(three.sector_info.sector[1], [-0.04, 0.04], rtol=1e-9)


def test_channel_depending_on_many_outputs_refused_naming_f1():
    from qpp.io.config_checks import _check_sample_count

    p = 12
    exprs = ["0.01*c*sin(" + "+".join(f"y{i + 1}" for i in range(p)) + ")"] + ["0"] * (p - 1)
    m = ExpressionModel(exprs, p, {"c": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * p, np.eye(p), 1.0)
    with pytest.raises(ValueError, match=r"nonlinearity: .*channel 1, on 12 outputs.*fewer outputs per channel "
                                         r"\(nonlinearity\.f1\).*ACMM_LIMIT_QPP_SECTOR_POINTS") as exc:
        _check_sample_count(m)
    assert "n_grid" not in str(exc.value)          # n_grid sets only 1- and 2-output grids


def test_twelve_output_plant_with_one_nonlinearity_per_channel_validates(tmp_path):
    """Twelve masses, a cubic spring of uncertain stiffness on the first: the config validates
    (its sector found on twelve one-output grids) with the sector of the one-mass case."""
    from qpp.io.config import load_config

    k = 12
    A = np.zeros((2 * k, 2 * k))
    A[:k, k:] = np.eye(k)
    A[k:, :k] = -2 * np.eye(k)
    A[k:, k:] = -0.2 * np.eye(k)
    B = np.vstack([np.zeros((k, k)), np.eye(k)])
    C = np.hstack([np.eye(k), np.zeros((k, k))])
    base = yaml.safe_load((CONFIGS / "qpp_cubic2.yaml").read_text())
    base["name"] = "twelve"
    base["plant"] = {"A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "G": B.tolist(),
                     "Ac": np.zeros((k, k)).tolist(), "Bc": np.eye(k).tolist(), "Cc": np.eye(k).tolist()}
    base["nonlinearity"]["f1"] = [{"form": "cubic", "output": 1, "gain": "-c"}] + ["0"] * (k - 1)
    base["nonlinearity"]["y_range"] = [[-1.0, 1.0]] * k
    base["simulation"]["r_o"] = [[{"kind": "step", "amplitude": 0.5, "t_on": 0.0}]] * k
    base["simulation"]["scenarios"] = [{"name": "c_min", "parameters": {"c": 0.9}}]
    path = tmp_path / "twelve.yaml"
    path.write_text(yaml.safe_dump(base))
    cfg = load_config(path)
    si = cfg.expression_model().sector_info
    # φ_1 = −(c − 1)·y1³ on |y1| ≤ 1, c ∈ [0.9, 1.1]: the sector [−0.1, 0.1]; the others are 0
    np.testing.assert_allclose(si.sector[0], [-0.1, 0.1], rtol=1e-12)
    assert np.all(np.abs(si.sector[1:]) <= 1e-12)


def test_scenario_figure_of_many_outputs_keeps_a_short_legend(monkeypatch, tmp_path):
    """Twelve outputs: the legend names the line styles and the output with the largest error
    (not 48 + 12 + 12 entries), and the title the scenario's parameters by name."""
    from qpp import plots
    from qpp.simulate.closed_loop import SimResult

    figs = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, **kw: figs.append(fig))
    p, N = 12, 50
    t = np.linspace(0, 1, N)
    y = np.outer(np.arange(1, p + 1), t) * 0.01
    y_o = np.zeros((p, N))
    err = np.abs(y - y_o).max(axis=1)
    sim = SimResult("a", t, y, y, y, y_o, y, y, y, y, 0.9, float(err.max()), err, 0.3, {"c": 0.9})
    plots.plot_scenario(sim, tmp_path / "s.png")
    (fig,) = figs
    texts = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes]
    assert len(texts[0]) == 4 and all("all outputs" in s for s in texts[0])
    assert texts[1] == ["other outputs", "|y12 − y_o12| (largest)", "β_o = 0.3"]
    assert texts[2] == ["u1 … u12"]
    assert fig._suptitle.get_text() == "scenario a (c = 0.9)"


def test_small_n_grid_on_three_outputs_not_coarser_than_the_joint_grid():
    """A narrow bump on y1 in a 3-output plant: the channel's grid holds the points of the grid
    over all three outputs (27 per axis), so n_grid = 5 still finds it."""
    bump = "c*y1*(1 + 3*exp(-((y1 - 0.3)/0.01)**2))"
    m = ExpressionModel([bump, "0", "0"], 3, {"c": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * 3, np.eye(3), 1.0, n_grid=5)
    grid = m._y_grid(m.channel_outputs(0))[0]
    assert set(np.linspace(-1.0, 1.0, 27)) <= set(grid) and set(np.linspace(-1.0, 1.0, 5)) <= set(grid)
    # the ratio (c − 1)(1 + 3 e^…) reaches 0.1 · 4 at y1 = 0.3: the 27-point axis has a point
    # 0.008 from it (the 5-point one none nearer than 0.2), from which the refinement climbs
    lo, hi = _brute_ratio(lambda y: y * (1 + 3 * np.exp(-((y - 0.3) / 0.01) ** 2)), (-1.0, 1.0), n=400001)
    want = 0.1 * max(abs(lo), abs(hi))
    np.testing.assert_allclose(m.sector_info.sector[0], [-want, want], rtol=1e-6)


def test_sample_count_message_names_what_can_be_lowered():
    from qpp.io.config_checks import _check_sample_count

    exprs = [f"c*e*y{i + 1}**3*cos(t)" for i in range(12)]
    m = ExpressionModel(exprs, 12, {"c": (0.9, 1.1, 1.0), "e": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * 12, np.eye(12),
                        1.0, n_grid=201)
    with pytest.raises(ValueError) as exc:
        _check_sample_count(m)
    msg = str(exc.value)
    # the factors: Σ over the channels of 3² parameter samples × 205 grid points, × 256 times
    assert "over 12 channels: 9 samples of 2 uncertain parameters" in msg and "2.46e+03 points in all" in msg
    assert "× 256 times on the channels that depend on t" in msg and "on 1 output)" in msg
    assert m.sector_points() == 9 * 12 * 205 * 256
    assert "a coarser nonlinearity.n_grid (now 201)" in msg and "outputs per channel" not in msg


def test_only_the_channels_that_depend_on_t_count_their_time_samples():
    """The sample budget multiplied every channel's grid by the time samples when any one channel
    depended on t, so a design that runs in seconds was refused at every n_grid (review).  The
    count now follows the work: φ_i without t is evaluated once per output point."""
    m = ExpressionModel(["c*y1**3", "0.1*c*y2*sin(t)", "c*sat(y3)"], 3, {"c": (0.9, 1.1, 1.0)},
                        [[-1.0, 1.0]] * 3, np.eye(3), 10.0, n_grid=21, n_t=256)
    sizes = [m.sector_grid_size(i) for i in range(3)]
    assert m.time_sample_count() == 256
    assert m.sector_points() == m.theta_sample_count() * (sizes[0] + 256 * sizes[1] + sizes[2])
    # and the count is the work done: sector_info evaluates φ at exactly these points
    assert m.sector_info.n_samples == m.sector_points()
