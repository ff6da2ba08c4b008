"""Self-describing HDF5 results, written atomically.

Every dataset carries a ``units`` attribute; the root group carries the resolved config
(YAML text), its hash, the package version, the git commit when known and the creation
time.  Files are written to a temporary name in the target directory and renamed into
place, so an interrupted run never leaves a partial file.
"""
from __future__ import annotations

import hashlib
import json
import os
import subprocess
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Mapping

import numpy as np


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
    #: :mod:`common.netcdf_layout`.
    dims: tuple[str, ...] | None = None


#: Called with the path of each file :func:`atomic_path` completes (:mod:`common.outputs` adds
#: its recorder on import, so this module need not import it).
WRITTEN_HOOKS: list = []


def git_commit() -> str:
    """The git commit of the source tree, or ``"unknown"``.

    Returns
    -------
    str
        The commit hash, or ``"unknown"``.
    """
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5
        )
        if out.returncode == 0:
            return out.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return "unknown"


def config_hash(config_text: str) -> str:
    """SHA-256 of a canonical config text (first 16 hex digits).

    Parameters
    ----------
    config_text : str
        The canonical config text.

    Returns
    -------
    str
        The first 16 hex digits of the hash.
    """
    return hashlib.sha256(config_text.encode()).hexdigest()[:16]


def provenance(config_text: str) -> dict[str, str]:
    """Attributes stored on every results file.

    Parameters
    ----------
    config_text : str
        The resolved config as YAML.

    Returns
    -------
    dict
        Package, version, git commit, config hash and creation time (UTC).
    """
    from common import __version__

    return {
        "package": "acmm-qpp",
        "package_version": __version__,
        "git_commit": git_commit(),
        "config_hash": config_hash(config_text),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }


def _write_group(group, items: Mapping[str, Any]) -> None:
    for key, value in items.items():
        if isinstance(value, Mapping):
            _write_group(group.create_group(key), value)
            continue
        if not isinstance(value, Dataset):
            raise TypeError(f"results item {key!r} must be a Dataset or a mapping")
        data = value.data
        if isinstance(data, str):
            ds = group.create_dataset(key, data=data)
        else:
            arr = np.asarray(data)
            if arr.dtype.kind in "OU":   # text arrays: variable-length UTF-8 strings
                import h5py

                ds = group.create_dataset(key, data=arr.astype(object), dtype=h5py.string_dtype())
            else:
                ds = group.create_dataset(key, data=arr)
        ds.attrs["units"] = value.units
        if value.description:
            ds.attrs["description"] = value.description
        if value.names is not None:
            ds.attrs["names"] = json.dumps(list(value.names))
        for ak, av in value.attrs.items():
            ds.attrs[ak] = av


#: Run names (acmm, qpp and sweep configs, qpp scenarios): a single path component of letters,
#: digits, ``_ . -`` that does not start with a dot (so never ``.``/``..``/hidden), at most
#: :data:`RUN_NAME_MAX` characters (room for the longest file name written inside it).
RUN_NAME_PATTERN = r"^[A-Za-z0-9_-][A-Za-z0-9_.-]*$"
RUN_NAME_MAX = 100
#: ``output.root``: any path without a NUL byte.
ROOT_PATTERN = r"^[^\x00]+$"


def make_dirs(directory: str | Path) -> list[Path]:
    """Create ``directory`` and its missing parents; return the ones created (outermost first),
    so that a refused run can remove them again (:func:`remove_empty_dirs`).

    Parameters
    ----------
    directory : path-like
        The directory to create.

    Returns
    -------
    list of Path
        The directories created, outermost first.

    Raises
    ------
    NotADirectoryError
        ``directory`` exists but is not a directory.
    """
    d = Path(directory)
    missing = []
    while not os.path.lexists(d) and d != d.parent:
        missing.append(d)
        d = d.parent
    created = []
    try:
        for q in reversed(missing):
            try:
                os.mkdir(q)
            except FileExistsError:
                if not os.path.isdir(q):
                    raise
                continue
            created.append(q)
    except BaseException:
        remove_empty_dirs(created)
        raise
    if not os.path.isdir(directory):
        raise NotADirectoryError(20, "Not a directory", str(directory))
    return created


def remove_empty_dirs(created: list[Path]) -> None:
    """Remove the directories of :func:`make_dirs` again, innermost first, while they are empty.

    Parameters
    ----------
    created : list of Path
        Directories as returned by :func:`make_dirs`.
    """
    for q in reversed(created):
        try:
            os.rmdir(q)
        except OSError:
            break


