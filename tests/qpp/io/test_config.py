"""qpp configs (qpp.io.config).  The user's own plants (a review's findings): stated sectors that
do not hold φ, channel counts the circle criterion cannot take, scenario parameters out of range,
a twelve-output plant that validates.  The nonlinearity section: library forms and stated sector,
β3 and β4 overrides.  The sample budget of a nonlinearity's sector: a channel on many outputs is
refused naming f1, the message names what can be lowered."""
import numpy as np
import pytest
import yaml

from acmm_qpp.errors import ConfigError
from qpp.io.config import _check_sample_count, load_config, parse_config
from qpp.model.nonlin import ExpressionModel

from tests.conftest import CONFIGS
from tests.qpp.conftest import _base, _cfg


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


def test_library_forms_and_stated_overrides(tmp_path):
    d = _cfg("qpp_saturation", tmp_path)
    d["nonlinearity"]["f1"] = [{"form": "dead_zone", "output": 1, "gain": "-k", "level": 0.3}]
    d["nonlinearity"]["parameters"] = {"k": {"min": 1.0, "max": 2.0}}
    for sc in d["simulation"]["scenarios"]:
        sc["parameters"] = None
    m = parse_config(d).expression_model()
    # dead zone: (y - sat(y, .3))/y in [0, 0.9] on |y| <= 3; phi = -(k - 1.5)·dz(y) -> ±0.5·0.9
    np.testing.assert_allclose(m.sector_info.sector, [[-0.45, 0.45]], rtol=1e-6)
    d["nonlinearity"]["f1"] = [{"form": "sin", "output": 1, "gain": "k"}]
    m = parse_config(d).expression_model()
    np.testing.assert_allclose(m.sector_info.sector, [[-0.5, 0.5]], rtol=1e-6)
    d["nonlinearity"]["f1"] = ["k*sin(y)"]                     # y is y1 when p = 1
    np.testing.assert_allclose(parse_config(d).expression_model().sector_info.sector, [[-0.5, 0.5]], rtol=1e-6)
    d["simulation"]["scenarios"][0]["gamma"] = 0.1
    with pytest.raises(ConfigError, match="not gamma"):
        parse_config(d)
    d["simulation"]["scenarios"][0]["gamma"] = 0.0
    d["nonlinearity"].update({"sector": [[-0.7, 0.7]], "beta3": 0.01, "beta4": 0.02})
    d["simulation"]["t_final"] = 2.0
    from qpp.design.certificate import certify, default_sector

    cfg = parse_config(d)
    np.testing.assert_array_equal(default_sector(cfg), [[-0.7, 0.7]])
    res = certify(cfg, [[-10.0, -4.0]], [[20.0]], [[-1.0], [-0.5]], 1e-4)
    st = res.threshold("stated")
    assert (st.beta3, st.beta4) == (0.01, 0.02) and res.bookkeeping == "consistent"   # stated: reported only
    assert st.m == pytest.approx(0.3 / (0.05 + 0.3 * 0.01 + 0.02))


def test_channel_depending_on_many_outputs_refused_naming_f1():
    p = 12
    exprs = ["0.01*c*sin(" + "+".join(f"y{i + 1}" for i in range(p)) + ")"] + ["0"] * (p - 1)
    m = ExpressionModel(exprs, p, {"c": (0.9, 1.1, 1.0)}, [[-1.0, 1.0]] * p, np.eye(p), 1.0)
    with pytest.raises(ValueError, match=r"nonlinearity: .*channel 1, on 12 outputs.*fewer outputs per channel "
                                         r"\(nonlinearity\.f1\).*ACMM_LIMIT_QPP_SECTOR_POINTS") as exc:
        _check_sample_count(m)
    assert "n_grid" not in str(exc.value)          # n_grid sets only 1- and 2-output grids


def test_sample_count_message_names_what_can_be_lowered():
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
