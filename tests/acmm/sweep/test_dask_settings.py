"""The recommended Dask settings (acmm.sweep.dask_settings) are distributed's own keys, and their
YAML text (shown in the guide, docs/howto/sweeps.md) says the same."""
from __future__ import annotations

import pytest
import yaml

from tests.conftest import REPO


def test_dask_settings_are_dask_keys_and_their_yaml_says_the_same():
    # a misspelt key would be accepted by dask.config.set and do nothing: each must be one of
    # distributed's own keys, with a value of the default's kind; the YAML file text nests the
    # same keys and values, and the guide shows that text
    pytest.importorskip("distributed", reason="optional extra acmm-qpp[dask] not installed")
    import dask
    from dask.utils import parse_timedelta

    from acmm.sweep.dask_settings import DASK_SETTINGS, dask_settings_yaml

    assert DASK_SETTINGS
    for key, value in DASK_SETTINGS.items():
        default = dask.config.get(key)            # KeyError for a key distributed does not have
        if isinstance(default, bool):
            assert isinstance(value, bool) and value != default, key
        else:
            assert parse_timedelta(value) > parse_timedelta(default), key
    tree = yaml.safe_load(dask_settings_yaml())
    flat = {}

    def walk(node, prefix):
        for k, v in node.items():
            if isinstance(v, dict):
                walk(v, prefix + k + ".")
            else:
                flat[prefix + k] = v

    walk(tree, "")
    assert flat == DASK_SETTINGS
    guide = (REPO / "docs" / "howto" / "sweeps.md").read_text(encoding="utf-8")
    assert dask_settings_yaml().strip() in guide
