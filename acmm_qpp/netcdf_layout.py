"""netCDF4-compatible layout of the HDF5 results (dimension scales, coordinates, CF attributes).

:func:`acmm_qpp.results.write_h5` writes the arrays; this module gives them the netCDF-4 structure
so that ``xarray.open_dataset(path, engine="h5netcdf")`` (and netCDF-4 tools) see named
dimensions and coordinates, while plain h5py readers find the same datasets as before:

* every array axis is attached to an HDF5 *dimension scale*.  A dimension is named by the
  dataset's :attr:`~acmm_qpp.results.Dataset.dims` when given, else inferred: a last axis with
  roll/pitch/yaw names is ``axis`` (a 3×3 matrix is ``(axis, axis_col)``), the 24 states of
  eq 4.47 are ``state``, other named axes ``<dataset>_name``, the rest ``<dataset>_dim<i>``;
* a 1-D dataset whose name equals its dimension (``t``, ``point`` ...) is that dimension's
  *coordinate variable*; ``axis``/``axis_col``, ``state`` and other named axes get a string
  coordinate variable; a dimension with no coordinate is a netCDF "dimension but not a
  variable" (a scale dataset with a ``NAME`` attribute, as the netCDF-C library writes it);
* CF attributes: ``units`` (already on every dataset), ``long_name`` (the description),
  ``standard_name="time"``/``axis="T"`` on the time coordinate ``t``, ``coordinates="orbits"``
  on the variables along ``t`` when an ``orbits`` variable exists, root ``Conventions``.

Time is always the first axis: ``(t, channel)``.
"""
from __future__ import annotations

from collections.abc import Mapping  # not typing.Mapping: its isinstance check is slow
from typing import Any

import numpy as np

from acmm_qpp.state_names import state_names as _state_names

#: Attribute value netCDF-C gives a dimension scale that is not a variable.
NOT_A_VARIABLE = "This is a netCDF dimension but not a netCDF variable."
AXES = ("roll", "pitch", "yaw")
#: Auxiliary coordinates: a 1-D variable with this name along ``t`` is listed in the
#: ``coordinates`` attribute of every variable along ``t``.
AUX_COORDS = ("orbits",)
TIME = "t"


def _shape(value) -> tuple:
    data = value.data
    if isinstance(data, str):
        return ()
    return np.shape(np.asarray(data))


def _infer_dims(key: str, value, shape: tuple) -> list[str]:
    names = tuple(value.names) if value.names is not None else None
    dims = [f"{key}_dim{i}" for i in range(len(shape))]
    if not shape:
        return dims
    if names is not None and len(names) == shape[-1]:
        if names == AXES:
            dims[-1] = "axis"
            # an axis × axis matrix only where the key says so (inertia): a (3 cases, 3 axes)
            # array was labelled (axis, axis_col), its dims then depending on the case count
            if len(shape) >= 2 and shape[-2] == 3 and "inertia" in key:
                dims[-2], dims[-1] = "axis", "axis_col"
        elif names == _state_names():
            dims[-1] = "state"
        else:
            dims[-1] = f"{key}_name"
    elif len(shape) >= 2 and shape[-2:] == (3, 3) and "inertia" in key:
        dims[-2], dims[-1] = "axis", "axis_col"
    elif len(shape) >= 2 and shape[-1] == 24 and shape[-2] == 3 and key in ("K", "gain"):
        dims[-2], dims[-1] = "axis", "state"
    return dims


def _coord_values(dim: str, named: Mapping[str, tuple]) -> tuple | None:
    if dim in ("axis", "axis_col"):
        return AXES
    if dim == "state":
        return _state_names()
    return named.get(dim)


def _plan_dims(items: Mapping[str, Any]) -> tuple[dict, dict, dict]:
    """Dimension names of every dataset of one group: (plan: key → dims, sizes: dim → length,
    named: dim → names of its entries).  A name reused with another length or clashing with a
    dataset of another shape gets a suffix."""
    sizes: dict[str, int] = {}
    plan: dict[str, list[str]] = {}
    named: dict[str, tuple] = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            continue
        shape = _shape(value)
        if not shape:
            continue
        dims = list(value.dims) if getattr(value, "dims", None) else _infer_dims(key, value, shape)
        if len(dims) != len(shape):
            raise ValueError(f"dataset {key!r}: {len(dims)} dimension names for shape {shape}")
        for i, (d, n) in enumerate(zip(dims, shape)):
            other = items.get(d)
            if d in sizes and sizes[d] != n:
                d = f"{d}_{n}"
            elif d != key and (isinstance(other, Mapping)
                               or (other is not None and _shape(other) != (n,))):
                d = f"{d}_dim"
            dims[i] = d
            sizes[d] = n
        if value.names is not None and len(value.names) == shape[-1] and dims[-1] not in named:
            named[dims[-1]] = tuple(str(x) for x in value.names)
        plan[key] = dims
    return plan, sizes, named


def _dimension_scales(group, sizes: dict, named: dict, handles: dict, w) -> dict:
    """One dimension scale per dimension: the coordinate variable when the group has one, else a
    string coordinate of the entries' names, else a bare netCDF dimension."""
    scales = {}
    for d, n in sizes.items():
        own = handles.get(d)
        if own is not None and not isinstance(own, tuple) and own.shape == (n,):
            ds = own
            w.make_scale(ds, d)
        else:
            values = _coord_values(d, named)
            if values is not None and len(values) == n:
                ds = w.dataset(group, d, np.array(values, dtype=object), dtype=w.text)
                w.attr(ds, "units", "1", new=True)
                w.attr(ds, "long_name", {"axis": "body control axis", "axis_col": "body control axis (column)",
                                         "state": "state of eq 4.47"}.get(d, f"name along {d}"), new=True)
                w.make_scale(ds, d)
            else:
                ds = w.dataset(group, d, shape=(n,), dtype="f4")
                w.attr(ds, "units", "1", new=True)
                w.make_scale(ds, f"{NOT_A_VARIABLE}{n:10d}")
        scales[d] = ds
    return scales


