"""The report's manifest (acmm.report.manifest): dataset hashes ignore timing and attributes."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.report import manifest as manifest_mod

pytestmark = pytest.mark.slow      # a whole `acmm report --fast` per session: `make test-slow`


def test_dataset_hashes_ignore_timing_and_attributes(tmp_path):
    from acmm_qpp.results import Dataset, write_h5

    a = write_h5(tmp_path / "a.h5", {"x": Dataset(np.arange(3.0), "1", dims=("i",)), "wall_time": Dataset(1.0, "s")}, "c: 1")
    b = write_h5(tmp_path / "b.h5", {"x": Dataset(np.arange(3.0), "1", dims=("i",)), "wall_time": Dataset(2.0, "s")}, "c: 1")
    c = write_h5(tmp_path / "c.h5", {"x": Dataset(np.arange(3.0) + 1e-15, "1", dims=("i",))}, "c: 1")
    assert manifest_mod.dataset_hashes(a) == manifest_mod.dataset_hashes(b) and list(manifest_mod.dataset_hashes(a)) == ["x"]
    assert manifest_mod.dataset_hashes(a) != manifest_mod.dataset_hashes(c)
