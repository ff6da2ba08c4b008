"""The tea.h5 written by the TEA stage (acmm.stages.runners.run_tea): its contents, units and
embedded config; an overwrite is atomic."""
from __future__ import annotations

import hashlib

import h5py
import numpy as np
import yaml

import acmm
from acmm.io.config import load_config, parse_config
from acmm_qpp.results import read_h5
from acmm.stages.runners import run_tea

from tests.conftest import CONFIGS


def _all_datasets(path):
    """Datasets other than the netCDF dimension scales."""
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.__setitem__(name, dict(obj.attrs))
                     if isinstance(obj, h5py.Dataset) and not h5py.h5ds.is_scale(obj.id) else None)
    return found


def _leftovers(directory, keep):
    return sorted(p.name for p in directory.iterdir() if p.name not in keep)


def test_tea_h5_contents(tmp_runs):
    result, path = run_tea(CONFIGS / "mb3.yaml")
    assert path.resolve() == (tmp_runs / "runs" / "mb3" / "tea.h5").resolve()
    ds = _all_datasets(path)
    assert {"theta", "omega", "bias", "inertia"} <= set(ds)
    for name, attrs in ds.items():
        assert attrs.get("units"), f"dataset {name} has no units attribute"
    assert ds["theta"]["units"] == "rad" and ds["omega"]["units"] == "rad/s"
    assert ds["bias"]["units"] == "ft*lbf" and ds["inertia"]["units"] == "slug*ft^2"
    back = read_h5(path)
    np.testing.assert_allclose(np.degrees(back["theta"]), [1.3, -44.7, 2.1], atol=0.01)
    np.testing.assert_array_equal(back["inertia"], load_config(CONFIGS / "mb3.yaml").inertia.matrix())
    np.testing.assert_array_equal(back["bias"], result.tea.bias)
    np.testing.assert_array_equal(back["omega"], result.tea.omega)
    attrs = back["attrs"]
    # the embedded config is the resolved config and re-validates to the same run
    assert parse_config(yaml.safe_load(attrs["config"])) == result.config
    assert attrs["config_hash"] == hashlib.sha256(attrs["config"].encode()).hexdigest()[:16]
    assert attrs["package_version"] == acmm.__version__
    assert "git_commit" in attrs
    assert _leftovers(path.parent, {"tea.h5", "config.yaml"}) == []


def test_tea_h5_overwrite_is_atomic_and_clean(tmp_runs):
    _, p1 = run_tea(CONFIGS / "ac.yaml")
    _, p2 = run_tea(CONFIGS / "ac.yaml")
    assert p1 == p2
    assert _leftovers(p1.parent, {"tea.h5", "config.yaml"}) == []
    np.testing.assert_allclose(np.degrees(read_h5(p2)["theta"]), [0.19, -5.0, 0.56], atol=0.01)
