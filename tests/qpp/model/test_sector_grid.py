"""Plants with many outputs: the sector of an expression nonlinearity is sampled per channel, over
the outputs that channel depends on (qpp.model.sector_grid), with the bounds of an independent
brute-force evaluation or of the same φ in a one-output model."""
import numpy as np

from qpp.model.nonlin import ExpressionModel


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
