"""The named dimensions of acmm's results files and their coordinates.

Every stage passes :data:`COORDS` to :func:`acmm_qpp.results.write_h5`: a group with a dimension
``axis`` (the body control axes roll, pitch, yaw), ``axis_col`` (the same, along the columns of a
3 × 3 matrix such as the inertia) or ``state`` (the 24 states of eq 4.47) gets that coordinate.
"""
from __future__ import annotations

import numpy as np

from acmm.model.linearize import STATE_NAMES
from acmm_qpp.results import Dataset

#: The body control axes, in order.
AXES = ("roll", "pitch", "yaw")


def _names(values, long_name: str, dim: str) -> Dataset:
    return Dataset(np.array(values, dtype=object), "1", attrs={"long_name": long_name}, dims=(dim,))


#: Dimension → its coordinate in every acmm results file (``write_h5(..., coords=COORDS)``).
COORDS = {
    "axis": _names(AXES, "body control axis", "axis"),
    "axis_col": _names(AXES, "body control axis (column)", "axis_col"),
    "state": _names(STATE_NAMES, "state of eq 4.47", "state"),
}
#: The auxiliary time coordinate of the simulation files: orbits elapsed along ``t``.
AUX_COORDS = ("orbits",)
