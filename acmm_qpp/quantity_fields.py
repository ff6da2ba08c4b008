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


def quantity(unit: str, check: Optional[Callable[[float], float]] = None, *,
             allow_none: bool = False) -> BeforeValidator:
    """The before-validator of a quantity field in the unit ``unit``: a number (in ``unit``) or a
    ``"<number> <unit>"`` string, converted to ``unit``, checked finite and by ``check``.

    Use as ``Annotated[float, quantity("s")]``; its ``func`` converts one value (the elements of
    a list field).

    Parameters
    ----------
    unit : str
        The field's unit, pint syntax (``"slug*ft^2"``, ``"s"``, ``"1"``).
    check : callable, optional
        ``check(x) -> x``: a further check of the converted value (e.g. a plausible range),
        raising :class:`ValueError`.
    allow_none : bool
        Pass ``None`` through unchanged (for optional fields); otherwise ``None`` is refused
        as not a number.

    Returns
    -------
    pydantic.BeforeValidator
        The validator; it raises :class:`ValueError` (pydantic adds the field name) for a value
        that is not a number, has a wrong or unknown unit, is not finite or is refused by ``check``.
    """
    def conv(v):
        if allow_none and v is None:
            return v
        x = to_canonical(v, unit)
        if not math.isfinite(x):
            raise ValueError("must be a finite number")
        return x if check is None else check(x)
    return BeforeValidator(conv)
