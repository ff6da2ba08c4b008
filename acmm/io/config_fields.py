"""Field types of the acmm configuration: quantities in the report's units (CR-185644 Table 1, eq 3.9).

A number may be written as ``"<number> <unit>"`` (:func:`acmm_qpp.config_model.quantity`); it is
converted to the report's units (slug·ft², ft·lbf, ft·lbf·s, deg, rad/s, s) and must lie
within a physically plausible range.  Also the strict base model of every section.

Moved out of :mod:`acmm.io.config` (issue 12).
"""
from __future__ import annotations

from typing import Annotated

from pydantic import BeforeValidator

from acmm_qpp.config_model import StrictModel
from acmm_qpp.config_model import quantity
from acmm.model.inertia import MAX_INERTIA


#: |value| bound per dimension, canonical units (issue 13: no overflow accepted): beyond it a value
#: is refused as a typo or an overflow hazard (bias torques are a few ft·lbf, CMG momentum ~1e4
#: ft·lbf·s; the inertia's reasoning is :data:`acmm.model.inertia.MAX_INERTIA`'s).
_RANGE = {"inertia": MAX_INERTIA, "torque": 1e9, "momentum": 1e12, "angle": 3600.0, "rate": 1.0, "time": 1e9}
_CANON = {"inertia": "slug·ft²", "torque": "ft·lbf", "momentum": "ft·lbf·s", "angle": "deg", "rate": "rad/s",
          "time": "s"}
#: The report's unit of each dimension kind of the config (pint syntax): a bare number is in it.
UNITS = {"inertia": "slug*ft^2", "torque": "ft*lbf", "momentum": "ft*lbf*s", "angle": "deg", "rate": "rad/s",
         "time": "s", "weight_torque": "1/(ft*lbf)^2"}


#: Smallest accepted principal moment of inertia, slug·ft² (a 1 cm, 1 g body is ~1e-8; below
#: this the linear model's scaling underflows and "uncontrollable" would be reported instead).
MIN_PRINCIPAL_MOMENT = 1e-6


def plausible_value(x: float, dimension: str) -> float:
    """``x`` itself when its magnitude is physically plausible for ``dimension``.

    Parameters
    ----------
    x : float
        A value in the canonical unit of its dimension (units of :data:`_CANON`).
    dimension : str
        Its dimension kind (``inertia``, ``torque``…).

    Returns
    -------
    float
        ``x``, unchanged (canonical unit).

    Raises
    ------
    ValueError
        ``|x|`` is beyond the plausible range of the dimension (the message names both).
    """
    bound = _RANGE.get(dimension)
    if bound is not None and abs(x) > bound:
        raise ValueError(f"{x:.4g} {_CANON[dimension]} is outside the physically plausible range "
                         f"|value| ≤ {bound:g} {_CANON[dimension]}")
    return x


def _q(dimension: str):
    """The quantity validator of the acmm config: in :data:`UNITS`, finite and within :data:`_RANGE`."""
    return quantity(UNITS[dimension], lambda x: plausible_value(x, dimension))


def _vec3(dimension: str):
    def conv(v):
        if isinstance(v, (str, int, float)) or not hasattr(v, "__len__"):
            raise ValueError("must be a list of three values [roll, pitch, yaw]")
        if len(v) != 3:
            raise ValueError(f"must have three values [roll, pitch, yaw], got {len(v)}")
        return [_q(dimension).func(x) for x in v]
    return BeforeValidator(conv)


InertiaValue = Annotated[float, _q("inertia")]
Torque = Annotated[float, _q("torque")]
Momentum = Annotated[float, _q("momentum")]
Angle = Annotated[float, _q("angle")]
Rate = Annotated[float, _q("rate")]
Time = Annotated[float, _q("time")]
TorqueVec = Annotated[list[float], _vec3("torque")]
AngleVec = Annotated[list[float], _vec3("angle")]
WeightTorque = Annotated[float, _q("weight_torque")]


class SectionModel(StrictModel):
    """Strict base of every config section: unknown keys, NaN, infinity and booleans given as
    numbers refused (:class:`acmm_qpp.config_model.StrictModel`)."""
