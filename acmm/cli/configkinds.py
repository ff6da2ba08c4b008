"""The three config kinds (acmm run, sweep, qpp) side by side: the JSON schema of each, and
loading a file of any kind (CR-185644 Part II for acmm and sweeps, Part III for qpp); which kind a
YAML file is, is :meth:`acmm_qpp.cli.plumbing.ConfigKinds.kind_of` of :data:`acmm.cli.command.CONFIGS`.
It imports ``acmm`` and ``qpp``; neither imports it (``tests/test_layers.py``).
"""
from __future__ import annotations

import json

from acmm import DEFAULT_CONFIG, PACKAGED_CONFIGS
from acmm.io.config import load_config, split_overrides
from acmm.io.schema import acmm_schema
from acmm.sweep.config import load_sweep
from acmm.sweep.spec import sweep_schema
from acmm.cli.command import CONFIGS
from acmm_qpp.configio import apply_overrides, read_yaml
import qpp.io.config


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
    schema = {"acmm": acmm_schema, "sweep": sweep_schema, "qpp": qpp.io.config.qpp_schema}[kind]()
    return json.dumps(schema, indent=2, ensure_ascii=False)


def load_any(path, overrides=None):
    """Read a config of any kind (detected), apply the overrides, validate (``acmm validate``).

    Parameters
    ----------
    path : str or os.PathLike or None
        YAML file or packaged name; None, or an override that names no file, means the packaged
        default (with that override first: :func:`acmm.io.config.split_overrides`).
    overrides : list of str, optional
        ``key.path=value`` overrides, applied before validation.

    Returns
    -------
    tuple
        ``(kind, model)``: the kind (:meth:`acmm_qpp.cli.plumbing.ConfigKinds.kind_of` of
        :data:`acmm.cli.command.CONFIGS`) and the validated model, its origin remembered.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        Exactly like the kind's own loader.
    """
    path, overrides = split_overrides(path, overrides)
    data, p = read_yaml(DEFAULT_CONFIG if path is None else path, PACKAGED_CONFIGS)
    kind = CONFIGS.kind_of(apply_overrides(data, overrides))
    # the kind's own loader (schedule.to and the like relative to the config's folder, as `acmm
    # tea|design|...` read them)
    return kind, {"sweep": load_sweep, "qpp": qpp.io.config.load_config, "acmm": load_config}[kind](p, overrides)
