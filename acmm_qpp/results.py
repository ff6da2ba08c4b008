"""Self-describing netCDF-4/HDF5 results, written atomically by h5netcdf.

Every dataset carries a ``units`` attribute and named dimensions; the root group carries the
resolved config (YAML text), its hash, the package version, the git commit when known and the
creation time (:mod:`acmm_qpp.provenance`).  The file is built in memory by
`h5netcdf <https://h5netcdf.org>`_ and written to a temporary name beside the target, then renamed
into place, so an interrupted run never leaves a partial file (:mod:`acmm_qpp.outputs`).

The netCDF layout, for ``xarray.open_dataset(path, engine="h5netcdf")`` and the netCDF-C library:

* each array names the dimension of every axis (:attr:`Dataset.dims`, time first);
* a 1-D dataset named like its dimension (``t``, ``point`` ...) is that dimension's coordinate
  (a product adds the coordinates of its own dimensions to its items: acmm's
  :func:`acmm.io.dimensions.with_coordinates`); else the :attr:`Dataset.names` of a dataset along
  it (its last axis) make a text coordinate; a dimension with neither is a netCDF "dimension but
  not a variable";
* CF attributes: ``units`` (on every dataset), ``long_name`` (the description),
  ``standard_name="time"``/``axis="T"`` on the time coordinate ``t``, root ``Conventions``.
"""
from __future__ import annotations

import io
import json
from collections.abc import Mapping  # not typing.Mapping: its isinstance check is slow
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5netcdf
import h5py
import numpy as np

from acmm_qpp import __version__
from acmm_qpp.outputs import write_bytes
from acmm_qpp.errors import ConfigError, FigureError
from acmm_qpp.provenance import config_hash, git_commit, git_dirty


@dataclass
class Dataset:
    """One array to store, with its unit, its dimensions and optional axis/element names.

    Attributes
    ----------
    data : array-like or str
        The values, in the unit ``units`` (report units; converted on writing).
    units : str
        Unit of ``data`` (stored as the ``units`` attribute).
    description : str
        Stored as the ``description`` and ``long_name`` attributes when not empty.
    names : list of str or None
        Names of the entries of the last axis, stored as JSON in the ``names`` attribute (and
        the text coordinate of that dimension when nothing else gives it one).
    attrs : dict
        Further dataset attributes (they replace the defaults above).
    dims : tuple of str or None
        netCDF dimension name of each axis (time first); required for an array, None for a scalar.
    """

    data: Any
    units: str
    description: str = ""
    names: list[str] | None = None
    attrs: dict[str, Any] = field(default_factory=dict)
    dims: tuple[str, ...] | None = None


#: Root attribute ``Conventions``: the CF version the layout follows.
CONVENTIONS = "CF-1.8"
#: Name of the time coordinate (``standard_name="time"``, ``axis="T"``).
TIME = "t"


def _shape(data) -> tuple:
    return () if isinstance(data, str) else np.shape(data)


def _dims(key: str, value: Dataset) -> tuple:
    """The dimension names of dataset ``key`` (checked against its shape)."""
    shape = _shape(value.data)
    dims = tuple(value.dims) if value.dims is not None else ()
    if len(dims) != len(shape):
        raise ValueError(f"dataset {key!r}: {len(dims)} dimension names {dims} for shape {shape}"
                         + (" (an array names its dimensions: Dataset(..., dims=...))" if not dims else ""))
    return dims


def _sizes(items: Mapping[str, Any]) -> dict[str, int]:
    """Dimension name → length of the datasets of one group (a name has one length)."""
    sizes: dict[str, int] = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            continue
        if not isinstance(value, Dataset):
            raise TypeError(f"results item {key!r} must be a Dataset or a mapping")
        for d, n in zip(_dims(key, value), _shape(value.data)):
            if sizes.setdefault(d, n) != n:
                raise ValueError(f"dataset {key!r}: dimension {d!r} of length {n}, "
                                 f"{sizes[d]} elsewhere in the group")
    return sizes


