"""What every stage shares: the config it is given (object, file or packaged name) and the
conversion of its per-state output arrays into the config's unit system.

Used by :mod:`acmm.stages.runners`, :mod:`acmm.stages.design` and :mod:`acmm.stages.simulate`.
"""
from __future__ import annotations

import functools
import operator
from pathlib import Path

import numpy as np

from acmm.io.config import Config, load_config, parse_config
import yaml
from dataclasses import replace
from acmm.io.dimensions import with_coordinates
from acmm.io.units import convert_items, state_factors, state_space_in
from acmm_qpp.results import h5_text, write_h5
from acmm_qpp.units import conversion_factor

#: The body axes, in the order of every per-axis array (the names of an ``axis`` dimension).
AXES = ["roll", "pitch", "yaw"]
#: Units of the per-state arrays, element by element: ``state_units[i]`` is the unit of state
#: ``i``, given by the dataset's ``state_units`` attribute (set by :func:`in_system`); under
#: ``output.units: SI`` ft*lbf reads N*m.  x' = A x + B u + G w (eq 4.46), u = −K x, and the
#: LQR cost ∫ (x'Q x + u'R u) dt = x0'P x0 with R in 1/(ft*lbf)^2 (ch. 5.2).
UNIT_STATE = "state_units[i]"
UNIT_A = "state_units[i]/(state_units[j]*s)"
UNIT_B = "state_units[i]/(s*ft*lbf)"
UNIT_K = "ft*lbf/state_units[j]"
UNIT_Q = "1/(state_units[i]*state_units[j])"
UNIT_P = "s/(state_units[i]*state_units[j])"


def in_system(items: dict, cfg: Config, roles: dict) -> dict:
    """Per-state arrays of ``items`` (path → role of :func:`acmm.io.units.state_space_in`) in the
    config's ``output.units``, each with a ``state_units`` attribute (the 24 state units, or the
    12 of the DRF block for role ``drf``) that its unit string refers to (:data:`UNIT_A`, …); a
    top-level ``state_units`` dataset follows too.  Other datasets are converted by unit string
    in :func:`write_results`.

    Parameters
    ----------
    items : dict
        The datasets (imperial units), nested by group.
    cfg : Config
        The run's config (its ``output.units`` and DRF mode).
    roles : dict
        Dataset path (``group/name``) → its role for :func:`acmm.io.units.state_space_in`.

    Returns
    -------
    dict
        ``items`` with those arrays converted to the config's unit system.
    """
    system = cfg.output.units
    _, su = state_factors(cfg.design.drf_mode, system)
    for path, role in roles.items():
        *groups, key = path.split("/")
        g = functools.reduce(operator.getitem, groups, items)
        ds = g[key]
        attrs = dict(ds.attrs, state_units=np.array(su[12:] if role == "drf" else su, dtype="S"))
        if system == "imperial":
            g[key] = replace(ds, attrs=attrs)
            continue
        new = state_space_in(system, cfg.design.drf_mode, **{role: ds.data})[role]
        g[key] = replace(ds, data=new, units=ds.units.replace("ft*lbf", "N*m"), attrs=attrs)
    if "state_units" in items:
        items["state_units"] = replace(items["state_units"], data=np.array(su, dtype="S"))
    return items


def write_results(path: Path, items: dict, cfg: Config, attrs: dict, aux_coords: tuple = ()) -> Path:
    """Write a stage's results file: ``items`` (the report's units) converted to the config's
    ``output.units`` (:func:`acmm.io.units.convert_items`, root attribute
    ``unit_system``), with the resolved config and the coordinates of acmm's dimensions
    (:func:`acmm.io.dimensions.with_coordinates`) by :func:`acmm_qpp.results.write_h5`.

    Parameters
    ----------
    path : Path
        The file.
    items : dict
        Name → :class:`acmm_qpp.results.Dataset` or group, in the report's units.
    cfg : Config
        The run's config.
    attrs : dict
        Root attributes (the stage's name and verdicts).
    aux_coords : tuple of str, optional
        Auxiliary coordinates along the time dimension (:func:`acmm.io.dimensions.with_coordinates`).

    Returns
    -------
    Path
        ``path``.
    """
    system = cfg.output.units
    return write_h5(path, with_coordinates(convert_items(items, system), aux_coords), cfg.to_yaml(),
                    {**attrs, "unit_system": system})


def define_units(items: dict, orbit_rate: float) -> dict:
    """``items`` with a ``units_definition`` attribute on every dataset in units of the orbit
    rate (``n``) or of orbits (``orbit``): the unit in pint's definition syntax, e.g.
    ``n = 0.0011313 * rad / s``, so ``pint.UnitRegistry().define(...)`` reads the file.

    Parameters
    ----------
    items : dict
        Name → :class:`acmm_qpp.results.Dataset` or nested dict (changed in place).
    orbit_rate : float
        The orbit rate n, rad/s.

    Returns
    -------
    dict
        ``items``.
    """
    definitions = {"n": f"n = {float(orbit_rate)!r} * rad / s",
                   "orbit": f"orbit = {float(2 * np.pi / orbit_rate)!r} * s"}
    for key, ds in items.items():
        if isinstance(ds, dict):
            define_units(ds, orbit_rate)
        elif getattr(ds, "units", None) in definitions:
            items[key] = replace(ds, attrs=dict(ds.attrs, units_definition=definitions[ds.units]))
    return items


def as_config(config) -> Config:
    """A config as given, or loaded from a file or packaged name.

    Parameters
    ----------
    config : Config, str or path-like
        The config, or what :func:`acmm.io.config.load_config` reads.

    Returns
    -------
    Config
        The validated config.
    """
    return config if isinstance(config, Config) else load_config(config)


def stored_config(attrs: dict) -> Config:
    """The config a results file was written from (its root attribute ``config``, the resolved
    YAML), validated again.

    Parameters
    ----------
    attrs : dict
        The file's root attributes (:func:`acmm_qpp.results.read_h5`'s ``"attrs"``).

    Returns
    -------
    acmm.io.config.Config
        The config.
    """
    return parse_config(yaml.safe_load(h5_text(attrs["config"])), source="stored config")


def stored_in(f, key: str, unit: str) -> np.ndarray:
    """Dataset ``key`` of an open results file (h5py) in the unit ``unit``, converted from the
    unit its ``units`` attribute names (a file in SI units is read back in the report's units).

    Parameters
    ----------
    f : h5py.File or h5py.Group
        The open file.
    key : str
        Dataset path.
    unit : str
        Unit wanted (e.g. ``"ft*lbf*s"``, ``"deg/s"``).

    Returns
    -------
    ndarray
        The values in ``unit``.
    """
    ds = f[key]
    stored = h5_text(ds.attrs.get("units", unit))
    value = np.asarray(ds[()])
    return value if stored == unit else value * conversion_factor(stored, unit)
