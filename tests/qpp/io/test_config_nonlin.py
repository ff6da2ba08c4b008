"""The nonlinearity section of a qpp config (qpp.io.config_nonlin): library forms and stated
sector, β3 and β4 overrides."""
import numpy as np
import pytest

from acmm_qpp.errors import ConfigError
from qpp.io.config import parse_config

from tests.qpp.conftest import _cfg


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
