"""Work and size limits (issue 13: nothing hangs), each changed without editing code through an
environment variable ``ACMM_LIMIT_<NAME>`` (e.g. ``ACMM_LIMIT_CONFIG_BYTES=4000000``).

A config that would exceed a limit is refused at validation with one line naming the field, the
limit and the variable that raises it (:func:`how_to_raise`).  The base's own limits bound the
reading of a YAML config (:data:`DEFAULTS`); each product keeps the table of its own work limits
(``acmm.LIMITS``, ``qpp.LIMITS``) and passes it to :func:`limit`.

=====================  ============  ==========================================================
name                   default       what it bounds
=====================  ============  ==========================================================
CONFIG_BYTES           1 000 000     size of a YAML config file, bytes
YAML_DEPTH             32            nesting depth of mappings/lists in a YAML config
YAML_NODES             20 000        scalars + collections in a YAML config (aliases expanded)
=====================  ============  ==========================================================
"""
from __future__ import annotations

import os
from collections.abc import Mapping

from acmm_qpp.errors import ConfigError

DEFAULTS: dict[str, float] = {
    "CONFIG_BYTES": 1_000_000,
    "YAML_DEPTH": 32,
    "YAML_NODES": 20_000,
}


def limit(name: str, defaults: Mapping[str, float] = DEFAULTS) -> float:
    """The value of limit ``name`` (``ACMM_LIMIT_<name>`` overrides the default).

    Parameters
    ----------
    name : str
        A key of ``defaults``.
    defaults : mapping, optional
        The table the limit belongs to: :data:`DEFAULTS` (the YAML reading) or a product's.

    Returns
    -------
    float
        The limit, in the unit of its table (bytes, samples, 1, s, ...).

    Raises
    ------
    ConfigError
        The variable is set to something else than a positive finite number (it was ignored
        without a word: a review).
    """
    raw = os.environ.get(f"ACMM_LIMIT_{name}")
    if raw is None or not raw.strip():
        return defaults[name]
    try:
        value = float(raw)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise ConfigError(f"ACMM_LIMIT_{name}: must be a positive number (got {raw!r}); unset it for the "
                          f"default {defaults[name]:.6g}")
    return value


def how_to_raise(name: str, defaults: Mapping[str, float] = DEFAULTS) -> str:
    """The hint appended to a refusal: which environment variable raises the limit.

    Parameters
    ----------
    name : str
        A key of ``defaults``.
    defaults : mapping, optional
        The table the limit belongs to (:func:`limit`).

    Returns
    -------
    str
        The hint, with the current value of the limit.
    """
    return f"limit {limit(name, defaults):.6g}; set ACMM_LIMIT_{name} to change it"