def _handles(group, items: Mapping[str, Any]) -> dict:
    """The handles of the objects written from ``items`` (as :func:`acmm_qpp.results.write_h5` keeps
    them), looked up by name: dataset identifier, or ``(sub-group, its handles)``."""
    return {key: (group[key], _handles(group[key], value)) if isinstance(value, Mapping) else group[key].id
            for key, value in items.items()}


def annotate(group, items: Mapping[str, Any], root: bool = True, handles: dict | None = None,
             writer=None) -> None:
    """Give the datasets of ``group`` (already written from ``items``) the netCDF layout.

    Recurses into sub-groups.  ``items`` maps names to :class:`acmm_qpp.results.Dataset` or to
    nested mappings, exactly as passed to :func:`acmm_qpp.results.write_h5`.

    Parameters
    ----------
    group : h5py.Group
        The group (the file's root first) holding the datasets written from ``items``.
    items : Mapping
        Dataset name → :class:`acmm_qpp.results.Dataset` or nested mapping (a sub-group).
    root : bool, optional
        ``group`` is the file's root (it gets ``Conventions="CF-1.8"``).
    handles : dict, optional
        The written objects: name → ``h5py`` dataset identifier, or ``(sub-group, its handles)``
        (default: looked up in ``group`` by name).
    writer : acmm_qpp.hdf5_lowlevel.Writer, optional
        The file's writer (default: a new one).

    Raises
    ------
    ValueError
        When a dataset's ``dims`` do not match its number of axes.
    """
    if writer is None:
        from acmm_qpp.hdf5_lowlevel import Writer

        writer = Writer()
    w = writer
    if handles is None:
        handles = _handles(group, items)
    if root:
        w.attr(group.id, "Conventions", "CF-1.8")
    plan, sizes, named = _plan_dims(items)
    scales = _dimension_scales(group, sizes, named, handles, w)
    aux = [a for a in AUX_COORDS if a in plan and plan[a] == [TIME]]
    for key, dims in plan.items():
        ds = handles[key]
        for i, d in enumerate(dims):
            if key == d:
                continue
            w.attach_scale(ds, scales[d], i)
        if aux and TIME in dims and key not in aux and key != TIME:
            w.attr(ds, "coordinates", " ".join(aux))
    if TIME in plan and plan[TIME] == [TIME]:
        w.attr(handles[TIME], "standard_name", "time")
        w.attr(handles[TIME], "axis", "T")
    for key, value in items.items():
        if isinstance(value, Mapping):
            sub, sub_handles = handles[key]
            annotate(sub, value, root=False, handles=sub_handles, writer=w)
        elif value.description and not w.has_attr(handles[key], "long_name"):
            w.attr(handles[key], "long_name", value.description, new=True)


def unit_system_of(config_text: str) -> str:
    """``output.units`` of a resolved config text (``imperial`` when absent or unreadable).

    Parameters
    ----------
    config_text : str
        Resolved config, YAML.

    Returns
    -------
    str
        ``"imperial"`` or ``"SI"`` (whatever the config says).
    """
    import yaml

    try:       # libyaml's loader when PyYAML has it: the same objects, several times faster
        data = yaml.load(config_text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
        return str(((data or {}).get("output") or {}).get("units") or "imperial")
    except (yaml.YAMLError, AttributeError):
        return "imperial"


def convert_items(items: Mapping[str, Any], system: str) -> dict:
    """A copy of ``items`` with each dataset in its output unit (:func:`acmm_qpp.units.output_unit`):
    deg → rad always, imperial → SI under ``SI``.  Units pint does not know are kept.

    Parameters
    ----------
    items : Mapping
        Dataset name → :class:`acmm_qpp.results.Dataset` or nested mapping.
    system : str
        Output unit system, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    dict
        Same structure; float/complex datasets converted with their ``units`` updated.
    """
    from dataclasses import replace

    from acmm_qpp.units import to_system

    out = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            out[key] = convert_items(value, system)
            continue
        if not hasattr(value, "data"):   # not a Dataset: write_h5 reports it
            out[key] = value
            continue
        data = value.data
        if isinstance(data, str) or np.asarray(data).dtype.kind not in "fc":
            out[key] = value
            continue
        try:
            new, unit = to_system(np.asarray(data), value.units, system)
        except ValueError:
            new, unit = data, value.units
        out[key] = value if unit == value.units else replace(value, data=new, units=unit)
    return out


def with_leading_dim(items: Mapping[str, Any], dim: str, n: int) -> dict:
    """``items`` with ``dims`` set on every dataset (recursively) whose first axis has length
    ``n`` and no dims yet: ``(dim, <inferred rest>)`` — e.g. one row per sweep case.

    Parameters
    ----------
    items : Mapping
        Dataset name → :class:`acmm_qpp.results.Dataset` or nested mapping.
    dim : str
        Name of the leading dimension.
    n : int
        Its length.

    Returns
    -------
    dict
        Same structure, with ``dims`` set where they apply.
    """
    from dataclasses import replace

    out = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            out[key] = with_leading_dim(value, dim, n)
            continue
        shape = _shape(value) if hasattr(value, "data") else ()
        if shape and shape[0] == n and getattr(value, "dims", None) is None:
            rest = _infer_dims(key, value, shape)[1:] if len(shape) > 1 else []
            value = replace(value, dims=(dim, *rest))
        out[key] = value
    return out
