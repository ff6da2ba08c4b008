"""JSON schemas of the acmm config kinds (acmm run and sweep), generated from the pydantic models
so that they accept what the loader accepts (the generic machinery is :mod:`acmm_qpp.config_model`,
acmm's own forms :class:`AcmmGenerator`):

* a dimensional field (one converted by a unit-aware before-validator, e.g. ``"2 N*m"``) is
  ``number`` **or** a ``"<number> [unit]"`` string; a vector of them likewise per element;
* ``inertia`` may also be a symmetric 3×3 list of rows; a choice spelt ``true`` (``sweep.tea_estimate``)
  also a YAML boolean;
* a sweep file is either a sweep file proper (``sweep.base``/``bases``) or an ordinary acmm
  config with an inline ``sweep`` section (no ``base``/``bases``).

What JSON Schema cannot express is left to the loader: cross-field rules (``simulation.levels``
against the design points, matrix shapes of a qpp plant, a positive-definite inertia, a unit of the
right dimension).  Also, like pydantic's lax mode, the loader converts numeric strings (``"0.5"``)
where a number is expected; the schema documents the canonical number form.

Editors: ``acmm schema --kind acmm > acmm.schema.json`` and a first line
``# yaml-language-server: $schema=./acmm.schema.json`` in the YAML file (VS Code's YAML
extension, any editor using yaml-language-server).
"""
from __future__ import annotations

from acmm_qpp.config_model import Generator, header, quantity_schema
from acmm.io.config import Config


def _inertia_matrix() -> dict:
    return {"type": "array", "minItems": 3, "maxItems": 3,
            "description": "symmetric 3×3 inertia matrix, rows",
            "items": {"type": "array", "minItems": 3, "maxItems": 3,
                      "items": quantity_schema({"type": "number"})}}


class AcmmGenerator(Generator):
    """The base's schema generator (:class:`acmm_qpp.config_model.Generator`), taught acmm's own forms:
    an inertia given as a 3×3 matrix, a vector of three values ``[roll, pitch, yaw]``, a choice
    spelt like a YAML boolean (``sweep.tea_estimate: true``) also given as one."""

    def function_before_schema(self, schema):
        """The JSON schema of a field with a before-validator, widened to the accepted forms.

        Parameters
        ----------
        schema : dict
            pydantic-core schema of the ``function-before`` node.

        Returns
        -------
        dict
            JSON schema: the base's, with the inertia matrix or a boolean alternative, or three
            elements.
        """
        qual = getattr(schema.get("function", {}).get("function"), "__qualname__", "")
        generated = super().function_before_schema(schema)
        inner = schema["schema"]
        if inner.get("type") == "literal" and {"true", "false"} & set(map(str, inner["expected"])):
            return {"anyOf": [generated, {"type": "boolean"}]}
        if qual.endswith("Inertia._from_matrix"):
            return {"anyOf": [generated, _inertia_matrix()]}
        if "_vec3" in qual and "items" in generated:          # [roll, pitch, yaw]
            generated["minItems"] = generated["maxItems"] = 3
        return generated


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


def acmm_schema() -> dict:
    """Schema of an acmm run config (:class:`acmm.io.config.Config`).

    Returns
    -------
    dict
        JSON schema (draft 2020-12); dimensional fields accept a number in the report's units or
        a quantity string in any unit of the field's dimension.
    """
    schema = Config.model_json_schema(mode="validation", schema_generator=AcmmGenerator)
    return header(fix_alternatives(schema), "acmm run config (CR-185644 Part II)")
