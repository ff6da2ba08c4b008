"""qpp configs of the user's own plants (qpp.io.config; a review's findings): stated sectors that
do not hold φ, channel counts the circle criterion cannot take, scenario parameters out of range,
a twelve-output plant that validates."""
import numpy as np
import pytest
import yaml

from acmm_qpp.errors import ConfigError
from qpp.io.config import load_config, parse_config

from tests.conftest import CONFIGS
from tests.qpp.conftest import _base


@pytest.mark.parametrize("field", ["nonlinearity.sector", "design.sector"])
def test_a_stated_sector_narrower_than_phi_is_refused(field):
    # φ = k·sat(y, 0.5), |k| ≤ 0.3: its sector is ±0.3 (exactly, at |y| ≤ 0.5)
    with pytest.raises(ConfigError, match=r"does not hold φ_1.*\[-0\.3, 0\.3\]"):
        parse_config(_base(**{field: [[-0.01, 0.01]]}))
    parse_config(_base(**{field: [[-0.3, 0.3]]}))            # the exact sector, stated: accepted
    parse_config(_base(**{field: [[-0.5, 0.4]]}))            # wider: accepted


def test_a_sinusoidal_plant_needs_as_many_phi_channels_as_outputs():
    data = _base(**{"plant.A": [[0, 1, 0], [0, 0, 1], [-1, -2, -2]], "plant.B": [[0], [0], [1]],
                    "plant.C": [[1, 0, 0], [0, 1, 0]], "plant.G": [[0], [0], [1]], "plant.Bc": [[1, 0]],
                    "nonlinearity": {"kind": "sinusoidal", "F0": [[0.0, 0.0]], "F1": [[0.1, 0.0]],
                                     "F_unc": [[1.0, 0.0]], "omega": 1.0, "gamma_max": 0.05},
                    "simulation.r_o": [[{"kind": "step", "amplitude": 0.5}], [{"kind": "step", "amplitude": 0.0}]],
                    "simulation.scenarios": [{"name": "g", "gamma": 0.05}]})
    with pytest.raises(ConfigError, match="as many disturbance channels as outputs"):
        parse_config(data)


@pytest.mark.parametrize("name, gamma, ok", [("qpp_siso", 5.0, False), ("qpp_siso", -0.05, True),
                                             ("qpp_manipulator", 0.0, False), ("qpp_manipulator", 1000.0, False),
                                             ("qpp_manipulator", 50.0, True)])
def test_scenario_gamma_within_the_nonlinearity_range(name, gamma, ok):
    over = [f"simulation.scenarios.0.gamma={gamma}"]
    if ok:
        load_config(name, over)
    else:
        with pytest.raises(ConfigError, match="gamma .* outside"):
            load_config(name, over)
    with pytest.raises(ConfigError, match="takes gamma, not parameters"):
        load_config(name, ["simulation.scenarios.0.parameters={dm: 1}"])


def test_a_scenario_cannot_take_the_cartesian_figures_name():
    """The polar arm writes qpp_sim_cartesian.png beside qpp_sim_<scenario>.png: a scenario named
    'cartesian' lost one of the two figures silently; it is refused, elsewhere allowed."""
    with pytest.raises(ConfigError, match="'cartesian' is the polar arm's cartesian figure"):
        load_config("qpp_manipulator", ["simulation.scenarios.0.name=cartesian"])
    assert load_config("qpp_siso", ["simulation.scenarios.0.name=cartesian"]).simulation.scenarios[0].name == "cartesian"


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