def output_error(exc: OSError, what: str, where: str | Path):
    """A one-line :class:`~common.errors.OutputError` (exit 4) for an OS error while writing.

    Parameters
    ----------
    exc : OSError
        The error (an OutputError is returned as it is).
    what : str
        What was being written ("results", "figure", ...).
    where : path-like
        Where it was being written.

    Returns
    -------
    OutputError
        The error to raise.
    """
    from common.errors import OutputError

    if isinstance(exc, OutputError):
        return exc
    why = exc.strerror or str(exc)
    return OutputError(f"cannot write {what} {where}: {why}")


@contextmanager
def atomic_path(path: str | Path, what: str = "results"):
    """Yield a temporary path beside ``path``; on success it is renamed onto ``path``.

    The file gets the usual permissions (0666 & ~umask, not mkstemp's 0600); on any error the
    temporary file is removed, directories created for it are removed again, ``path`` is left
    as it was, and an OS error (read-only, not a directory, no space, name too long, a
    directory where the file should go) becomes one :class:`~common.errors.OutputError` line.

    Parameters
    ----------
    path : path-like
        The target file.
    what : str
        What is written, for error messages.

    Yields
    ------
    Path
        The temporary path to write to.

    Raises
    ------
    OutputError
        A directory of that name is in the way, or an OS error occurred.
    output_error
        (the :class:`~common.errors.OutputError` built by :func:`output_error` from an OS error)
    """
    from common.errors import OutputError

    path = Path(path)
    created: list[Path] = []
    try:
        created = make_dirs(path.parent)
        if os.path.isdir(path):
            remove_empty_dirs(created)
            raise OutputError(f"cannot write {what} {path}: a directory of that name is in the way")
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        remove_empty_dirs(created)
        raise output_error(exc, what, path) from None
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
        for hook in WRITTEN_HOOKS:
            hook(path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        remove_empty_dirs(created)
        if isinstance(exc, OSError):
            raise output_error(exc, what, path) from None
        raise


def write_bytes(path: str | Path, data: bytes, what: str = "results") -> Path:
    """Write ``data`` atomically with plain ``os.write`` calls and an fsync (see
    :func:`atomic_path`): a full disk is then an ordinary OSError → OutputError, never a crash
    inside a C library, and no temporary file survives.

    Parameters
    ----------
    path : path-like
        The target file.
    data : bytes-like
        The content.
    what : str
        What is written, for error messages.

    Returns
    -------
    Path
        ``path``.
    """
    with atomic_path(path, what) as tmp:
        fd = os.open(tmp, os.O_WRONLY | os.O_TRUNC | getattr(os, "O_CLOEXEC", 0))
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
            os.fsync(fd)
        finally:
            os.close(fd)
    return Path(path)


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file atomically (see :func:`atomic_path`).

    Parameters
    ----------
    path : path-like
        The target file.
    text : str
        The content, written as UTF-8.

    Returns
    -------
    Path
        ``path``.
    """
    return write_bytes(path, text.encode("utf-8"), "text")


@contextmanager
def _in_memory(path: Path, what: str = "results"):
    """Yield a :class:`io.BytesIO`; afterwards its bytes are written to ``path`` atomically.

    HDF5 files and figures are built in memory so that the libraries (HDF5 segfaults on ENOSPC)
    never write to the disk themselves."""
    import io

    buf = io.BytesIO()
    yield buf
    view = buf.getbuffer()                # no copy of a large file
    try:
        write_bytes(path, view, what)
    finally:
        view.release()


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
        are stored in rad in both systems (:func:`common.units.output_unit`).

    Returns
    -------
    Path
        ``path``.
    """
    from common.netcdf_layout import annotate, convert_items, unit_system_of
    import h5py

    path = Path(path)
    with _in_memory(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["config"] = config_text
            for k, v in provenance(config_text).items():
                f.attrs[k] = v
            for k, v in (attrs or {}).items():
                f.attrs[k] = v
            system = units or unit_system_of(config_text)
            items = convert_items(items, system)
            f.attrs["unit_system"] = system
            _write_group(f, items)
            annotate(f, items)
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

    The format is taken from ``path``'s suffix; ``kwargs`` go to ``savefig``.

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
    with _in_memory(path, "figure") as tmp:
        fig.savefig(tmp, format=path.suffix.lstrip(".") or "png", **kwargs)
    return path
