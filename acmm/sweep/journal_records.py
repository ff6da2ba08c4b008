"""What a sweep journal record must hold, checked when a sweep is resumed from its journal.

A journal line that is valid JSON but not a record the sweep wrote (edited, or from another
version) would otherwise fail later, deep in the table builder, with a traceback.
:func:`record_problem` names the first missing or mistyped field instead.
"""
from __future__ import annotations

import functools

import numpy as np
from acmm.sweep.case import empty_row
from acmm.sweep.cases import VERDICTS

_NUMBER = (int, float)

#: the fields a case record adds to its metrics row (:func:`acmm.sweep.case.empty_row`)
CASE_KEYS = {"base": ("str", ()), "index": ("int", ()), "n_draws": ("int", ())}


@functools.cache
def case_fields() -> dict:
    """Case record fields: name → (kind, shape), kind "num" (a number, NaN or ±inf), "int" or
    "str": :data:`CASE_KEYS` and the metrics row's fields, read off its empty row."""
    fields = dict(CASE_KEYS)
    for k, v in empty_row(1).items():
        fields[k] = ("str" if isinstance(v, str) else "int" if isinstance(v, int) else "num", np.shape(v))
    return fields


#: margin-search record fields, as :func:`case_fields` ("bool": true/false; shape None: a list)
MARGIN_FIELDS = {
    "base": ("str", ()), "direction": ("str", ()), "limit": ("num", ()), "first_failure": ("num", ()),
    "failure_verdict": ("str", ()), "failure_reason": ("str", ()), "reached_end": ("bool", ()),
    "search_end": ("num", ()), "evaluated_s": ("num", None), "evaluated_verdict": ("str", None),
}


def _is(kind: str, v) -> bool:
    if kind == "num":            # any float the sweep writes: finite, NaN or ±inf
        return isinstance(v, _NUMBER) and not isinstance(v, bool)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool) and v >= 0
    if kind == "bool":
        return isinstance(v, bool)
    return isinstance(v, str)


def _shaped(kind: str, v, shape) -> bool:
    if shape is None:
        return isinstance(v, list) and all(_is(kind, x) for x in v)
    if not shape:
        return _is(kind, v)
    return (isinstance(v, list) and len(v) == shape[0]
            and all(_shaped(kind, x, shape[1:]) for x in v))


def record_problem(rec: object, bases: set | None = None) -> str | None:
    """What is wrong with a journal record, or None when it is one the sweep wrote.

    Parameters
    ----------
    rec : object
        A parsed journal line (after the header).
    bases : set of str, optional
        The sweep's base labels (a record of another base is wrong).

    Returns
    -------
    str or None
        The first problem (a missing or mistyped field, an unknown verdict, kind or base).
    """
    if not isinstance(rec, dict):
        return "not a record (a JSON object)"
    kind = rec.get("kind")
    fields = case_fields() if kind == "case" else MARGIN_FIELDS if kind == "margin" else None
    if fields is None:
        return f"unknown record kind {kind!r}"
    for name, (k, shape) in fields.items():
        if name not in rec:
            return f"{kind} record without {name!r}"
        if not _shaped(k, rec[name], shape):
            return f"{kind} record with a malformed {name!r}"
    if kind == "case":
        if rec["verdict"] not in VERDICTS:
            return f"unknown verdict {rec['verdict']!r}"
        values = rec.get("values")
        if not isinstance(values, dict) or not all(_is("num", v) for v in values.values()):
            return "case record with a malformed 'values'"
    elif rec["direction"] not in ("up", "down"):
        return f"unknown margin direction {rec['direction']!r}"
    if bases is not None and rec["base"] not in bases:
        return f"record of base {rec['base']!r}, which the sweep does not have"
    return None
