"""The strict pydantic base of every config section (acmm, sweep, qpp).

Unknown keys, NaN and infinity are refused, the model is frozen; an unknown key's error names the
closest valid key of its own model ("did you mean `x`?", :mod:`difflib`) or lists that model's keys
when none is close (a wrap validator: each model knows its keys).  A YAML boolean is not a
number: pydantic's lax mode would read ``count: true`` as 1 and ``rate: false`` as 0,
so a boolean given where the field wants a number (or a list of numbers) is refused, naming
the field.  Strict mode for the whole model is not used: it would also refuse YAML lists for
tuple fields and plain strings for enum fields.
"""
from __future__ import annotations

import difflib
import types
import typing
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError, model_validator
from pydantic_core import PydanticCustomError

_NUMBERS = (int, float, complex)
#: the pydantic error type of a boolean given as a number; its context names the field, which
#: :func:`acmm_qpp.configio` adds to the error's location
BOOLEAN_AS_NUMBER = "boolean_as_number"


def closest(word: str, candidates: list[str]) -> str | None:
    """The candidate closest to ``word`` (case-insensitive difflib ratio ≥ 0.6), or None.

    Parameters
    ----------
    word : str
        The misspelt word.
    candidates : list of str
        Valid spellings.

    Returns
    -------
    str or None
        The closest candidate, in its own spelling.
    """
    lower = {c.lower(): c for c in candidates}
    m = difflib.get_close_matches(str(word).lower(), list(lower), n=1, cutoff=0.6)
    return lower[m[0]] if m else None


def union_members(annotation: Any) -> list:
    """The types an annotation can hold, with ``Optional``/``Union``/``Annotated`` removed.

    Parameters
    ----------
    annotation : type or typing form
        A field's annotation.

    Returns
    -------
    list
        The members, each a type or a generic alias (``list[float]``, ``dict[str, float]``…).
    """
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return union_members(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [x for arg in typing.get_args(annotation) for x in union_members(arg)]
    return [annotation]


def _kinds(annotation: Any) -> tuple[set, list]:
    """(the scalar types ``annotation`` admits, the element annotations of its list/tuple
    types, and the values' of its mappings)."""
    scalars, elements = set(), []
    for member in union_members(annotation):
        origin, args = typing.get_origin(member), typing.get_args(member)
        if origin in (list, tuple, set, frozenset):
            elements += [a for a in args if a is not Ellipsis]
        elif origin is dict:
            elements += [args[1]] if len(args) == 2 else []
        elif isinstance(member, type):
            scalars.add(member)
    return scalars, elements


def boolean_as_number(annotation: Any, value: Any) -> bool:
    """Whether ``value`` holds a boolean where ``annotation`` wants a number (at any depth of
    its lists and tuples).

    Parameters
    ----------
    annotation : type or typing form
        The field's annotation (``float``, ``Optional[float]``, ``tuple[float, float]``,
        ``list[list[float]]``, ``dict[str, float]``, …).
    value : object
        The value as read from the config.

    Returns
    -------
    bool
        True when a boolean stands where only a number (int, float, complex) is admitted (in
        a list, tuple or the values of a mapping too).
    """
    scalars, elements = _kinds(annotation)
    if isinstance(value, bool):
        return bool(scalars & set(_NUMBERS)) and bool not in scalars
    if isinstance(value, dict) and elements:
        return any(boolean_as_number(elements[0], v) for v in value.values())
    if isinstance(value, (list, tuple)) and elements:
        if len(elements) == len(value) and len(elements) > 1:        # a fixed tuple
            return any(boolean_as_number(a, v) for a, v in zip(elements, value))
        return any(boolean_as_number(a, v) for a in elements for v in value)
    return False


class StrictModel(BaseModel):
    """Base of every config section: unknown keys, NaN, infinity and booleans-as-numbers refused."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _no_boolean_numbers(cls, data: Any) -> Any:
        # a model-level check: a field validator on every field would also wrap the ``kind``
        # discriminator of a tagged union (qpp's nonlinearity), which pydantic refuses
        if isinstance(data, dict):
            for name, field in cls.model_fields.items():
                key = field.alias or name
                if key in data and boolean_as_number(field.annotation, data[key]):
                    raise PydanticCustomError(BOOLEAN_AS_NUMBER, "expected a number, got a boolean (true/false)",
                                              {"field": key})
        return data

    @model_validator(mode="wrap")
    @classmethod
    def _unknown_keys_named(cls, data: Any, handler) -> Any:
        # pydantic's "extra inputs are not permitted" for a key of this model becomes "unknown key
        # (did you mean `x`?)" or "(valid keys: ...)"; every other error keeps its type, message
        # and context (an inner model's unknown keys were named by that model)
        try:
            return handler(data)
        except ValidationError as exc:
            errors = exc.errors()
            if not any(e["type"] == "extra_forbidden" and len(e["loc"]) == 1 for e in errors):
                raise
            keys = list(cls.model_fields)
            for e in errors:
                if e["type"] == "extra_forbidden" and len(e["loc"]) == 1:
                    best = closest(str(e["loc"][0]), keys)
                    e["msg"] = "unknown key " + (f"(did you mean `{best}`?)" if best else f"(valid keys: {', '.join(keys)})")
            raise ValidationError.from_exception_data(exc.title, [
                {**e, "type": PydanticCustomError(e["type"], e["msg"], e.get("ctx"))} for e in errors]) from None