def h5_text(v) -> str:
    """An HDF5 string (bytes of a fixed-length one, or str, or a numpy scalar of either) as str.

    Parameters
    ----------
    v : bytes, str or numpy scalar
        The stored value.

    Returns
    -------
    str
        The text.
    """
    v = v.item() if hasattr(v, "item") else v
    return v.decode() if isinstance(v, bytes) else str(v)


def _text(values) -> np.ndarray:
    """Text as an array of variable-length UTF-8 strings."""
    return np.array(values, dtype=h5py.string_dtype())


def _coordinates(items: Mapping[str, Any], sizes: dict) -> dict:
    """Dimension → the text coordinate to create for it from the :attr:`Dataset.names` of a
    dataset along it, for the dimensions of one group that have no dataset of their own name."""
    out = {}
    for d, n in sizes.items():
        own = items.get(d)
        if isinstance(own, Dataset) and _shape(own.data) == (n,):
            continue
        for key, value in items.items():
            if (isinstance(value, Dataset) and value.names is not None and len(value.names) == n
                    and _dims(key, value)[-1:] == (d,)):
                out[d] = Dataset([str(x) for x in value.names], "1", attrs={"long_name": f"name along {d}"},
                                 dims=(d,))
                break
    return out


def _attr_value(value):
    """An attribute value as stored: a flag as int8 0/1 (one kind of flag in every file)."""
    return np.int8(value) if isinstance(value, (bool, np.bool_)) else value


def _array(value: Dataset):
    """``value.data`` as the array to store and its type: text as UTF-8 (variable-length for
    str, fixed-length for bytes)."""
    data = value.data
    if isinstance(data, str):
        return _text(data), h5py.string_dtype()
    arr = np.asarray(data)
    if arr.dtype.kind in "OU":
        return _text(arr.astype(object)), h5py.string_dtype()
    if arr.dtype.kind == "S":       # fixed-length text is UTF-8 (a unit such as ft·lbf in it)
        dtype = h5py.string_dtype("utf-8", arr.dtype.itemsize)
        return arr.astype(dtype), dtype
    return arr, arr.dtype


def _write_group(group, h5group, items: Mapping[str, Any]) -> None:
    """Write ``items`` into ``group`` (an :class:`h5netcdf.Group`, whose HDF5 group is ``h5group``),
    its dimensions first.  Attributes are set through h5py: a number stays a scalar (h5netcdf
    makes it a 1-element array, as the netCDF-C library writes it)."""
    sizes = _sizes(items)
    for d, n in sizes.items():        # declared here: a sub-group has dimensions of its own
        group.dimensions[d] = n
    made = _coordinates(items, sizes)
    for d in sizes:                   # a dimension without a variable: no data, unit "1"
        if d not in made and not (isinstance(items.get(d), Dataset) and _shape(items[d].data) == (sizes[d],)):
            h5group[d].attrs["units"] = "1"
    for key, value in {**made, **items}.items():
        if isinstance(value, Mapping):
            sub = group.create_group(key)
            _write_group(sub, h5group[key], value)
            continue
        dims = _dims(key, value)
        data, dtype = _array(value)
        group.create_variable(key, dims, dtype, data=data)
        attrs = {"units": value.units}
        if value.description:
            attrs.update(description=value.description, long_name=value.description)
        if value.names is not None:
            attrs["names"] = json.dumps(list(value.names))
        attrs.update(value.attrs)
        if key == TIME and dims == (TIME,):
            attrs.update(standard_name="time", axis="T")
        for k, v in attrs.items():
            h5group[key].attrs[k] = _attr_value(v)


#: Run names (every config's, and the names a config gives its runs): a single path component of letters,
#: digits, ``_ . -`` that does not start with a dot (so never ``.``/``..``/hidden), at most
#: :data:`RUN_NAME_MAX` characters (room for the longest file name written inside it).
RUN_NAME_PATTERN = r"^[A-Za-z0-9_-][A-Za-z0-9_.-]*$"
RUN_NAME_MAX = 100
#: ``output.root``: any path without a NUL byte.
ROOT_PATTERN = r"^[^\x00]+$"


