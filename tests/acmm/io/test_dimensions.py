"""acmm's dimensions in its results files (acmm.io.dimensions): every group using ``axis``,
``axis_col`` or ``state`` gets that coordinate, and the time in orbits is an auxiliary coordinate
of the time series."""
from __future__ import annotations

import h5py
import numpy as np

from acmm.io.dimensions import AUX_COORDS, with_coordinates
from acmm_qpp.results import Dataset, write_h5


def test_each_group_gets_the_coordinates_of_the_dimensions_it_uses(tmp_path):
    items = {"t": Dataset(np.arange(3.0), "s", "time", dims=("t",)),
             "orbits": Dataset(np.arange(3.0) / 2, "1", "orbit count", dims=("t",)),
             "w": Dataset(np.ones((3, 3)), "rad/s", "rate", attrs={"coordinates": "mine"}, dims=("t", "axis")),
             "grp": {"K": Dataset(np.ones((3, 24)), "1", "gain", dims=("axis", "state")),
                     "axis": Dataset(np.arange(3.0), "1", "its own axis", dims=("axis",))},
             "other": {"v": Dataset(np.ones(2), "1", dims=("two",))}}
    out = with_coordinates(items, AUX_COORDS)
    assert items["w"].attrs == {"coordinates": "mine"} and "axis" not in items      # the input is unchanged
    assert list(out)[:4] == ["t", "orbits", "axis", "w"] and set(out["other"]) == {"v"}
    path = write_h5(tmp_path / "a.h5", out, "name: x\n")
    with h5py.File(path, "r") as f:
        assert f["axis"].asstr()[()].tolist() == ["roll", "pitch", "yaw"]
        assert f["axis"].attrs["long_name"] == "body control axis"
        assert f["w"].attrs["coordinates"] == "orbits" and "coordinates" not in f["orbits"].attrs
        assert f["grp/state"].shape == (24,) and f["grp/axis"][()].tolist() == [0.0, 1.0, 2.0]
