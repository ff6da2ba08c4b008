"""Command-line overrides in the dotted ``key=value`` style of Hydra / OmegaConf.

A command given ``CONFIG a.b=1 c.d=0.6`` reads CONFIG, sets the two values in the raw mapping
and only then validates it, so an override is checked exactly like the same value written in
the file (a misspelt key gets the file's "unknown key (did you mean …)" message).  Rules:

* ``a.b.c=value`` sets ``c`` inside ``a.b``; missing intermediate mappings are created (the
  file may rely on a section's defaults), an integer element addresses a list item
  (``a.list.1=5``);
* the value is parsed as YAML: ``10`` is an int, ``0.6`` a float, ``true`` a bool, ``null`` (or
  nothing after ``=``) is null, ``"2 N*m"`` or ``2 N*m`` a unit string, ``[0, 5, 0]`` a list;
* ``~a.b`` removes ``b`` from ``a`` (back to its default).

The overrides, in order, are kept with the loaded config (``override_list``) and written as a
comment heading the run folder's ``config.yaml``.
"""
from __future__ import annotations

import copy
import re

import yaml

from acmm_qpp.configio import load_yaml_text
from acmm_qpp.errors import EXIT_USAGE, ConfigError


class OverrideSyntaxError(ConfigError):
    """A command-line word that is not ``dotted.key=value`` / ``~dotted.key``: a usage error
    (exit 64), unlike a bad key or value, which is reported like the same error in the file (2)."""

    exit_code = EXIT_USAGE

_KEY = re.compile(r"^~?[A-Za-z_][A-Za-z0-9_]*(\.([A-Za-z0-9_]+))*$")


def looks_like_override(text: str) -> bool:
    """True when ``text`` has the form ``dotted.key=value`` or ``~dotted.key``.

    Parameters
    ----------
    text : str
        A command-line word.

    Returns
    -------
    bool
        It is an override.
    """
    text = str(text)
    if text.startswith("~"):
        return bool(_KEY.match(text))
    key, eq, _ = text.partition("=")
    return bool(eq) and bool(_KEY.match(key)) and not key.startswith("~")


def apply_overrides(data: object, overrides: list[str] | tuple[str, ...] | None) -> object:
    """A deep copy of the raw mapping ``data`` with every override applied in order.

    Parameters
    ----------
    data : object
        The config as read from YAML (a mapping; anything else is returned unchanged for the
        loader to report).
    overrides : list of str or None
        Overrides, applied left to right.

    Returns
    -------
    object
        The modified copy (``data`` itself when there is nothing to apply).

    Raises
    ------
    OverrideSyntaxError
        A word is not ``dotted.key=value`` / ``~dotted.key`` (exit 64).
    ConfigError
        A value is not valid YAML, or an override goes into a missing list element or inside a
        scalar value.
    """
    if not overrides:
        return data
    if not isinstance(data, dict):
        return data                       # the loader reports the malformed top level itself
    out = copy.deepcopy(data)
    for text in overrides:
        text = str(text)
        if not looks_like_override(text):
            raise OverrideSyntaxError(f"unexpected argument {text!r}: an override must read dotted.key=value "
                                      "or ~dotted.key to remove a key")
        dotted, _, raw = text.partition("=")
        delete = text.startswith("~")
        try:   # the value: YAML, with the bounds of a config file (depth, nodes with aliases expanded)
            value = load_yaml_text(raw, f"override {dotted}") if raw.strip() else None
        except yaml.YAMLError as exc:
            what = getattr(exc, "problem", None) or "not valid YAML"
            raise ConfigError(f"override {dotted}: value {raw!r} is not valid YAML ({what})") from None
        path = [int(p) if p.isdigit() else p for p in dotted.lstrip("~").split(".")]
        node = out
        for depth, key in enumerate(path):
            last, where = depth == len(path) - 1, ".".join(map(str, path[:depth + 1]))
            if isinstance(node, list):
                if not isinstance(key, int) or not -len(node) <= key < len(node):
                    raise ConfigError(f"override {text}: {where}: no such list element (the list has {len(node)})")
            elif not isinstance(node, dict):
                raise ConfigError(f"override {text}: {where.rpartition('.')[0] if last else where}: cannot go "
                                  f"inside a {type(node).__name__} value")
            elif not last and node.get(key) is None:
                if delete:
                    break                   # removing something that is not there: nothing to do
                if isinstance(path[depth + 1], int):
                    raise ConfigError(f"override {text}: {where} is not set in the file, so it has no element "
                                      f"{path[depth + 1]}; give the whole list ({where}=[...])")
                node[key] = {}
            if not last:
                node = node[key]
            elif not delete:
                node[key] = value
            elif isinstance(node, list):
                del node[key]
            else:
                node.pop(key, None)
    return out


# ---------------------------------------------------------------------------------------------
# where a loaded config came from (for the config.yaml header): carried by the loaded object itself,
# in an attribute that is no field, so that equality, hashing and the YAML dump of configs ignore it
# ---------------------------------------------------------------------------------------------
#: the attribute of a loaded config holding ``(source, overrides)``
ORIGIN_ATTRIBUTE = "_loaded_from"


def remember_origin(model: object, source: str, overrides: list[str] | None) -> object:
    """Record on ``model`` the file and the overrides it was loaded from; returns ``model``.

    The record is an attribute of the object (:data:`ORIGIN_ATTRIBUTE`), not a field: a frozen
    pydantic model or dataclass compares, hashes and dumps its fields only, so two configs of the
    same values are equal whatever their origin.

    Parameters
    ----------
    model : object
        The loaded config.
    source : str
        The file or packaged name.
    overrides : list of str or None
        The overrides applied.

    Returns
    -------
    object
        ``model``.
    """
    object.__setattr__(model, ORIGIN_ATTRIBUTE, (str(source), list(overrides or [])))
    return model


def origin_of(model: object) -> tuple[str | None, list[str]]:
    """(source, overrides) recorded by :func:`remember_origin`, or (None, []).

    Parameters
    ----------
    model : object
        A config.

    Returns
    -------
    tuple
        (source or None, list of overrides).
    """
    source, overrides = getattr(model, ORIGIN_ATTRIBUTE, (None, []))
    return source, list(overrides)
