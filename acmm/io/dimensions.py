"""The named dimensions of acmm's results files and their coordinates.

Every stage writes its items with :func:`with_coordinates`: a group with a dimension ``axis`` (the
body control axes roll, pitch, yaw), ``axis_col`` (the same, along the columns of a 3 × 3 matrix
such as the inertia) or ``state`` (the 24 states of eq 4.47) gets that coordinate (:data:`COORDS`),
and the simulation's time in orbits is named as an auxiliary coordinate of its time series
(:data:`AUX_COORDS`, the CF ``coordinates`` attribute).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from acmm.model.linearize import STATE_NAMES
from acmm_qpp.results import TIME, Dataset

#: The body control axes, in order.
AXES = ("roll", "pitch", "yaw")


def _names(values, long_name: str, dim: str) -> Dataset:
    return Dataset(np.array(values, dtype=object), "1", attrs={"long_name": long_name}, dims=(dim,))


#: Dimension → its coordinate in every acmm results file (:func:`with_coordinates`).
COORDS = {
    "axis": _names(AXES, "body control axis", "axis"),
    "axis_col": _names(AXES, "body control axis (column)", "axis_col"),
    "state": _names(STATE_NAMES, "state of eq 4.47", "state"),
}
#: The auxiliary time coordinate of the simulation files: orbits elapsed along ``t``.
AUX_COORDS = ("orbits",)


def with_coordinates(items: Mapping, aux_coords: tuple = ()) -> dict:
    """``items`` for :func:`acmm_qpp.results.write_h5` with, in every group, the coordinate
    (:data:`COORDS`) of each of acmm's dimensions its datasets use (of its length) and that has no
    item of its own name, placed before the first dataset along it (a coordinate variable made
    after the variables along its dimension has h5netcdf attach its scale to each of them again);
    and, when datasets ``aux_coords`` of a group lie along the time dimension ``t`` alone, the CF
    ``coordinates`` attribute naming them on every other dataset along ``t`` of that group.

    Parameters
    ----------
    items : mapping
        Name → :class:`acmm_qpp.results.Dataset` or group (a nested mapping).
    aux_coords : tuple of str, optional
        Names of auxiliary time coordinates (e.g. :data:`AUX_COORDS`).

    Returns
    -------
    dict
        The items, groups copied; a dataset that gets the attribute is a copy.
    """
    aux = [a for a in aux_coords if isinstance(items.get(a), Dataset) and items[a].dims == (TIME,)]
    out = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            out[key] = with_coordinates(value, aux_coords)
            continue
        dims = tuple(value.dims or ())
        for d, n in zip(dims, np.shape(value.data)):
            if d in COORDS and d not in items and d not in out and np.shape(COORDS[d].data) == (n,):
                out[d] = COORDS[d]
        if aux and TIME in dims and key not in aux and key != TIME:
            value = replace(value, attrs={**value.attrs, "coordinates": " ".join(aux)})
        out[key] = value
    return out
