"""JSON schemas of the acmm config kinds (acmm run and sweep), generated from the pydantic models
so that they accept what the loader accepts (the generic machinery is :mod:`acmm_qpp.schema`):

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

The qpp schema is :mod:`qpp.io.schema`; the dispatcher across the three kinds (:func:`schema_for`,
:func:`schema_json`, :func:`detect_kind`, :func:`load_any`) is :mod:`acmm.cli.configkinds`.

Editors: ``acmm schema --kind acmm > acmm.schema.json`` and a first line
``# yaml-language-server: $schema=./acmm.schema.json`` in the YAML file (VS Code's YAML
extension, any editor using yaml-language-server).
"""
from __future__ import annotations


from acmm_qpp.schema import header, model_schema
from acmm.io.config import Config

def acmm_schema() -> dict:
    """Schema of an acmm run config (:class:`acmm.io.config.Config`).

    Returns
    -------
    dict
        JSON schema (draft 2020-12); dimensional fields accept a number in the report's units or
        a quantity string in any unit of the field's dimension.
    """
    return header(model_schema(Config), "acmm", "acmm run config (CR-185644 Part II)")
