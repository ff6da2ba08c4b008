"""The three config kinds (acmm run, sweep, qpp) side by side: which kind a YAML file is, its
JSON schema, and loading a file of any kind (CR-185644 Part II for acmm and sweeps, Part III for
qpp).

This package sits above both cores (like :mod:`acmm.report`, below :mod:`acmm_qpp.cli`): it imports ``acmm``
and ``qpp``, neither of them imports it at import time (``tests/test_layers.py``).  It is not
part of :mod:`acmm_qpp.cli` because tests and scripts use it without the command line, and its
:func:`load_any` validates models, which is more than parsing arguments.  The schemas themselves
are in :mod:`acmm.io.schema`, :mod:`qpp.io.config` and :mod:`acmm_qpp.config_model`.
"""
from __future__ import annotations

import json

from acmm import DEFAULT_CONFIG, PACKAGED_CONFIGS
from acmm.io.config import parse_config, resolve_references, split_overrides
from acmm.io.schema import acmm_schema
from acmm.sweep.config import parse_sweep
from acmm.sweep.spec import sweep_schema
from acmm.cli.command import CONFIGS
from acmm_qpp.configio import apply_overrides, read_yaml, remember_origin
from qpp.io.config import parse_config as parse_qpp, qpp_schema

__all__ = ["KINDS", "detect_kind", "load_any", "load_any_from_command_line", "schema_for", "schema_json"]

KINDS = ("acmm", "sweep", "qpp")


def detect_kind(data: object) -> str:
    """The kind of a parsed config (:data:`acmm.cli.command.CONFIGS`).

    Parameters
    ----------
    data : object
        Parsed YAML document.

    Returns
    -------
    str
        ``sweep`` (a ``sweep`` section, or the resolved form's ``sweep_file``), ``qpp`` (a plant,
        nonlinearity, hinf or spheres section) or ``acmm``.
    """
    return CONFIGS.kind_of(data)


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

    data, p = read_yaml(DEFAULT_CONFIG if path is None else path, PACKAGED_CONFIGS)
    data = apply_overrides(data, overrides)
    kind = detect_kind(data)
    if kind == "sweep":
        model = parse_sweep(data, source=str(p), directory=p.parent)
    elif kind == "qpp":
        model = parse_qpp(data, source=str(p))
    else:
        # schedule.to and the like relative to the config's folder, as `acmm tea|design|...` read them
        model = parse_config(resolve_references(data, p.parent, str(p)), source=str(p))
    return kind, remember_origin(model, str(p), overrides)


def load_any_from_command_line(config, overrides):
    """:func:`load_any` of a command's CONFIG and KEY=VALUE arguments (``acmm validate``): a
    CONFIG that is really an override means the packaged default with it
    (:func:`acmm.io.config.split_overrides`).

    Parameters
    ----------
    config : str or None
        The positional CONFIG (a file, a packaged name, an override, or None).
    overrides : list of str or None
        The ``key.path=value`` overrides after it.

    Returns
    -------
    tuple
        ``(kind, model)`` as :func:`load_any` returns them.
    """
    return load_any(*split_overrides(config, overrides))

