"""JSON schemas of the three config kinds (acmm run, sweep, qpp), generated from the pydantic
models so that they accept what the loader accepts:

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

import copy
import json

from pydantic.json_schema import GenerateJsonSchema, models_json_schema

KINDS = ("acmm", "sweep", "qpp")

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


class _Generator(GenerateJsonSchema):
    """pydantic's generator, taught which before-validators widen the accepted input."""

    def function_before_schema(self, schema):
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


def _header(schema: dict, kind: str, title: str) -> dict:
    out = {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title}
    out.update(schema)
    return out


def _fix_alternatives(schema: dict) -> dict:
    """A model with a before-validator accepting another form (Inertia: a 3×3 list) comes out as
    ``{anyOf: [object, matrix], additionalProperties: false}``; the object-only keywords belong
    inside the object branch."""
    for d in schema.get("$defs", {}).values():
        if "anyOf" in d and d.get("anyOf") and d["anyOf"][0].get("type") == "object":
            for key in ("additionalProperties", "required", "properties"):
                if key in d:
                    d["anyOf"][0][key] = d.pop(key)
            d.pop("type", None)
    return schema


def _model_schema(model_cls) -> dict:
    return _fix_alternatives(model_cls.model_json_schema(mode="validation", schema_generator=_Generator))


def acmm_schema() -> dict:
    """Schema of an acmm run config (:class:`acmm.config.Config`)."""
    from acmm.config import Config

    return _header(_model_schema(Config), "acmm", "acmm run config (CR-185644 Part II)")


def qpp_schema() -> dict:
    """Schema of a qpp config (:class:`qpp.config.QppConfig`)."""
    from qpp.config import QppConfig

    return _header(_model_schema(QppConfig), "qpp", "qpp config (CR-185644 Part III)")


def sweep_schema() -> dict:
    """Schema of a sweep config: a sweep file, or an acmm config with an inline ``sweep`` section."""
    from acmm.config import Config
    from acmm.sweep.config import SweepFile, SweepSpec

    keys, top = models_json_schema([(SweepFile, "validation"), (Config, "validation"),
                                    (SweepSpec, "validation")], schema_generator=_Generator)
    defs = _fix_alternatives(top)["$defs"]
    ref_file = keys[(SweepFile, "validation")]["$ref"]
    ref_cfg = keys[(Config, "validation")]["$ref"]
    ref_spec = keys[(SweepSpec, "validation")]["$ref"]
    cfg_name = ref_cfg.split("/")[-1]
    inline = copy.deepcopy(defs[cfg_name])
    inline["title"] = "Config with an inline sweep section"
    inline["properties"]["sweep"] = {
        "allOf": [{"$ref": ref_spec},
                  {"not": {"anyOf": [{"required": ["base"]}, {"required": ["bases"]}]}}],
        "description": "sweep over this very config (no base/bases)"}
    inline["required"] = sorted(set(inline.get("required", [])) | {"sweep"})
    defs["InlineSweepConfig"] = inline
    file_name = ref_file.split("/")[-1]
    file_def = defs[file_name]
    # the file form needs a base: the loader reads a `sweep` without base/bases as inline
    file_def["properties"]["sweep"] = {"allOf": [file_def["properties"]["sweep"],
                                                 {"anyOf": [{"required": ["base"]}, {"required": ["bases"]}]}]}
    schema = {"anyOf": [{"$ref": ref_file}, {"$ref": "#/$defs/InlineSweepConfig"}], "$defs": defs}
    return _header(schema, "sweep", "acmm sweep config")


def schema_for(kind: str) -> dict:
    """The JSON schema of a config kind (``acmm``, ``sweep`` or ``qpp``)."""
    return {"acmm": acmm_schema, "sweep": sweep_schema, "qpp": qpp_schema}[kind]()


def schema_json(kind: str) -> str:
    return json.dumps(schema_for(kind), indent=2, ensure_ascii=False)


def detect_kind(data: object) -> str:
    """The kind of a parsed config mapping: ``sweep`` (has a ``sweep`` section), ``qpp`` (has a
    plant / nonlinearity / hinf / spheres section) or ``acmm``."""
    if isinstance(data, dict):
        if "sweep" in data:
            return "sweep"
        if any(k in data for k in ("plant", "nonlinearity", "hinf", "spheres")):
            return "qpp"
    return "acmm"


def load_any(path, overrides=None):
    """Read a config of any kind (detected), apply the overrides, validate; returns (kind, model).

    Raises :class:`common.errors.ConfigError` exactly like the kind's own loader."""
    from acmm.config import parse_config
    from common.configio import read_yaml
    from common.overrides import apply_overrides, remember_origin

    data, p = read_yaml(path)
    data = apply_overrides(data, overrides)
    kind = detect_kind(data)
    if kind == "sweep":
        from acmm.sweep.config import parse_sweep

        model = parse_sweep(data, source=str(p), directory=p.parent)
    elif kind == "qpp":
        from qpp.config import parse_config as parse_qpp

        model = parse_qpp(data, source=str(p))
    else:
        model = parse_config(data, source=str(p))
    return kind, remember_origin(model, str(p), overrides)
