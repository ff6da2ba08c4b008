"""Generic machinery of the JSON schemas of the config kinds (issue 12): quantity fix-ups, the
schema header and the model-schema helper, shared by :mod:`acmm.io.schema` and :mod:`qpp.io.schema`.

The schema generated from a pydantic config model accepts what the loader accepts:

* a dimensional field (one converted by a unit-aware before-validator, e.g. ``"2 N*m"``) is
  ``number`` **or** a ``"<number> [unit]"`` string; a vector of them likewise per element;
* ``inertia`` may also be a symmetric 3×3 list of rows; a choice spelt ``true`` also a YAML
  boolean.

This module imports neither ``acmm`` nor ``qpp``: it recognises the before-validators by their
kind and qualified name only.
"""
from __future__ import annotations

from pydantic.json_schema import GenerateJsonSchema

__all__ = ["QUANTITY_PATTERN", "Generator", "fix_alternatives", "header", "model_schema"]

#: "<number>" or "<number> <unit>" (the unit is checked by the loader, dimension included).
QUANTITY_PATTERN = r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?:\s*\S.*)?$"

_QUANTITY_STRING = {"type": "string", "pattern": QUANTITY_PATTERN,
                    "description": "a number with a unit, e.g. \"2 N*m\", \"31.5e6 kg*m^2\", \"0.063 deg/s\""}


def _quantity(number_schema: dict) -> dict:
    """``number`` (with the field's bounds) or a quantity string."""
    return {"anyOf": [number_schema, dict(_QUANTITY_STRING)]}


def _inertia_matrix() -> dict:
    return {"type": "array", "minItems": 3, "maxItems": 3,
            "description": "symmetric 3×3 inertia matrix, rows",
            "items": {"type": "array", "minItems": 3, "maxItems": 3,
                      "items": _quantity({"type": "number"})}}


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
            a list of quantities, an inertia matrix alternative or a boolean alternative.
        """
        inner_core = schema["schema"]
        fn = schema.get("function", {}).get("function")
        qual = getattr(fn, "__qualname__", "")
        generated = super().function_before_schema(schema)
        if qual.endswith("Inertia._from_matrix"):
            return {"anyOf": [generated, _inertia_matrix()]}
        if inner_core.get("type") == "literal" and {"true", "false"} & set(map(str, inner_core["expected"])):
            # a choice spelt like a YAML boolean (sweep.tea_estimate: true) is also accepted as one
            return {"anyOf": [generated, {"type": "boolean"}]}
        kind = inner_core.get("type")
        if kind == "float":
            return _quantity(generated)
        if kind == "list" and inner_core.get("items_schema", {}).get("type") == "float":
            out = dict(generated)
            out["items"] = _quantity(generated.get("items", {"type": "number"}))
            if "_vec3" in qual:                 # [roll, pitch, yaw]
                out["minItems"] = out["maxItems"] = 3
            return out
        return generated


def header(schema: dict, kind: str, title: str) -> dict:
    """The schema with the draft-2020-12 ``$schema`` and a ``title`` in front.

    Parameters
    ----------
    schema : dict
        JSON schema body.
    kind : str
        Config kind (``acmm``, ``sweep`` or ``qpp``); kept for the callers' symmetry.
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


def fix_alternatives(schema: dict) -> dict:
    """Move object-only keywords into the object branch of a model with an alternative form.

    A model with a before-validator accepting another form (Inertia: a 3×3 list) comes out as
    ``{anyOf: [object, matrix], additionalProperties: false}``; the object-only keywords belong
    inside the object branch.

    Parameters
    ----------
    schema : dict
        JSON schema with ``$defs``; modified in place.

    Returns
    -------
    dict
        The same ``schema``.
    """
    for d in schema.get("$defs", {}).values():
        if "anyOf" in d and d.get("anyOf") and d["anyOf"][0].get("type") == "object":
            for key in ("additionalProperties", "required", "properties"):
                if key in d:
                    d["anyOf"][0][key] = d.pop(key)
            d.pop("type", None)
    return schema


def model_schema(model_cls) -> dict:
    """The validation-mode JSON schema of a pydantic model, quantities widened.

    Parameters
    ----------
    model_cls : type
        A pydantic ``BaseModel`` subclass.

    Returns
    -------
    dict
        Its JSON schema (:class:`Generator`, :func:`fix_alternatives`).
    """
    return fix_alternatives(model_cls.model_json_schema(mode="validation", schema_generator=Generator))

