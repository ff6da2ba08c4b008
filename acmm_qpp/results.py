"""Self-describing HDF5 results, written atomically.

Every dataset carries a ``units`` attribute; the root group carries the resolved config
(YAML text), its hash, the package version, the git commit when known and the creation
time.  Files are written to a temporary name in the target directory and renamed into
place, so an interrupted run never leaves a partial file (:mod:`acmm_qpp.atomic_write`; the
provenance attributes come from :mod:`acmm_qpp.provenance`).
"""
from __future__ import annotations

import json
from collections.abc import Mapping  # not typing.Mapping: its isinstance check is slow
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from acmm_qpp.atomic_write import in_memory
from acmm_qpp.errors import ConfigError, FigureError
from acmm_qpp.provenance import provenance


@dataclass
class Dataset:
    """One array to store, with its unit and optional axis/element names.

    Attributes
    ----------
    data : array-like or str
        The values, in the unit ``units`` (report units; converted on writing).
    units : str
        Unit of ``data`` (stored as the ``units`` attribute).
    description : str
        Stored as the ``description`` attribute when not empty.
    names : list of str or None
        Element names, stored as JSON in the ``names`` attribute.
    attrs : dict
        Further dataset attributes.
    dims : tuple of str or None
        netCDF dimension name of each axis (time first); inferred when None.
    """

    data: Any
    units: str
    description: str = ""
    names: list[str] | None = None
    attrs: dict[str, Any] = field(default_factory=dict)
    #: netCDF dimension name of each axis (time first); inferred when None, see
    #: :mod:`acmm_qpp.netcdf_layout`.
    dims: tuple[str, ...] | None = None


def _write_group(group, items: Mapping[str, Any], writer) -> dict:
    """Write ``items`` into ``group`` with ``writer`` (:class:`acmm_qpp.hdf5_lowlevel.Writer`);
    return the handles :func:`acmm_qpp.netcdf_layout.annotate` takes: name → dataset identifier,
    or → ``(sub-group, its handles)``."""
    handles: dict[str, Any] = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            sub = group.create_group(key)
            handles[key] = (sub, _write_group(sub, value, writer))
            continue
        if not isinstance(value, Dataset):
            raise TypeError(f"results item {key!r} must be a Dataset or a mapping")
        data = value.data
        if isinstance(data, str):
            ds = writer.dataset(group, key, data)
        else:
            arr = np.asarray(data)
            if arr.dtype.kind in "OU":   # text arrays: variable-length UTF-8 strings
                ds = writer.dataset(group, key, arr.astype(object), dtype=writer.text)
            else:
                ds = writer.dataset(group, key, arr)
        handles[key] = ds
        writer.attr(ds, "units", value.units, new=True)         # a new dataset: no attributes yet
        if value.description:
            writer.attr(ds, "description", value.description, new=True)
        if value.names is not None:
            writer.attr(ds, "names", json.dumps(list(value.names)), new=True)
        for ak, av in value.attrs.items():
            writer.attr(ds, ak, av)
    return handles


#: Run names (acmm, qpp and sweep configs, qpp scenarios): a single path component of letters,
#: digits, ``_ . -`` that does not start with a dot (so never ``.``/``..``/hidden), at most
#: :data:`RUN_NAME_MAX` characters (room for the longest file name written inside it).
RUN_NAME_PATTERN = r"^[A-Za-z0-9_-][A-Za-z0-9_.-]*$"
RUN_NAME_MAX = 100
#: ``output.root``: any path without a NUL byte.
ROOT_PATTERN = r"^[^\x00]+$"


def write_h5(path: str | Path, items: Mapping[str, Any], config_text: str,
             attrs: Mapping[str, Any] | None = None, units: str | None = None) -> Path:
    """Write ``items`` (name → :class:`Dataset` or nested mapping) to ``path`` atomically.

    Parameters
    ----------
    path : path-like
        Target file; its directory is created if needed.
    items : mapping
        Datasets (or groups of datasets) to store.
    config_text : str
        The resolved config as YAML; embedded as the root attribute ``config``.
    attrs : mapping, optional
        Extra root attributes (e.g. a verdict).
    units : {"imperial", "SI"}, optional
        Output unit system (``output.units``; default: read from ``config_text``, else
        imperial).  Items are given in the report's units and converted on writing; angles
        are stored in rad in both systems (:func:`acmm_qpp.units.output_unit`).

    Returns
    -------
    Path
        ``path``.
    """
    from acmm_qpp.hdf5_lowlevel import Writer
    from acmm_qpp.netcdf_layout import annotate, convert_items, unit_system_of
    import h5py

    path = Path(path)
    with in_memory(path) as tmp:
        with h5py.File(tmp, "w") as f:
            w, root = Writer(), f.id
            w.attr(root, "config", config_text)
            for k, v in provenance(config_text).items():
                w.attr(root, k, v)
            for k, v in (attrs or {}).items():
                w.attr(root, k, v)
            system = units or unit_system_of(config_text)
            items = convert_items(items, system)
            w.attr(root, "unit_system", system)
            annotate(f, items, handles=_write_group(f, items, w), writer=w)
    return path


