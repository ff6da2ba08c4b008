"""The strict config base (acmm_qpp.config_model): a YAML boolean is not a number (``orbits: true``
is refused, naming the field, in the acmm, sweep and qpp configs: pydantic's lax mode alone would
read it as 1), and an unknown key names the closest valid key of its model."""
from __future__ import annotations

from typing import Literal, Optional, Union

import pytest
import yaml

from acmm.io.config import parse_config
from acmm_qpp.config_model import _boolean_as_number as boolean_as_number
from acmm_qpp.errors import ConfigError
from qpp.io.config import parse_config as parse_qpp
from tests.conftest import CONFIGS, invoke


@pytest.mark.parametrize("annotation, value, refused", [
    (float, True, True),
    (int, False, True),
    (Optional[float], True, True),
    (Optional[tuple[float, float]], [1.0, True], True),
    (tuple[float, float], [1.0, 2.0], False),
    (list[list[float]], [[0.0, 1.0], [False, 2.0]], True),
    (list[list[float]], [[0.0, 1.0], [3.0, 2.0]], False),
    (bool, True, False),
    (Union[bool, float], True, False),
    (Literal["a", "b"], True, False),
    (str, True, False),                  # pydantic refuses it itself
    (tuple[str, float], ["x", True], True),
    (tuple[str, float], ["x", 2.0], False),
    (dict[str, float], {"c": True}, True),                      # mappings' values too (review)
    (dict[str, list[float]], {"bias_roll": [True, 0.0]}, True),
    (dict[str, float], {"c": 1.0}, False),
    (Optional[dict[str, bool]], {"c": True}, False),
])
def test_boolean_as_number(annotation, value, refused):
    assert boolean_as_number(annotation, value) is refused


@pytest.mark.parametrize("app, config, override, field", [
    ("acmm", "mb3", "simulation.orbits=true", "simulation.orbits"),
    ("acmm", "mb3", "design.sector.sigma=false", "design.sector.sigma"),
    ("acmm", "mb3", "inertia.I11=true", "inertia.I11"),
    ("acmm", "sweep_smoke", "sweep.orbits=true", "sweep.orbits"),
    ("acmm", "sweep_smoke", "sweep.monte_carlo.offset_pitch.uniform=[true, 2]",
     "sweep.monte_carlo.offset_pitch.uniform"),
    ("qpp", "qpp_siso", "hinf.rho=true", "hinf.rho"),
    ("qpp", "qpp_siso", "plant.A=[[true, 1], [0, -1]]", "plant.A"),
    ("qpp", "qpp_siso", "design.sector=[[false, 0.5]]", "design.sector"),
    ("qpp", "qpp_siso", "nonlinearity.omega=true", "omega"),
    ("qpp", "qpp_cubic2", "simulation.scenarios.0.parameters={c: true}", "simulation.scenarios.0.parameters"),
])
def test_boolean_in_a_number_field_is_one_error_line(tmp_runs, app, config, override, field):
    if app == "acmm":
        from acmm.cli.app import app as typer_app
    else:
        from qpp.cli import app as typer_app
    r = invoke(typer_app, "validate", config, override)
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), r.output
    assert f"{field}: expected a number, got a boolean" in lines[0]
    assert "Traceback" not in r.output and not (tmp_runs / "runs").exists()


def test_booleans_still_accepted_where_the_field_is_a_switch(tmp_runs):
    from acmm.cli.app import app as acmm_app
    from qpp.cli import app as qpp_app

    assert invoke(acmm_app, "validate", "mb3", "output.figures=false").exit_code == 0
    assert invoke(qpp_app, "validate", "qpp_siso", "spheres.adapt_T=true").exit_code == 0


def test_unknown_key_hints():
    d = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
    d["inertia"] = {"Ixx": 23.22e6, "I22": 1.30e6, "I33": 23.23e6}
    with pytest.raises(ConfigError, match=r"inertia\.Ixx: unknown key \(valid keys: I11, I22"):
        parse_config(d)
    d = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
    d["simulaton"] = {"orbits": 2}
    with pytest.raises(ConfigError, match=r"simulaton: unknown key \(did you mean `simulation`\?\)"):
        parse_config(d)
    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["nonlinearity"]["omgea"] = 1.0
    with pytest.raises(ConfigError, match=r"did you mean `omega`"):
        parse_qpp(q)
