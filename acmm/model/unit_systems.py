"""The unit systems of acmm's outputs (``output.units``): ``imperial``, the report's units of
Table 1 (slug·ft², ft·lbf, ft·lbf·s, rad, s), or ``SI``.

Results are computed in the report's units and converted when written: angles are stored in rad
in every HDF5 file of both systems (a degree value is converted on writing,
:func:`acmm.io.units.convert_items`);
prints, CSV files and figures show degrees (:func:`shown`).  qpp works in SI only and converts
nothing.
"""
from __future__ import annotations

import math

from acmm_qpp.units import conversion_factor

#: 1 ft·lbf in N·m (exact by definition of the foot and the pound-force).
FT_LBF_IN_NM = 0.3048 * 4.4482216152605

#: imperial unit -> SI unit for each quantity kind that differs.
_SI = {
    "slug*ft^2": "kg*m^2",
    "ft*lbf": "N*m",
    "ft*lbf*s": "N*m*s",
    "ft*lbf*s^2": "N*m*s^2",
    "1/(ft*lbf)^2": "1/(N*m)^2",
}


def output_unit(unit: str, system: str = "imperial") -> str:
    """The unit a quantity stored in ``unit`` (report units) is written in under ``system``.

    Angles (deg) become rad in both systems (one angle unit in every file); imperial units
    become SI under ``SI``; anything else (``1``, ``s``, ``rad/s``, descriptive units) is kept.

    Parameters
    ----------
    unit : str
        The report unit of the quantity.
    system : {"imperial", "SI"}
        Output unit system.

    Returns
    -------
    str
        The unit written to output files.
    """
    if unit in ("deg", "deg/s"):
        return unit.replace("deg", "rad")
    return display_unit(unit, system)


def display_unit(unit: str, system: str = "imperial") -> str:
    """The unit shown to a person (prints, CSV, figures): like :func:`output_unit` but angles
    stay in degrees.

    Parameters
    ----------
    unit : str
        The report unit of the quantity.
    system : {"imperial", "SI"}
        Output unit system.

    Returns
    -------
    str
        The unit shown.
    """
    return _SI.get(unit, unit) if system == "SI" else unit


def to_system(value, unit: str, system: str = "imperial", display: bool = False):
    """(value, unit) of a report-unit quantity in ``system`` (``display``: degrees kept).

    Parameters
    ----------
    value : float or array
        The value, in the report unit ``unit``.
    unit : str
        Its report unit.
    system : {"imperial", "SI"}
        Output unit system.
    display : bool
        Keep degrees (as shown to a person) instead of converting them to rad.

    Returns
    -------
    value : float or array
        The value in the unit returned alongside.
    unit : str
        The unit of ``value`` under ``system``.
    """
    target = display_unit(unit, system) if display else output_unit(unit, system)
    if target == unit:
        return value, unit
    if unit in ("deg", "deg/s") and not display:
        return value * (math.pi / 180.0), target
    return value * conversion_factor(unit, target), target


def pretty(unit: str) -> str:
    """A unit as printed in labels: ``ft*lbf*s`` → ``ft·lbf·s``, ``kg*m^2`` → ``kg·m²``.

    Parameters
    ----------
    unit : str
        A unit in pint spelling.

    Returns
    -------
    str
        The unit as printed.
    """
    return unit.replace("*", "·").replace("^2", "²")


def shown(value, unit: str, system: str = "imperial"):
    """(value, unit) of a report-unit quantity as shown to a person under ``system``
    (prints, CSV, figures; angles stay in degrees).

    Parameters
    ----------
    value : float or array
        The value, in the report unit ``unit``.
    unit : str
        Its report unit.
    system : {"imperial", "SI"}
        Output unit system.

    Returns
    -------
    value : float or array
        The value in the unit returned alongside.
    unit : str
        The unit shown under ``system``.
    """
    return to_system(value, unit, system, display=True)