def write_h5(path: str | Path, items: Mapping[str, Any], config_text: str,
             attrs: Mapping[str, Any] | None = None) -> Path:
    """Write ``items`` (name → :class:`Dataset` or nested mapping) to ``path`` atomically.

    Parameters
    ----------
    path : path-like
        Target file; its directory is created if needed.
    items : mapping
        Datasets (or groups of datasets) to store.
    config_text : str
        The resolved config as YAML; embedded as the root attribute ``config``, with the
        provenance (:mod:`acmm_qpp.provenance`: package version, git commit, config hash,
        creation time in UTC).
    attrs : mapping, optional
        Extra root attributes (e.g. a verdict).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    TypeError
        An item is neither a :class:`Dataset` nor a mapping.
    ValueError
        An array without dimension names, or a dimension with two lengths in one group.
    """
    path = Path(path)
    root = {"config": config_text, "package": "acmm-qpp", "package_version": __version__,
            "git_commit": git_commit(), "git_dirty": git_dirty(), "config_hash": config_hash(config_text),
            "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"), **(attrs or {}),
            "Conventions": CONVENTIONS}
    buf = io.BytesIO()        # built in memory, written by write_bytes (HDF5 crashes on ENOSPC)
    # invalid_netcdf: bool datasets (HDF5 enums, as h5py writes them), which the netCDF-C
    # library reads; track_order off: groups and attributes listed by name, as before
    with h5py.File(buf, "w", track_order=False) as h5, h5netcdf.File(h5, "w", invalid_netcdf=True) as f:
        for k, v in root.items():
            h5.attrs[k] = _attr_value(v)
        _write_group(f, h5, items)
    return write_bytes(path, buf.getbuffer())


def dimension_only(ds) -> bool:
    """Whether an HDF5 dataset is a netCDF dimension that is not a variable (it holds no data).

    Parameters
    ----------
    ds : h5py.Dataset
        The dataset.

    Returns
    -------
    bool
        It is such a dimension scale.
    """
    return h5_text(ds.attrs.get("NAME", b"")).startswith("This is a netCDF dimension but not a netCDF variable.")


def read_h5(path: str | Path) -> dict[str, Any]:
    """Read a results file back as a nested dict of numpy arrays plus ``"attrs"``.

    Parameters
    ----------
    path : path-like
        The results file.

    Returns
    -------
    dict
        Nested dict of the stored datasets (in the file's units, see their ``units``
        attributes) plus the root attributes under ``"attrs"``.
    """
    def _read(group):
        out: dict[str, Any] = {}
        for k, v in group.items():
            if isinstance(v, h5py.Group):
                out[k] = _read(v)
            elif isinstance(v, h5py.Datatype) or dimension_only(v):   # (complex numbers' type)
                continue
            else:
                val = v[()]
                out[k] = val.decode() if isinstance(val, bytes) else val
        return out

    with h5py.File(path, "r") as f:
        out = _read(f)
        out["attrs"] = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    return out


