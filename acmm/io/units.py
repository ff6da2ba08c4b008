"""acmm's results in the unit system of ``output.units`` (:mod:`acmm.model.unit_systems`): the
datasets by their unit strings (:func:`convert_items`), and what needs the 24 states of eq 4.47
(:func:`state_factors`, :func:`state_space_in`); the general unit handling lives in
:mod:`acmm_qpp.units`.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from acmm_qpp.results import Dataset
from acmm_qpp.units import conversion_factor
import numpy as np
from acmm.model.linearize import state_units
from acmm.model.unit_systems import to_system


def state_factors(drf_mode: str = "attitude_hold", system: str = "imperial"):
    """(factors d, units) of the 24 states of eq 4.47 under ``system``: x_system = d · x_report.

    Angles stay in rad, rates in rad/s; momentum-like states become N·m·s (·sⁿ) under SI.

    Parameters
    ----------
    drf_mode : str, optional
        ``"attitude_hold"`` or ``"momentum_hold"`` (:func:`acmm.model.linearize.state_units`).
    system : str, optional
        ``"imperial"`` (the report's units: factors all 1) or ``"SI"``.

    Returns
    -------
    tuple
        ((24,) array of dimensionless factors d, list of the 24 unit strings under ``system``).
    """

    units = state_units(drf_mode)
    if system != "SI":
        return np.ones(len(units)), units
    si = [u.replace("ft*lbf", "N*m") for u in units]
    return np.array([conversion_factor(u, v) for u, v in zip(units, si)]), si


def state_space_in(system: str, drf_mode: str, **arrays):
    """Per-state matrices of the report's units expressed in ``system`` (x_sys = D x, u_sys = k u):
    A → D A D⁻¹, B, G → D B / k, K (…, 3, 24) → k K D⁻¹, P, Q → D⁻¹ P D⁻¹, R → R / k²,
    x (…, 24) or scales → D x; a DRF block ``drf`` (…, 12) → D[12:] x.  Returns a dict of the
    arrays given (unchanged under imperial).

    Parameters
    ----------
    system : str
        ``"imperial"`` or ``"SI"``.
    drf_mode : str
        DRF mode of the 24 states (:func:`state_factors`).
    **arrays : dict
        Named arrays in the report's units (ft·lbf, rad, s); names A, B, G, K, P, Q, R, x, scales
        or drf; a None value passes through.

    Returns
    -------
    dict
        The same names, as float arrays in the units of ``system``.

    Raises
    ------
    KeyError
        For an array name not listed above.
    """
    d, _ = state_factors(drf_mode, system)
    k = conversion_factor("ft*lbf", "N*m") if system == "SI" else 1.0
    rules = {"A": lambda a: d[:, None] * a / d[None, :], "B": lambda a: d[:, None] * a / k,
             "G": lambda a: d[:, None] * a / k, "K": lambda a: k * a / d,
             "P": lambda a: a / d[:, None] / d[None, :], "Q": lambda a: a / d[:, None] / d[None, :],
             "R": lambda a: a / k ** 2, "x": lambda a: a * d, "scales": lambda a: a * d, "drf": lambda a: a * d[12:]}
    return {name: None if a is None else rules[name](np.asarray(a, float)) for name, a in arrays.items()}


def convert_items(items: Mapping[str, Any], system: str) -> dict:
    """A copy of ``items`` with each dataset in its output unit (:func:`acmm.model.unit_systems.output_unit`):
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
    out = {}
    for key, value in items.items():
        if isinstance(value, Mapping):
            out[key] = convert_items(value, system)
            continue
        data = value.data if isinstance(value, Dataset) else None     # (not a Dataset: write_h5 reports it)
        if data is None or isinstance(data, str) or np.asarray(data).dtype.kind not in "fc":
            out[key] = value
            continue
        try:
            new, unit = to_system(np.asarray(data), value.units, system)
        except ValueError:
            new, unit = data, value.units
        out[key] = value if unit == value.units else replace(value, data=new, units=unit)
    return out
