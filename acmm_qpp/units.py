"""Physical units: config values with units, and the unit system of the outputs (pint).

The report works in slug·ft², ft·lbf, ft·lbf·s, rad and s.  A config value may be a bare
number (taken in the field's documented unit) or a string ``"<number> <unit>"`` in any unit
pint understands (``"31.5e6 kg*m^2"``, ``"2 N*m"``, ``"1e-4 1/(N*m)^2"``, ``"0.063 deg/s"``);
it is converted to the field's unit, and a unit of the wrong dimension is an error naming the
expected unit.  One :class:`pint.UnitRegistry` (:data:`ureg`) serves the whole package.

Outputs are written in the system chosen by ``output.units`` (:data:`SYSTEMS`): ``imperial``
(the report's units) or ``SI``.  Angles are stored in rad in every HDF5 file of both systems
(a degree value is converted on writing); prints, CSV files and figures show degrees.
"""
from __future__ import annotations

import math
import re
from functools import lru_cache


@lru_cache(maxsize=1)
def pint_module():
    """:mod:`pint`, imported on first use (~0.3 s, so runs whose configs hold bare numbers never
    pay for it).

    Returns
    -------
    module
        The pint module.
    """
    import pint  # deferred: pint start-up, only when a unit is converted

    return pint


@lru_cache(maxsize=1)
def registry():
    """The package's single :class:`pint.UnitRegistry` (built on first use: ~0.5 s, so runs whose
    configs hold bare numbers never pay for it)."""
    return pint_module().UnitRegistry()


#: 1 ft·lbf in N·m (exact by definition of the foot and the pound-force).
FT_LBF_IN_NM = 0.3048 * 4.4482216152605
#: 1 slug·ft² in kg·m² (1 slug = 1 lbf·s²/ft, so slug·ft² = lbf·ft·s²).
SLUG_FT2_IN_KGM2 = FT_LBF_IN_NM

