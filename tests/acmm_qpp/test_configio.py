"""YAML config files (acmm_qpp.configio): merge keys are read as PyYAML's safe loader reads them,
a key written twice is still refused."""
from __future__ import annotations

import pytest

from acmm_qpp.errors import ConfigError


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
    from acmm_qpp.configio import user_path

    data = {"nonlinearity": {"kind": "expression", "f1": [{"form": "saturation", "bogus": 1}]}}
    loc = ("nonlinearity", "expression", "f1", 0, "function-after[_plausible_magnitudes(), LibraryForm]", "bogus")
    assert user_path(loc, data) == ("nonlinearity", "f1", 0, "bogus")
    assert user_path(("nonlinearity", "expression", "f1", 0, "str"), data) == ("nonlinearity", "f1", 0)
    assert user_path(("design", "sector", "sigma"), {"design": {"sector": {}}}) == ("design", "sector", "sigma")


def test_user_path_keeps_a_users_key_that_looks_like_a_validator_step():
    """A key with brackets, a key named like a type, a key whose sibling's value is its name: all
    the user's (a review found each dropped)."""
    from acmm_qpp.configio import user_path

    data = {"parameters": {"k(2)": {"min": 1}}, "to": {"name": "inertia"}, "str": 1}
    assert user_path(("parameters", "k(2)", "nominal"), data) == ("parameters", "k(2)", "nominal")
    assert user_path(("to", "inertia"), data) == ("to", "inertia")
    assert user_path(("str",), data) == ("str",)
