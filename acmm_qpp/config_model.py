"""The strict pydantic base of every config section (acmm, sweep, qpp).

Unknown keys, NaN and infinity are refused, the model is frozen, and a YAML boolean is not a
number: pydantic's lax mode would read ``count: true`` as 1 and ``rate: false`` as 0,
so a boolean given where the field wants a number (or a list of numbers) is refused, naming
the field.  Strict mode for the whole model is not used: it would also refuse YAML lists for
tuple fields and plain strings for enum fields.
"""
from __future__ import annotations

import types
import typing
from typing import Any

from pydantic import BaseModel, ConfigDict, model_validator
from pydantic_core import PydanticCustomError

_NUMBERS = (int, float, complex)
#: the pydantic error type of a boolean given as a number; its context names the field, which
#: :func:`acmm_qpp.configio` adds to the error's location
BOOLEAN_AS_NUMBER = "boolean_as_number"


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
