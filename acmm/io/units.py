"""Units of the acmm state vector; the general unit handling lives in :mod:`acmm_qpp.units`.

This module holds what needs the 24 states of eq 4.47: :func:`state_factors` and
:func:`state_space_in`.
"""
from __future__ import annotations

from acmm_qpp.units import conversion_factor
import numpy as np
from acmm.model.linearize import state_units


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
    out = {}
    for name, a in arrays.items():
        if a is None:
            out[name] = None
            continue
        a = np.asarray(a, float)
        if name == "A":
            out[name] = d[:, None] * a / d[None, :]
        elif name in ("B", "G"):
            out[name] = d[:, None] * a / k
        elif name == "K":
            out[name] = k * a / d
        elif name in ("P", "Q"):
            out[name] = a / d[:, None] / d[None, :]
        elif name == "R":
            out[name] = a / k ** 2
        elif name in ("x", "scales"):
            out[name] = a * d
        elif name == "drf":
            out[name] = a * d[12:]
        else:
            raise KeyError(name)
    return out
