"""The sample budget of a nonlinearity's sector (qpp.io.config_checks): a channel on many
outputs is refused naming f1, the message names what can be lowered."""
import numpy as np
import pytest

from qpp.model.nonlin import ExpressionModel


def test_channel_depending_on_many_outputs_refused_naming_f1():
    from qpp.io.config_checks import check_sample_count

    p = 12
    exprs = ["0.01*c*sin(" + "+".join(f"y{i + 1}" for i in range(p)) + ")"] + ["0"] * (p - 1)
    m = ExpressionModel(exprs, p, {"c": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * p, np.eye(p), 1.0)
    with pytest.raises(ValueError, match=r"nonlinearity: .*channel 1, on 12 outputs.*fewer outputs per channel "
                                         r"\(nonlinearity\.f1\).*ACMM_LIMIT_QPP_SECTOR_POINTS") as exc:
        check_sample_count(m)
    assert "n_grid" not in str(exc.value)          # n_grid sets only 1- and 2-output grids


def test_sample_count_message_names_what_can_be_lowered():
    from qpp.io.config_checks import check_sample_count

    exprs = [f"c*e*y{i + 1}**3*cos(t)" for i in range(12)]
    m = ExpressionModel(exprs, 12, {"c": (0.9, 1.1, 1.0), "e": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * 12, np.eye(12),
                        1.0, n_grid=201)
    with pytest.raises(ValueError) as exc:
        check_sample_count(m)
    msg = str(exc.value)
    # the factors: Σ over the channels of 3² parameter samples × 205 grid points, × 256 times
    assert "over 12 channels: 9 samples of 2 uncertain parameters" in msg and "2.46e+03 points in all" in msg
    assert "× 256 times on the channels that depend on t" in msg and "on 1 output)" in msg
    assert m.sector_points() == 9 * 12 * 205 * 256
    assert "a coarser nonlinearity.n_grid (now 201)" in msg and "outputs per channel" not in msg
