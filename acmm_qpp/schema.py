"""Generic machinery of the JSON schemas of the config kinds (issue 12): quantity fields widened
(:class:`Generator`, for pydantic's ``model_json_schema(mode="validation", schema_generator=...)``)
and the schema header, shared by :mod:`acmm.io.schema` and :mod:`qpp.io.schema`.

The schema generated from a pydantic config model accepts what the loader accepts:

* a dimensional field (one converted by a unit-aware before-validator, e.g. ``"2 N*m"``) is
  ``number`` **or** a ``"<number> [unit]"`` string; a list of them likewise per element;
* a choice spelt ``true`` is also a YAML boolean.

A product widens the forms of its own fields in a subclass of :class:`Generator`.
"""
from __future__ import annotations

from pydantic.json_schema import GenerateJsonSchema

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
            JSON schema: a quantity (``number`` or ``"<number> <unit>"``, units of the field),
            a list of quantities or a boolean alternative.
        """
        inner_core = schema["schema"]
        generated = super().function_before_schema(schema)
        if inner_core.get("type") == "literal" and {"true", "false"} & set(map(str, inner_core["expected"])):
            # a choice spelt like a YAML boolean is also accepted as one
            return {"anyOf": [generated, {"type": "boolean"}]}
        kind = inner_core.get("type")
        if kind == "float":
            return quantity_schema(generated)
        if kind == "list" and inner_core.get("items_schema", {}).get("type") == "float":
            out = dict(generated)
            out["items"] = quantity_schema(generated.get("items", {"type": "number"}))
            return out
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
    out = {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title}
    out.update(schema)
    return out
