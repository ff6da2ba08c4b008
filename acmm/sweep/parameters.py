"""The sweepable parameters of a sweep config (CR-185644 Table 1 inertias, eq 3.9 disturbance).

Relative inertia-element changes ``dI11 … dI23`` (shorthand ``inertia``), a uniform inertia
scale ``inertia_scale``, additive bias torques ``bias_roll|pitch|yaw`` (ft·lbf, shorthand
``bias``), a factor on the harmonic amplitudes ``harmonic_scale`` (eq 3.9) and initial attitude
offsets ``offset_roll|pitch|yaw`` (deg, shorthand ``offset``); and the conversion of a value
given with a unit to the parameter's unit.
"""
from __future__ import annotations

from dataclasses import dataclass
from acmm_qpp.units import to_canonical


@dataclass(frozen=True)
class Parameter:
    """A sweepable quantity: unit, neutral value, kind (relative | scale | absolute).

    Attributes
    ----------
    name : str
        Parameter name (a column of ``sweep.csv``).
    unit : str
        Its unit: ``"1"`` (dimensionless), ``"ft*lbf"`` or ``"deg"``.
    neutral : float
        The value that leaves the base config unchanged, in ``unit``.
    kind : str
        ``relative`` (x → x·(1 + p)), ``scale`` (x → p·x) or ``absolute`` (added).
    description : str
        What it changes.
    """

    name: str
    unit: str
    neutral: float
    kind: str
    description: str


_AX = ("roll", "pitch", "yaw")
_ELEMENTS = ("I11", "I22", "I33", "I12", "I13", "I23")

#: Every sweepable parameter, in canonical (column) order.
PARAMETERS: dict[str, Parameter] = {}
for _e in _ELEMENTS:
    PARAMETERS[f"d{_e}"] = Parameter(f"d{_e}", "1", 0.0, "relative",
                                     f"relative change of {_e}: {_e} → {_e}·(1 + d{_e})")
PARAMETERS["inertia_scale"] = Parameter("inertia_scale", "1", 1.0, "scale",
                                        "uniform inertia scaling: I → s·I (applied after the element changes)")
for _a in _AX:
    PARAMETERS[f"bias_{_a}"] = Parameter(f"bias_{_a}", "ft*lbf", 0.0, "absolute",
                                         f"torque added to the {_a} bias (eq 3.9)")
PARAMETERS["harmonic_scale"] = Parameter("harmonic_scale", "1", 1.0, "scale",
                                         "factor on the harmonic amplitudes A and B (eq 3.9)")
for _a in _AX:
    PARAMETERS[f"offset_{_a}"] = Parameter(f"offset_{_a}", "deg", 0.0, "absolute",
                                           f"initial {_a} attitude minus the plant's TEA, added to "
                                           "simulation.initial_offset")

#: Shorthands expanding to several parameters (each drawn independently).
SHORTHANDS = {"inertia": [f"d{e}" for e in _ELEMENTS],
              "bias": [f"bias_{a}" for a in _AX],
              "offset": [f"offset_{a}" for a in _AX]}

#: Derived columns that may also be used as stability-map axes.
MAP_EXTRAS = ("tea_shift_roll", "tea_shift_pitch", "tea_shift_yaw")


def to_parameter_unit(v, unit: str, where: str):
    """A value that may carry a unit (``"2 N*m"``, ``"5 deg"``), converted (pint) to ``unit``.

    Parameters
    ----------
    v : float or str
        The value; a bare number is returned as it is (already in ``unit``).
    unit : str
        The target unit (``"1"``, ``"ft*lbf"``, ``"deg"``).
    where : str
        The config field, for error messages.

    Returns
    -------
    float
        The value in ``unit``.

    Raises
    ------
    ValueError
        The unit is malformed or of the wrong dimension (pydantic turns it into a field error).
    """
    if not isinstance(v, str):
        return v
    try:
        return to_canonical(v, unit)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def parameter_value(name: str, v, where: str):
    """A grid or distribution value of parameter ``name``, converted to its unit.

    Parameters
    ----------
    name : str
        The parameter (an unknown name returns ``v`` unchanged; the schema reports it).
    v : float or str
        The value, bare (in the parameter's unit) or with a unit.
    where : str
        The config field, for error messages.

    Returns
    -------
    float or str
        The value in the parameter's unit (:data:`PARAMETERS`).
    """
    p = PARAMETERS.get(name)
    return v if p is None else to_parameter_unit(v, p.unit, where)
