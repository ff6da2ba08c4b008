"""Config fields holding a physical quantity: a number, or a ``"<number> <unit>"`` string.

The one pydantic before-validator of the acmm, sweep and qpp configs (:func:`quantity`): the
value is converted (pint, :func:`acmm_qpp.units.to_canonical`) to the field's unit and must be
finite; a config may add its own range check.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

from pydantic import BeforeValidator

from acmm_qpp.units import to_canonical


def quantity_value(value: object, unit: str, check: Optional[Callable[[float], float]] = None) -> float:
    """A number or ``"<number> <unit>"`` string in the unit ``unit``, checked finite.

    Parameters
    ----------
    value : float or str
        The value as written in the config (a bare number is in ``unit``).
    unit : str
        The field's unit, pint syntax (``"slug*ft^2"``, ``"s"``, ``"1"``).
    check : callable, optional
        ``check(x) -> x``: a further check of the converted value (e.g. a plausible range),
        raising :class:`ValueError`.

    Returns
    -------
    float
        The value in ``unit``.

    Raises
    ------
    ValueError
        Not a number, a wrong or unknown unit, not finite, or refused by ``check`` (pydantic
        adds the field name).
    """
    x = to_canonical(value, unit)
    if not math.isfinite(x):
        raise ValueError("must be a finite number")
    return x if check is None else check(x)


def quantity(unit: str, check: Optional[Callable[[float], float]] = None, *,
             allow_none: bool = False) -> BeforeValidator:
    """The before-validator of a quantity field in the unit ``unit`` (:func:`quantity_value`).

    Use as ``Annotated[float, quantity("s")]``.

    Parameters
    ----------
    unit : str
        The field's unit, pint syntax.
    check : callable, optional
        ``check(x) -> x``, a further check of the converted value.
    allow_none : bool
        Pass ``None`` through unchanged (for optional fields); otherwise ``None`` is refused
        as not a number.

    Returns
    -------
    pydantic.BeforeValidator
        The validator, converting to ``unit``.
    """
    def conv(v):
        if allow_none and v is None:
            return v
        return quantity_value(v, unit, check)
    return BeforeValidator(conv)
