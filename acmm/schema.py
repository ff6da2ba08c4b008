"""JSON schemas of the acmm config kinds (acmm run and sweep), generated from the pydantic models
so that they accept what the loader accepts (the generic machinery is :mod:`common.schema`):

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

The qpp schema is :mod:`qpp.schema`; the dispatcher across the three kinds (:func:`schema_for`,
:func:`schema_json`, :func:`detect_kind`, :func:`load_any`) is :mod:`configkinds`, which sits above
both cores.  The four names stay importable from here: thin wrappers that import
:mod:`configkinds` when called, so importing ``acmm`` never loads ``qpp`` (``tests/test_layers.py``).

Editors: ``acmm schema --kind acmm > acmm.schema.json`` and a first line
``# yaml-language-server: $schema=./acmm.schema.json`` in the YAML file (VS Code's YAML
extension, any editor using yaml-language-server).
"""
from __future__ import annotations

import copy

from pydantic.json_schema import models_json_schema

from common.schema import (QUANTITY_PATTERN, _QUANTITY_STRING, _fix_alternatives,  # noqa: F401
                           _Generator, _header, _inertia_matrix, _model_schema, _quantity)

KINDS = ("acmm", "sweep", "qpp")


def acmm_schema() -> dict:
    """Schema of an acmm run config (:class:`acmm.config.Config`).

    Returns
    -------
    dict
        JSON schema (draft 2020-12); dimensional fields accept a number in the report's units or
        a quantity string in any unit of the field's dimension.
    """
    from acmm.config import Config

    return _header(_model_schema(Config), "acmm", "acmm run config (CR-185644 Part II)")


def sweep_schema() -> dict:
    """Schema of a sweep config: a sweep file, or an acmm config with an inline ``sweep`` section.

    Returns
    -------
    dict
        JSON schema (draft 2020-12) with ``anyOf`` the two forms.
    """
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


# ------------------------------------------------------------------------------------------------
# compatibility: the dispatcher moved to configkinds (issue 12); imported when called
# ------------------------------------------------------------------------------------------------
def qpp_schema() -> dict:
    """Schema of a qpp config; moved to :func:`qpp.schema.qpp_schema`.

    Returns
    -------
    dict
        JSON schema (draft 2020-12).
    """
    from qpp.schema import qpp_schema as impl

    return impl()


def schema_for(kind: str) -> dict:
    """The JSON schema of a config kind; moved to :func:`configkinds.schema_for`.

    Parameters
    ----------
    kind : str
        ``acmm``, ``sweep`` or ``qpp``.

    Returns
    -------
    dict
        JSON schema (draft 2020-12).
    """
    from configkinds import schema_for as impl

    return impl(kind)


def schema_json(kind: str) -> str:
    """The JSON schema of a config kind as indented JSON; moved to :func:`configkinds.schema_json`.

    Parameters
    ----------
    kind : str
        ``acmm``, ``sweep`` or ``qpp``.

    Returns
    -------
    str
        JSON text.
    """
    from configkinds import schema_json as impl

    return impl(kind)


def detect_kind(data: object) -> str:
    """The kind of a parsed config mapping; moved to :func:`configkinds.detect_kind`.

    Parameters
    ----------
    data : object
        Parsed YAML document.

    Returns
    -------
    str
        ``sweep``, ``qpp`` or ``acmm``.
    """
    from configkinds import detect_kind as impl

    return impl(data)


def load_any(path, overrides=None):
    """Read a config of any kind; moved to :func:`configkinds.load_any`.

    Parameters
    ----------
    path : str or os.PathLike
        YAML file.
    overrides : list of str, optional
        ``key.path=value`` overrides.

    Returns
    -------
    tuple
        ``(kind, model)``.
    """
    from configkinds import load_any as impl

    return impl(path, overrides)
