"""The three config kinds (acmm run, sweep, qpp) side by side: which kind a YAML file is, its
JSON schema, and loading a file of any kind (CR-185644 Part II for acmm and sweeps, Part III for
qpp).

This package sits above both cores (like :mod:`acmm.report`, below :mod:`acmm_qpp.cli`): it imports ``acmm``
and ``qpp``, neither of them imports it at import time (``tests/test_layers.py``).  It is not
part of :mod:`acmm_qpp.cli` because tests and scripts use it without the command line, and its
:func:`load_any` validates models, which is more than parsing arguments.  The schemas themselves
are in :mod:`acmm.io.schema`, :mod:`qpp.io.schema` and :mod:`acmm_qpp.schema`.
"""
from __future__ import annotations

import json

from acmm_qpp.configio import detect_kind

__all__ = ["KINDS", "detect_kind", "load_any", "schema_for", "schema_json"]

KINDS = ("acmm", "sweep", "qpp")


def schema_for(kind: str) -> dict:
    """The JSON schema of a config kind.

    Parameters
    ----------
    kind : str
        ``acmm``, ``sweep`` or ``qpp``.

    Returns
    -------
    dict
        JSON schema (draft 2020-12).
    """
    from acmm.io.schema import acmm_schema
    from acmm.sweep.spec import sweep_schema
    from qpp.io.schema import qpp_schema

    return {"acmm": acmm_schema, "sweep": sweep_schema, "qpp": qpp_schema}[kind]()


def schema_json(kind: str) -> str:
    """The JSON schema of a config kind as indented JSON text.

    Parameters
    ----------
    kind : str
        ``acmm``, ``sweep`` or ``qpp``.

    Returns
    -------
    str
        JSON text (UTF-8 characters kept).
    """
    return json.dumps(schema_for(kind), indent=2, ensure_ascii=False)




def load_any(path, overrides=None):
    """Read a config of any kind (detected), apply the overrides, validate.

    Parameters
    ----------
    path : str or os.PathLike
        YAML file.
    overrides : list of str, optional
        ``key.path=value`` overrides, applied before validation.

    Returns
    -------
    tuple
        ``(kind, model)``: the kind (:func:`detect_kind`) and the validated model, its origin
        remembered.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        Exactly like the kind's own loader.
    """
    from acmm.io.config import parse_config
    from acmm import DEFAULT_CONFIG, PACKAGED_CONFIGS
    from acmm_qpp.configio import read_yaml
    from acmm_qpp.overrides import apply_overrides, remember_origin

    data, p = read_yaml(DEFAULT_CONFIG if path is None else path, PACKAGED_CONFIGS)
    data = apply_overrides(data, overrides)
    kind = detect_kind(data)
    if kind == "sweep":
        from acmm.sweep.config import parse_sweep

        model = parse_sweep(data, source=str(p), directory=p.parent)
    elif kind == "qpp":
        from qpp.io.config import parse_config as parse_qpp

        model = parse_qpp(data, source=str(p))
    else:
        from acmm.io.config import resolve_references

        # schedule.to and the like relative to the config's folder, as `acmm tea|design|...` read them
        model = parse_config(resolve_references(data, p.parent, str(p)), source=str(p))
    return kind, remember_origin(model, str(p), overrides)
