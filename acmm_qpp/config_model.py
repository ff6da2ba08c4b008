"""The pydantic side of the configs (acmm, sweep, qpp): the strict base of every config section,
the quantity validator of their dimensional fields and the generator of their JSON schemas.

Unknown keys, NaN and infinity are refused, the model is frozen; an unknown key's error names the
closest valid key of its own model ("did you mean `x`?", :mod:`difflib`) or lists that model's keys
when none is close (a wrap validator: each model knows its keys).  A YAML boolean is not a
number: pydantic's lax mode would read ``count: true`` as 1 and ``rate: false`` as 0,
so a boolean given where the field wants a number (or a list of numbers) is refused, naming
the field.  Strict mode for the whole model is not used: it would also refuse YAML lists for
tuple fields and plain strings for enum fields.

A field holding a physical quantity (:func:`quantity`) takes a number, or a ``"<number> <unit>"``
string converted (pint, :func:`acmm_qpp.units.to_canonical`) to the field's unit; it must be
finite, and a config may add its own range check.

The JSON schema of a config model (issue 12; pydantic's ``model_json_schema(mode="validation",
schema_generator=Generator)``) accepts what the loader accepts: a dimensional field is ``number``
**or** a ``"<number> [unit]"`` string, a list of them likewise per element.  A product widens the
forms of its own fields in a subclass of :class:`Generator`; the schema header is :func:`header`.
"""
from __future__ import annotations

import difflib
import math
import types
import typing
from pathlib import Path
from typing import Any, Callable, Optional

import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, ValidationError, model_validator
from pydantic.json_schema import GenerateJsonSchema
from pydantic_core import PydanticCustomError

from acmm_qpp.units import to_canonical

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


def _union_members(annotation: Any) -> list:
    """The types an annotation can hold (each a type or a generic alias, ``list[float]``…), with
    ``Optional``/``Union``/``Annotated`` removed."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _union_members(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [x for arg in typing.get_args(annotation) for x in _union_members(arg)]
    return [annotation]


def _kinds(annotation: Any) -> tuple[set, list]:
    """(the scalar types ``annotation`` admits, the element annotations of its list/tuple
    types, and the values' of its mappings)."""
    scalars, elements = set(), []
    for member in _union_members(annotation):
        origin, args = typing.get_origin(member), typing.get_args(member)
        if origin in (list, tuple, set, frozenset):
            elements += [a for a in args if a is not Ellipsis]
        elif origin is dict:
            elements += [args[1]] if len(args) == 2 else []
        elif isinstance(member, type):
            scalars.add(member)
    return scalars, elements


def _boolean_as_number(annotation: Any, value: Any) -> bool:
    """Whether ``value`` (as read from the config) holds a boolean where ``annotation``
    (``float``, ``Optional[float]``, ``tuple[float, float]``, ``list[list[float]]``,
    ``dict[str, float]``, …) admits only a number (int, float, complex), at any depth of its
    lists, tuples and the values of its mappings."""
    scalars, elements = _kinds(annotation)
    if isinstance(value, bool):
        return bool(scalars & set(_NUMBERS)) and bool not in scalars
    if isinstance(value, dict) and elements:
        return any(_boolean_as_number(elements[0], v) for v in value.values())
    if isinstance(value, (list, tuple)) and elements:
        if len(elements) == len(value) and len(elements) > 1:        # a fixed tuple
            return any(_boolean_as_number(a, v) for a, v in zip(elements, value))
        return any(_boolean_as_number(a, v) for a in elements for v in value)
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
                if key in data and _boolean_as_number(field.annotation, data[key]):
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


class RunConfig:
    """The methods of a complete run config (a :class:`StrictModel` with ``name`` and ``output.root``)."""

    def run_dir(self) -> Path:
        """Directory of this run's results.

        Returns
        -------
        Path
            ``<output.root>/<name>``.
        """
        return Path(self.output.root) / self.name

    def to_yaml(self) -> str:
        """The resolved config (all defaults filled in) as YAML text, keys in schema order (what is
        embedded in every results file).

        Returns
        -------
        str
            The YAML text.
        """
        return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)


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


#: "<number>" or "<number> <unit>" (the unit is checked by the loader, dimension included).
QUANTITY_PATTERN = r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?:\s*\S.*)?$"

_QUANTITY_STRING = {"type": "string", "pattern": QUANTITY_PATTERN,
                    "description": "a number with a unit, e.g. \"2 N*m\", \"31.5e6 kg*m^2\", \"0.063 deg/s\""}


def quantity_schema(number_schema: dict) -> dict:
    """``number`` (with the field's bounds) or a quantity string.

    Parameters
    ----------
    number_schema : dict
        The JSON schema of the number.

    Returns
    -------
    dict
        ``{"anyOf": [number_schema, <quantity string>]}``.
    """
    return {"anyOf": [number_schema, dict(_QUANTITY_STRING)]}


class Generator(GenerateJsonSchema):
    """pydantic's schema generator, taught which before-validators widen the accepted input.

    Constructed like :class:`pydantic.json_schema.GenerateJsonSchema` (whose constructor it keeps).
    """

    def function_before_schema(self, schema):
        """The JSON schema of a field with a before-validator, widened to the accepted forms.

        Parameters
        ----------
        schema : dict
            pydantic-core schema of the ``function-before`` node.

        Returns
        -------
        dict
            JSON schema: a quantity (``number`` or ``"<number> <unit>"``, units of the field)
            or a list of quantities.
        """
        inner_core = schema["schema"]
        generated = super().function_before_schema(schema)
        kind = inner_core.get("type")
        if kind == "float":
            return quantity_schema(generated)
        if kind == "list" and inner_core.get("items_schema", {}).get("type") == "float":
            return {**generated, "items": quantity_schema(generated.get("items", {"type": "number"}))}
        return generated


def header(schema: dict, title: str) -> dict:
    """The schema with the draft-2020-12 ``$schema`` and a ``title`` in front.

    Parameters
    ----------
    schema : dict
        JSON schema body.
    title : str
        Title shown by editors.

    Returns
    -------
    dict
        A new schema mapping.
    """
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title, **schema}
