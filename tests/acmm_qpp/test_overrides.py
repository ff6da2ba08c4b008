"""Command-line overrides (acmm_qpp.overrides): dotted paths, removal, list elements and their
errors, for the acmm, sweep and qpp configs."""
from __future__ import annotations

import pytest

from acmm.io.config import load_config
from acmm_qpp.errors import ConfigError

from tests.conftest import invoke


def qpp(*args):
    from qpp.cli import app

    return invoke(app, *args)


def test_override_on_the_default_config_and_removal():
    cfg = load_config(None, ["simulation.orbits=3", "~schedule"])
    assert cfg.name == "staircase" and cfg.simulation.orbits == 3 and cfg.schedule is None
    # a unit string is a YAML scalar like any other, converted by the loader
    assert load_config("mb3", ["actuators.torque_limit=203.4 N*m"]).actuators.torque_limit == \
        pytest.approx(150.0, rel=1e-3)


def test_overrides_for_qpp_and_sweep(tmp_runs):
    from acmm.sweep.config import load_sweep
    from qpp.io.config import load_config as load_qpp

    assert load_qpp("qpp_siso", ["hinf.rho=2e-4"]).hinf.rho == 2e-4
    sw = load_sweep("sweep_smoke", ["sweep.n_runs=3", "sweep.orbits=1"])
    assert sw.spec.n_cases() == 3 and sw.spec.orbits == 1
    with pytest.raises(ConfigError, match=r"sweep\.n_run: unknown key \(did you mean `n_runs`\?\)"):
        load_sweep("sweep_smoke", ["sweep.n_run=3"])
    r = qpp("validate", "qpp_siso", "spheres.beta_o=0.3", "--show")
    assert r.exit_code == 0 and "beta_o: 0.3" in r.stdout


def test_override_paths_and_errors():
    from acmm_qpp.overrides import OverrideSyntaxError, apply_overrides

    data = {"a": {"b": [1, 2, 3]}, "c": 1}
    out = apply_overrides(data, ["a.b.1=5", "d.e=x", "~c", "~no.such", "a.f="])
    assert out == {"a": {"b": [1, 5, 3], "f": None}, "d": {"e": "x"}}
    assert data == {"a": {"b": [1, 2, 3]}, "c": 1}                 # the input is not modified
    for bad, match in ((["a.b.7=1"], "no such list element"), (["c.x=1"], "cannot go inside"),
                       (["z.0=1"], "give the whole list"), (["c=[1"], "not valid YAML")):
        with pytest.raises(ConfigError, match=match):
            apply_overrides(data, bad)
    with pytest.raises(OverrideSyntaxError):
        apply_overrides(data, ["a..b=1"])


def test_a_loaded_config_carries_its_origin_and_compares_by_its_values():
    """The file and overrides a config was loaded from travel with the object (config.yaml's
    header), not in a table keyed by id(); equality, the YAML dump and a pickled copy see it right."""
    import pickle

    import yaml

    from acmm.io.config import parse_config
    from acmm.sweep.config import load_sweep
    from acmm_qpp.outputs import config_text_of
    from acmm_qpp.overrides import origin_of

    cfg = load_config("mb3", ["design.sector.sigma=0.9"])
    source, overrides = origin_of(cfg)
    assert source.endswith("mb3.yaml") and overrides == ["design.sector.sigma=0.9"]
    plain = parse_config(yaml.safe_load(cfg.to_yaml()))           # the same values, no origin
    assert origin_of(plain) == (None, []) and plain == cfg
    assert "loaded_from" not in cfg.to_yaml() and "loaded_from" not in repr(cfg)
    assert origin_of(pickle.loads(pickle.dumps(cfg))) == (source, overrides)
    text = config_text_of(cfg)
    assert f"# source: {source}\n" in text and "# command-line overrides: design.sector.sigma=0.9\n" in text
    assert "# source:" not in config_text_of(plain)
    assert origin_of(load_sweep("sweep_smoke"))[0].endswith("sweep_smoke.yaml")
    assert origin_of(object()) == (None, [])
