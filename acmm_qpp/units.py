"""Physical units of config values (pint).

A config value may be a bare number (taken in the field's documented unit) or a string
``"<number> <unit>"`` in any unit pint understands (``"31.5e6 kg*m^2"``, ``"2 N*m"``,
``"1e-4 1/(N*m)^2"``, ``"0.063 deg/s"``); it is converted to the field's unit, and a unit of the
wrong dimension is an error naming the expected unit.  One :class:`pint.UnitRegistry`
(:func:`registry`) serves both products.
"""
from __future__ import annotations

import contextlib
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


_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _spell(unit: str) -> str:
    """Normalize the spellings pint does not take: · ² ³, and ``h`` (hour, not Planck)."""
    u = unit.strip().replace("·", "*").replace("²", "^2").replace("³", "^3").replace("⁻¹", "^-1")
    u = re.sub(r"(?<![A-Za-z_])h(?![A-Za-z_])", "hour", u)
    return re.sub(r"(?<![A-Za-z_])sec(?![A-Za-z_])", "s", u)


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
            with contextlib.suppress(pint.errors.DimensionalityError, ValueError):
                return float(ureg.Quantity(1.0, parse_unit(alt)).to(dst).magnitude)
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