#: Output unit systems: imperial unit -> SI unit for each quantity kind that differs.
SYSTEMS = ("imperial", "SI")
_SI = {
    "slug*ft^2": "kg*m^2",
    "ft*lbf": "N*m",
    "ft*lbf*s": "N*m*s",
    "ft*lbf*s^2": "N*m*s^2",
    "1/(ft*lbf)^2": "1/(N*m)^2",
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _spell(unit: str) -> str:
    """Normalize the spellings pint does not take: · ² ³, and ``h`` (hour, not Planck)."""
    u = unit.strip().replace("·", "*").replace("²", "^2").replace("³", "^3").replace("⁻¹", "^-1")
    u = re.sub(r"(?<![A-Za-z_])h(?![A-Za-z_])", "hour", u)
    u = re.sub(r"(?<![A-Za-z_])sec(?![A-Za-z_])", "s", u)
    return u


@lru_cache(maxsize=256)
def parse_unit(unit: str):
    """A pint unit from a string; ``ValueError`` if pint does not know it."""
    pint = pint_module()
    try:
        return registry().parse_units(_spell(unit))
    except Exception as exc:    # pint raises many kinds (tokenizer, syntax, undefined): one message
        if isinstance(exc, pint.errors.DimensionalityError):
            raise ValueError(f"unit {unit!r} cannot be used here: {exc}") from None
        raise ValueError(f"unknown unit {unit!r}") from exc


def conversion_factor(unit: str, target: str) -> float:
    """Factor from ``unit`` to ``target``.

    Parameters
    ----------
    unit : str
        The unit of a value (pint syntax; ``lb`` in a torque or momentum read as ``lbf``).
    target : str
        The unit to convert it to.

    Returns
    -------
    float
        The factor (dimensionless): a value in ``unit`` times it is in ``target``.

    Raises
    ------
    ValueError
        The dimensions differ (the message names both units).
    """
    pint = pint_module()
    ureg = registry()
    src, dst = parse_unit(unit), parse_unit(target)
    try:
        return float(ureg.Quantity(1.0, src).to(dst).magnitude)
    except (pint.errors.DimensionalityError, pint.errors.OffsetUnitCalculusError):
        # engineering habit: "lb" in a torque or momentum means pound-force
        alt = re.sub(r"(?<![A-Za-z_])lb(?![A-Za-z_])", "lbf", unit)
        if alt != unit:
            try:
                return float(ureg.Quantity(1.0, parse_unit(alt)).to(dst).magnitude)
            except (pint.errors.DimensionalityError, ValueError):
                pass
        raise ValueError(f"unit {unit!r} is not a unit of {target} (wrong dimension)") from None


def to_canonical(value: object, canonical: str) -> float:
    """Convert a number or a ``"<number> <unit>"`` string to the unit ``canonical``; a bare number
    is taken as already in that unit.

    Parameters
    ----------
    value : float or str
        A number (in the unit ``canonical``) or a ``"<number> <unit>"`` string.
    canonical : str
        The field's unit, pint syntax (``"slug*ft^2"``, ``"rad/s"``, ``"1"`` for a pure number).

    Returns
    -------
    float
        The value in the unit ``canonical``.

    Raises
    ------
    ValueError
        One line naming the unit and the expected one (pydantic adds the field name).
    """
    if isinstance(value, bool):
        raise ValueError("expected a number, got a boolean")
    if isinstance(value, (int, float)):
        try:
            return float(value)
        except OverflowError:                # an integer beyond the float range
            raise ValueError(f"{str(value)[:20]}... ({len(str(value))} digits) is beyond the range of a float") from None
    if not isinstance(value, str):
        raise ValueError(f"expected a number or a '<number> <unit>' string, got {value!r}")
    m = _QUANTITY.match(value)
    if not m:
        raise ValueError(f"cannot read {value!r} as '<number> <unit>'")
    number, unit = float(m.group(1)), m.group(2)
    if not unit:
        return number
    try:
        parse_unit(unit)
    except ValueError:
        raise ValueError(f"unknown unit {unit!r} (expected a unit of {canonical})") from None
    _check_angle(unit, canonical)
    return number * conversion_factor(unit, canonical)


def _check_angle(unit: str, canonical: str) -> None:
    """pint takes the radian as dimensionless, so it converts 1 Hz to 1 rad/s (not 2π) and 5 deg
    to the pure number 0.087: a ValueError for a cycle frequency (Hz) where an angular rate is
    asked, and for an angle where a pure number is."""
    def radian_power(u: str) -> float:
        return float(dict(registry().get_root_units(parse_unit(u))[1]._units).get("radian", 0.0))

    names = [str(k) for k in getattr(parse_unit(unit), "_units", {})]
    if radian_power(canonical) != 0 and radian_power(unit) == 0 and any(k.endswith("hertz") for k in names):
        raise ValueError(f"{unit!r} is cycles per second and this value an angular rate ({canonical}): "
                         f"give rad/s, deg/s, rpm or cycle/s (1 Hz = 2π rad/s)")
    if canonical == "1" and radian_power(unit) != 0:
        raise ValueError(f"unit {unit!r} is an angle, but this value is a pure number")


def convert(value, unit: str, target: str):
    """``value`` (number or array) in ``unit`` expressed in ``target``.

    Parameters
    ----------
    value : float or array
        The value, in the unit ``unit``.
    unit : str
        Its unit.
    target : str
        The unit wanted.

    Returns
    -------
    float or array
        The value in the unit ``target``.
    """
    return value * conversion_factor(unit, target)


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
    if unit == "deg":
        return "rad"
    if unit == "deg/s":
        return "rad/s"
    if system == "SI":
        return _SI.get(unit, unit)
    return unit


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
    if system == "SI":
        return _SI.get(unit, unit)
    return unit


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
    return convert(value, unit, target), target


def check_system(system: str) -> str:
    """``system`` if it is one of :data:`SYSTEMS` (case-insensitive), else ``ValueError``.

    Parameters
    ----------
    system : str
        A unit system's name, any case.

    Returns
    -------
    str
        The name as spelt in :data:`SYSTEMS`.

    Raises
    ------
    ValueError
        ``system`` is not one of :data:`SYSTEMS`.
    """
    for s in SYSTEMS:
        if str(system).lower() == s.lower():
            return s
    raise ValueError(f"unknown unit system {system!r} (use imperial or SI)")


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
