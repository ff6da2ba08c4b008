"""Hints attached to the error messages (acmm_qpp.hints): an unknown key's closest valid key (the
numerical hints are raised with their errors: tests/acmm_qpp/test_errors.py)."""
from __future__ import annotations

import pytest
import yaml

from acmm.io.config import parse_config
from acmm_qpp.errors import ConfigError

from tests.conftest import CONFIGS


def _mb3():
    return yaml.safe_load((CONFIGS / "mb3.yaml").read_text())


# ---------------------------------------------------------------------------------------------
# item 7: hints
# ---------------------------------------------------------------------------------------------
def test_unknown_key_hints(tmp_path):
    d = _mb3()
    d["inertia"] = {"Ixx": 23.22e6, "I22": 1.30e6, "I33": 23.23e6}
    with pytest.raises(ConfigError, match=r"inertia\.Ixx: unknown key \(valid keys: I11, I22"):
        parse_config(d)
    d = _mb3()
    d["simulaton"] = {"orbits": 2}
    with pytest.raises(ConfigError, match=r"simulaton: unknown key \(did you mean `simulation`\?\)"):
        parse_config(d)
    from qpp.io.config import parse_config as parse_qpp

    q = yaml.safe_load((CONFIGS / "qpp_siso.yaml").read_text())
    q["nonlinearity"]["omgea"] = 1.0
    with pytest.raises(ConfigError, match=r"did you mean `omega`"):
        parse_qpp(q)
