"""Physical units accepted in configs, and their conversion to the report's units.

The report works in slug·ft², ft·lbf, ft·lbf·s, rad and s.  A config value may be a bare
number (taken in the field's documented unit) or a string ``"<number> <unit>"``; a unit of
the wrong dimension is rejected with a message naming the accepted units.
"""
from __future__ import annotations

import math
import re

#: 1 ft·lbf in N·m (exact by definition of the foot and the pound-force).
FT_LBF_IN_NM = 0.3048 * 4.4482216152605
#: 1 slug·ft² in kg·m² (1 slug = 1 lbf·s²/ft, so slug·ft² = lbf·ft·s²).
SLUG_FT2_IN_KGM2 = FT_LBF_IN_NM

#: dimension -> (canonical unit, {normalized unit: factor to canonical})
DIMENSIONS: dict[str, tuple[str, dict[str, float]]] = {
    "inertia": ("slug*ft^2", {
        "slug*ft^2": 1.0, "slug*ft2": 1.0, "ft^2*slug": 1.0,
        "kg*m^2": 1.0 / SLUG_FT2_IN_KGM2, "kg*m2": 1.0 / SLUG_FT2_IN_KGM2,
    }),
    "torque": ("ft*lbf", {
        "ft*lbf": 1.0, "lbf*ft": 1.0, "ft*lb": 1.0,
        "n*m": 1.0 / FT_LBF_IN_NM, "nm": 1.0 / FT_LBF_IN_NM,
    }),
    "momentum": ("ft*lbf*s", {
        "ft*lbf*s": 1.0, "lbf*ft*s": 1.0, "ft*lb*s": 1.0,
        "n*m*s": 1.0 / FT_LBF_IN_NM, "nms": 1.0 / FT_LBF_IN_NM,
    }),
    "angle": ("deg", {"deg": 1.0, "degree": 1.0, "degrees": 1.0, "rad": 180.0 / math.pi}),
    "rate": ("rad/s", {"rad/s": 1.0, "rad/sec": 1.0, "deg/s": math.pi / 180.0}),
    "time": ("s", {"s": 1.0, "sec": 1.0, "min": 60.0, "h": 3600.0}),
    "weight_torque": ("1/(ft*lbf)^2", {"1/(ft*lbf)^2": 1.0}),
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def normalize_unit(unit: str) -> str:
    """Canonical spelling of a unit string: lower case, ``*`` for products, no blanks."""
    u = unit.strip().lower().replace("·", "*").replace("-", "*").replace(" ", "*")
    u = u.replace("²", "^2").replace("**", "^")
    return re.sub(r"\*+", "*", u)


def to_canonical(value: object, dimension: str) -> float:
    """Convert a number or a ``"<number> <unit>"`` string to the dimension's canonical unit.

    Raises
    ------
    ValueError
        With a message naming the unit and the accepted ones.
    """
    canonical, table = DIMENSIONS[dimension]
    if isinstance(value, bool):
        raise ValueError("expected a number, got a boolean")
    if isinstance(value, (int, float)):
        return float(value)
    if not isinstance(value, str):
        raise ValueError(f"expected a number or a '<number> <unit>' string, got {value!r}")
    m = _QUANTITY.match(value)
    if not m:
        raise ValueError(f"cannot read {value!r} as '<number> <unit>'")
    number, unit = float(m.group(1)), m.group(2)
    if not unit:
        return number
    factor = table.get(normalize_unit(unit))
    if factor is None:
        accepted = sorted({k for k in table})
        raise ValueError(
            f"unit {unit!r} is not a unit of {dimension} (use {canonical}; accepted: {', '.join(accepted)})"
        )
    return number * factor