def save_figure(fig, path: str | Path, **kwargs) -> Path:
    """``fig.savefig`` atomically: to a temporary file beside ``path``, then renamed into place.

    The format is taken from ``path``'s suffix; ``kwargs`` go to ``savefig``.  Vector files carry
    no creation date (unless ``metadata`` gives one), so that the same figure is the same file.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : path-like
        The target file.
    **kwargs : dict
        Passed on to ``savefig``.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt in _DATED_FORMATS:           # the same figure gives the same bytes: no creation date
        kwargs["metadata"] = {_DATED_FORMATS[fmt]: None, **(kwargs.get("metadata") or {})}
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, **kwargs)
    return write_bytes(path, buf.getbuffer(), "figure")


def draw_figures(calls) -> list[Path]:
    """Draw a stage's figures, in this process, after its results are written: every call is
    made even if one fails, and the first failure is raised then as a
    :class:`acmm_qpp.errors.FigureError` (exit 4: the results stay written).

    Parameters
    ----------
    calls : iterable of callable
        The figures, each a call without arguments (e.g. a ``functools.partial`` of a figure
        function that writes its file with :func:`save_figure`), returning the path or the list
        of paths it wrote (or None).

    Returns
    -------
    list of pathlib.Path
        The files written, in order.

    Raises
    ------
    acmm_qpp.errors.FigureError
        A figure could not be drawn or written (the first failure's message).
    """
    first, written = None, []
    for call in calls:
        try:
            out = call()
        except Exception as exc:  # noqa: BLE001 (raised once the others are drawn)
            first = first or exc
            continue
        written += [Path(x) for x in (out if isinstance(out, (list, tuple)) else [out]) if x is not None]
    if first is not None:
        err = FigureError.of(first)
        raise err from (None if err is first else first)
    return written


def redraw_stored(target: str | Path, sources: dict, readers: dict, out=None) -> list[Path]:
    """Draw the figures of stored results files (``acmm plot`` / ``qpp plot``): ``target`` itself
    (an ``.h5`` written by one of the stages of ``sources``) or, for a run folder, every file of
    ``sources`` in it written by its stage.  Every file is read first, then the output folders are
    made and the figures drawn (:func:`draw_figures`).

    Parameters
    ----------
    target : path-like
        A run folder or a results file.
    sources : dict
        Results file name → the stage that writes it (root attribute ``stage``), for the files
        whose figures the caller draws, in the order a run folder's figures are drawn.
    readers : dict
        Stage → ``reader(path, folder)`` returning the figure calls of that file.
    out : path-like, optional
        Folder of the figures (default: each file's own folder).

    Returns
    -------
    list of pathlib.Path
        The figures written.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        ``target`` does not exist, is not a results file of those stages, is a folder with none,
        or a file lacks a dataset or attribute its figures need (exit 2; nothing is written).
    """
    p = Path(target)
    stages = tuple(dict.fromkeys(sources.values()))
    if not str(target).strip() or not p.exists():
        raise ConfigError(f"{target}: no such run folder or results file")

    def stage_of(f: Path) -> str | None:
        try:
            with h5py.File(f, "r") as h:
                v = h.attrs.get("stage")
                return None if v is None or "config" not in h.attrs else h5_text(v)
        except (OSError, ValueError):
            return None

    if p.is_dir():
        files = [(p / name, stage_of(p / name)) for name in sources if (p / name).is_file()]
        files = [(f, st) for f, st in files if st in stages]
        if not files:
            raise ConfigError(f"{target}: no results file with figures in this folder (looked for {', '.join(sources)})")
    else:
        st = stage_of(p)
        if st is None:
            raise ConfigError(f"{target}: not a results file of this project (an HDF5 file with the root "
                              "attributes stage and config)")
        if st not in stages:
            raise ConfigError(f"{target}: a {st!r} result, whose figures this command does not draw "
                              f"(it draws {', '.join(stages)})")
        files = [(p, st)]
    calls, folders = [], []
    for path, stage in files:
        folder = Path(out) if out is not None else path.parent
        try:
            calls += readers[stage](path, folder)
        except (KeyError, ValueError, TypeError, IndexError, OSError) as exc:
            raise ConfigError(f"{path}: not a complete '{stage}' results file, its figures cannot be drawn "
                              f"({type(exc).__name__}: {exc})") from None
        folders.append(folder)
    for folder in folders:
        folder.mkdir(parents=True, exist_ok=True)
    return draw_figures(calls)


#: vector formats whose files matplotlib dates by default → the metadata key of that date
_DATED_FORMATS = {"pdf": "CreationDate", "svg": "Date", "ps": "CreationDate", "eps": "CreationDate"}
