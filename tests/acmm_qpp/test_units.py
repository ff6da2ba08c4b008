"""Physical units in the configs (acmm_qpp.units): unit strings in the acmm, sweep and qpp configs."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from acmm.io.config import parse_config
from acmm_qpp.errors import ConfigError

from tests.conftest import CONFIGS


# ---------------------------------------------------------------- unit strings everywhere
def test_unit_strings_in_acmm_sweep_and_qpp_configs():
    from acmm.sweep.spec import SweepSpec
    from acmm.model.unit_systems import FT_LBF_IN_NM as k
    from qpp.io.config import QppConfig

    base = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
    plain = parse_config(base)
    with_units = parse_config({**base, "design": {**base.get("design", {}), "R": f"{1e-4 / k ** 2!r} 1/(N*m)^2",
                                                  "sector": {"sigma": 0.5, "half_angle_deg": f"{np.pi / 4!r} rad"}}})
    assert with_units.design.R == pytest.approx(plain.design.R, rel=1e-12)
    assert with_units.design.sector.half_angle_deg == pytest.approx(45.0, rel=1e-12)
    with pytest.raises(ConfigError, match=r"^config: design\.R: unit 'N\*m' is not a unit of"):
        parse_config({**base, "design": {"R": "1 N*m"}})
    # sweep: grid values and distribution bounds in the parameter's unit
    s = SweepSpec.model_validate({"base": "ac", "grid": {"bias_pitch": [f"{k!r} N*m", 2.0], "offset_roll": ["1 rad"]}})
    assert s.grid["bias_pitch"] == pytest.approx([1.0, 2.0]) and s.grid["offset_roll"] == pytest.approx([np.degrees(1)])
    m = SweepSpec.model_validate({"base": "ac", "n_runs": 2, "monte_carlo": {"bias_roll": {"uniform": ["0 N*m", f"{k!r} N*m"]}}})
    assert m.monte_carlo["bias_roll"].uniform == pytest.approx((0.0, 1.0))
    with pytest.raises(ValueError, match="grid.bias_pitch: unit 'kg' is not a unit of ft"):
        SweepSpec.model_validate({"base": "ac", "grid": {"bias_pitch": ["1 kg"]}})
    # qpp: time, frequency, 1/s, mass, length, kg·m²
    q = yaml.safe_load((CONFIGS / "qpp_manipulator.yaml").read_text())
    ref = QppConfig.model_validate(q)
    q["spheres"]["T"] = f"{ref.spheres.T * 1000!r} ms"
    q["hinf"]["a"] = f"{ref.hinf.a * 60!r} 1/min"
    q["nonlinearity"].update(mu=f"{ref.nonlinearity.mu * 1000!r} g", a=f"{ref.nonlinearity.a * 100!r} cm",
                             J1=f"{ref.nonlinearity.J1 * 1e4!r} kg*cm^2")
    q["simulation"]["t_final"] = f"{ref.simulation.t_final / 60!r} min"
    got = QppConfig.model_validate(q)
    assert got.spheres.T == pytest.approx(ref.spheres.T, rel=1e-12)
    assert got.hinf.a == pytest.approx(ref.hinf.a, rel=1e-12)
    assert got.simulation.t_final == pytest.approx(ref.simulation.t_final, rel=1e-12)
    for f in ("mu", "a", "J1"):
        assert getattr(got.nonlinearity, f) == pytest.approx(getattr(ref.nonlinearity, f), rel=1e-12)
    q["spheres"]["T"] = "2 kg"
    with pytest.raises(ValueError, match="spheres.T"):
        QppConfig.model_validate(q)