def _dimension_only(ds) -> bool:
    """A netCDF dimension scale that is not a variable (holds no data)."""
    name = ds.attrs.get("NAME", b"")
    name = name.decode() if isinstance(name, bytes) else str(name)
    return name.startswith("This is a netCDF dimension but not a netCDF variable.")


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
    import h5py

    def _read(group):
        out: dict[str, Any] = {}
        for k, v in group.items():
            if isinstance(v, h5py.Group):
                out[k] = _read(v)
            elif _dimension_only(v):
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
    with in_memory(path, "figure") as tmp:
        fig.savefig(tmp, format=fmt, **kwargs)
    return path


def draw_figures(calls) -> None:
    """Draw a stage's figures, in this process, after its results are written: every call is
    made even if one fails, and the first failure is raised then as a
    :class:`acmm_qpp.errors.FigureError` (exit 4: the results stay written).

    Parameters
    ----------
    calls : iterable of callable
        The figures, each a call without arguments (e.g. a ``functools.partial`` of a figure
        function that writes its file with :func:`save_figure`).

    Raises
    ------
    acmm_qpp.errors.FigureError
        A figure could not be drawn or written (the first failure's message).
    """
    first = None
    for call in calls:
        try:
            call()
        except Exception as exc:  # noqa: BLE001 (raised once the others are drawn)
            first = first or exc
    if first is not None:
        err = FigureError.of(first)
        raise err from (None if err is first else first)


#: result file → the stage that writes it (root attribute ``stage``), in the order a run folder's
#: figures are redrawn
FIGURE_SOURCES = {"design.h5": "design", "sim.h5": "simulate", "sweep.h5": "sweep",
                  "qpp_design.h5": "qpp design", "qpp_sim.h5": "qpp simulate"}


def redraw_from_files(files: list, readers: dict, out=None) -> list[Path]:
    """Draw the figures of stored results files (``acmm plot`` / ``qpp plot``): every file is read
    first, then the output folders are made and the figures drawn.

    Parameters
    ----------
    files : list of (pathlib.Path, str)
        :func:`stored_results`.
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
        A file lacks a dataset or attribute its figures need (exit 2; nothing is written).
    """
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
    return draw_collected(calls)


def stored_results(target: str | Path, stages: tuple) -> list[tuple[Path, str]]:
    """The result files a figure redraw (``acmm plot`` / ``qpp plot``) reads: ``target`` itself
    (an ``.h5`` written by one of ``stages``) or, for a run folder, every file of
    :data:`FIGURE_SOURCES` in it written by one of ``stages``.

    Parameters
    ----------
    target : path-like
        A run folder or a results file.
    stages : tuple of str
        The stages (root attribute ``stage``) whose files the caller draws.

    Returns
    -------
    list of (pathlib.Path, str)
        Each file and its stage.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        ``target`` does not exist, is not a results file of those stages, or is a folder with
        none.
    """
    import h5py

    from acmm_qpp.errors import ConfigError

    p = Path(target)
    if not str(target).strip() or not p.exists():
        raise ConfigError(f"{target}: no such run folder or results file")

    def stage_of(f: Path) -> str | None:
        try:
            with h5py.File(f, "r") as h:
                v = h.attrs.get("stage")
                return None if v is None or "config" not in h.attrs else (v.decode() if isinstance(v, bytes) else str(v))
        except (OSError, ValueError):
            return None

    if p.is_dir():
        found = [(p / name, stage_of(p / name)) for name in FIGURE_SOURCES if (p / name).is_file()]
        found = [(f, st) for f, st in found if st in stages]
        if not found:
            names = ", ".join(n for n, st in FIGURE_SOURCES.items() if st in stages)
            raise ConfigError(f"{target}: no results file with figures in this folder (looked for {names})")
        return found
    st = stage_of(p)
    if st is None:
        raise ConfigError(f"{target}: not a results file of this project (an HDF5 file with the root "
                          "attributes stage and config)")
    if st not in stages:
        raise ConfigError(f"{target}: a {st!r} result, whose figures this command does not draw "
                          f"(it draws {', '.join(stages)})")
    return [(p, st)]


def draw_collected(calls) -> list[Path]:
    """:func:`draw_figures` of ``calls``, returning the files they wrote (each call returns a
    path or a list of paths).

    Parameters
    ----------
    calls : iterable of callable
        The figure calls.

    Returns
    -------
    list of pathlib.Path
        The files written, in order.

    Raises
    ------
    acmm_qpp.errors.FigureError
        A figure could not be drawn or written.
    """
    written: list[Path] = []

    def keep(call):
        def run():
            out = call()
            written.extend(Path(x) for x in (out if isinstance(out, (list, tuple)) else [out]) if x is not None)
        return run

    draw_figures([keep(c) for c in calls])
    return written


#: vector formats whose files matplotlib dates by default → the metadata key of that date
_DATED_FORMATS = {"pdf": "CreationDate", "svg": "Date", "ps": "CreationDate", "eps": "CreationDate"}
