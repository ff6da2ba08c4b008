"""Field types of the ``qpp`` configuration (CR-185644 Part III, ch. 10–14 examples): numbers
that may be written as ``"<number> <unit>"`` strings and are converted to SI on load, the bound
on plausible magnitudes, and the strict base model of every section.

Moved out of :mod:`qpp.io.config` (issue 12).
"""
from __future__ import annotations

from typing import Annotated, Optional

import numpy as np
from pydantic import BaseModel, model_validator

from acmm_qpp.config_model import StrictModel
from acmm_qpp.config_model import quantity

Matrix = list[list[float]]


def _q(unit: str):
    """A number, or a ``"<number> <unit>"`` string converted (pint) to the SI unit ``unit``;
    ``None`` passes (optional fields)."""
    return quantity(unit, allow_none=True)


Seconds = Annotated[float, _q("s")]
OptSeconds = Annotated[Optional[float], _q("s")]
RadPerSecond = Annotated[float, _q("rad/s")]
PerSecond = Annotated[float, _q("1/s")]
Kilograms = Annotated[float, _q("kg")]
Metres = Annotated[float, _q("m")]
KgM2 = Annotated[float, _q("kg*m^2")]
Radians = Annotated[float, _q("rad")]
#: Largest magnitude accepted for any number of a qpp config (matrix entry, gain, weight,
#: amplitude, time); beyond it products in the design and the simulation overflow (issue 13).
QPP_MAX = 1e12


def _implausible(v):
    """The first number in ``v`` (scalar or nested list) with |x| > QPP_MAX, else ``None``."""
    if isinstance(v, bool) or isinstance(v, BaseModel):
        return None
    if isinstance(v, (int, float)):
        return v if abs(v) > QPP_MAX else None
    if isinstance(v, (list, tuple)):
        for x in v:
            bad = _implausible(x)
            if bad is not None:
                return bad
    return None


class SectionModel(StrictModel):
    """Strict base of every qpp config section: unknown keys, NaN, infinity and booleans given as
    numbers refused (:class:`acmm_qpp.config_model.StrictModel`), and every number within the
    plausible magnitude ``QPP_MAX``."""

    @model_validator(mode="after")
    def _plausible_magnitudes(self):
        for name in type(self).model_fields:
            bad = _implausible(getattr(self, name))
            if bad is not None:
                raise ValueError(f"{name}: {bad:.4g} is outside the plausible range |value| ≤ {QPP_MAX:g}")
        return self


def finite_matrix(v):
    """A matrix field: a non-empty list of rows of one length, finite numbers.

    Parameters
    ----------
    v : object
        The value read from the config.

    Returns
    -------
    list of list
        ``v`` unchanged (units of its field).

    Raises
    ------
    ValueError
        Not such a matrix (the message says what is wrong).
    """
    if not isinstance(v, list) or not v or not all(isinstance(r, list) for r in v):
        raise ValueError("must be a non-empty matrix (list of rows)")
    if len({len(r) for r in v}) != 1 or not v[0]:
        raise ValueError(f"rows must all have the same, non-zero length (got row lengths {[len(r) for r in v]})")
    a = np.asarray(v, float)
    if not np.all(np.isfinite(a)):
        raise ValueError("must contain finite numbers")
    return v
