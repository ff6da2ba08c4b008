"""Hints attached to the error messages (acmm_qpp.hints): an unknown key's closest valid key, and
numerical hints that can help."""
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


def test_a_riccati_hint_never_suggests_the_method_that_failed():
    from acmm_qpp.hints import numerical_hint

    for used in ("scipy", "sign", "slycot"):
        for msg in (f"Riccati solve (method='{used}') residual 3e-6 above design.residual_tol",
                    f"sector LQR: Riccati solve (method='{used}') failed",
                    f"Riccati solve (method='{used}') did not converge"):
            hint = numerical_hint(msg)
            assert "riccati_method" in hint and used not in hint.split("riccati_method", 1)[1].split(")")[0], hint
    assert "scipy or sign or slycot" in numerical_hint("Riccati solve failed")


def test_hints_for_an_uncontrollable_pole_at_zero_and_a_narrow_sector_can_help():
    """'lower design.sector.sigma' cannot help an uncontrollable pole at 0 (no sector σ > 0 holds
    it), nor 'uncontrollable?' a controllable plant in a 1° sector (review)."""
    from acmm_qpp.hints import numerical_hint

    at0 = numerical_hint("sector LQR: open-loop pole λ/n = 0+0j lies outside the sector and is uncontrollable "
                         "(PBH ratio 3.2e-18); no feedback can move it")
    assert "sigma" not in at0 and "design.drf_mode" in at0
    away = numerical_hint("sector LQR: open-loop pole λ/n = 0.2+0j lies outside the sector and is uncontrollable")
    assert "lower design.sector.sigma" in away
    narrow = numerical_hint("sector LQR (shift): cannot shift the poles λ/n = [(-2.3+0.8j)] (uncontrollable?): "
                            "Riccati solve (method='scipy'): relative residual 1.2e-07 exceeds tolerance 1.0e-09")
    assert narrow.startswith("widen design.sector.half_angle_deg")
