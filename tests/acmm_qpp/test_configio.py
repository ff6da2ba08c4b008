"""YAML config files (acmm_qpp.configio): merge keys are read as PyYAML's safe loader reads them,
a key written twice is still refused; command-line overrides: dotted paths, removal, list
elements and their errors, for the acmm, sweep and qpp configs."""
from __future__ import annotations

import pytest

from acmm.io.config import load_config
from acmm_qpp.errors import ConfigError

from tests.conftest import invoke


def test_yaml_merge_keys_are_read_and_duplicates_still_refused(tmp_path):
    """``<<: *anchor`` (a YAML merge key) is read as PyYAML's safe loader reads it, the keys
    written next to it overriding the merged ones; a key written twice is still refused (the
    merge key used to be refused: "could not determine a constructor")."""
    from acmm_qpp.configio import read_yaml

    p = tmp_path / "m.yaml"
    p.write_text("ref: &I {I11: 21970000, I22: 13320000, I33: 32130000}\ninertia: {<<: *I, I11: 24000000}\n")
    got, _ = read_yaml(p, "acmm.configs")
    assert got["inertia"] == {"I11": 24000000, "I22": 13320000, "I33": 32130000}
    p.write_text("inertia: {<<: {I11: 1.0}, I22: 2.0, I22: 3.0}\n")
    with pytest.raises(ConfigError, match="duplicate key 'I22'"):
        read_yaml(p, "acmm.configs")


def test_an_unknown_key_of_a_library_form_names_the_users_field():
    from qpp.io.config import load_config
    from acmm_qpp.errors import ConfigError

    with pytest.raises(ConfigError) as got:
        load_config("qpp_saturation", ["nonlinearity.f1.0={form: saturation, output: 1, gain: k, bogus: 1}"])
    assert str(got.value).endswith("nonlinearity.f1.0.bogus: unknown key (valid keys: form, output, gain, level)")
    assert "function-after" not in str(got.value) and "more)" not in str(got.value)


def test_user_path_leaves_out_pydantics_own_steps():
    from acmm_qpp.configio import _user_path as user_path

    data = {"nonlinearity": {"kind": "expression", "f1": [{"form": "saturation", "bogus": 1}]}}
    loc = ("nonlinearity", "expression", "f1", 0, "function-after[_plausible_magnitudes(), LibraryForm]", "bogus")
    assert user_path(loc, data) == ("nonlinearity", "f1", 0, "bogus")
    assert user_path(("nonlinearity", "expression", "f1", 0, "str"), data) == ("nonlinearity", "f1", 0)
    assert user_path(("design", "sector", "sigma"), {"design": {"sector": {}}}) == ("design", "sector", "sigma")


def test_user_path_keeps_a_users_key_that_looks_like_a_validator_step():
    """A key with brackets, a key named like a type, a key whose sibling's value is its name: all
    the user's (a review found each dropped)."""
    from acmm_qpp.configio import _user_path as user_path

    data = {"parameters": {"k(2)": {"min": 1}}, "to": {"name": "inertia"}, "str": 1}
    assert user_path(("parameters", "k(2)", "nominal"), data) == ("parameters", "k(2)", "nominal")
    assert user_path(("to", "inertia"), data) == ("to", "inertia")
    assert user_path(("str",), data) == ("str",)


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
    from acmm_qpp.configio import OverrideSyntaxError, apply_overrides

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
    from acmm_qpp.configio import origin_of

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
