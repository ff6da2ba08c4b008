"""Config fields holding a physical quantity: a number, or a ``"<number> <unit>"`` string.

The one pydantic before-validator of the acmm, sweep and qpp configs (:func:`quantity`): the
value is converted (pint, :func:`acmm_qpp.units.to_canonical`) to the canonical unit of its
dimension kind and must be finite; a config may add its own range check.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

from pydantic import BeforeValidator

from acmm_qpp.units import to_canonical


def quantity_value(value: object, kind: str, check: Optional[Callable[[float, str], float]] = None) -> float:
    """A number or ``"<number> <unit>"`` string in the canonical unit of ``kind``, checked finite.

    Parameters
    ----------
    value : float or str
        The value as written in the config (a bare number is in the canonical unit).
    kind : str
        Dimension kind, a key of :data:`acmm_qpp.units.DIMENSIONS`.
    check : callable, optional
        ``check(x, kind) -> x``: a further check of the converted value (e.g. a plausible
        range), raising :class:`ValueError`.

    Returns
    -------
    float
        The value in the canonical unit of ``kind`` (:data:`acmm_qpp.units.DIMENSIONS`).

    Raises
    ------
    ValueError
        Not a number, a wrong or unknown unit, not finite, or refused by ``check`` (pydantic
        adds the field name).
    """
    x = to_canonical(value, kind)
    if not math.isfinite(x):
        raise ValueError("must be a finite number")
    return x if check is None else check(x, kind)


def quantity(kind: str, check: Optional[Callable[[float, str], float]] = None, *,
             allow_none: bool = False) -> BeforeValidator:
    """The before-validator of a quantity field of dimension kind ``kind`` (:func:`quantity_value`).

    Use as ``Annotated[float, quantity("torque")]``.

    Parameters
    ----------
    kind : str
        Dimension kind, a key of :data:`acmm_qpp.units.DIMENSIONS`.
    check : callable, optional
        ``check(x, kind) -> x``, a further check of the converted value.
    allow_none : bool
        Pass ``None`` through unchanged (for optional fields); otherwise ``None`` is refused
        as not a number.

    Returns
    -------
    pydantic.BeforeValidator
        The validator, converting to the canonical unit of ``kind``.
    """
    def conv(v):
        if allow_none and v is None:
            return v
        return quantity_value(v, kind, check)
    return BeforeValidator(conv)
