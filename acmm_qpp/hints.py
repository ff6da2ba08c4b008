"""Hints attached to user-facing error messages.

* :func:`unknown_key_hint` — the closest valid key of the model at an error's location
  ("did you mean `x`?", :mod:`difflib`), or the list of valid keys when none is close;
* :func:`prioritize` — the error to report first: an unknown key explains the "missing field"
  errors it causes (a misspelt key of a section is one typo, not a missing field for each of its
  required ones);
* :func:`missing_config_message` — a config that is neither a file nor a packaged name lists the
  packaged names (closest first).

Which setting to change when a solver or a design fails is the knowledge of the product that
raises the error: it passes ``hint=`` to the error (:class:`acmm_qpp.errors.AcmmError`).
"""
from __future__ import annotations

import difflib
import typing
from importlib import resources
from pathlib import Path

from pydantic import BaseModel

from acmm_qpp.config_model import union_members


# ---------------------------------------------------------------------------------------------
# unknown keys
# ---------------------------------------------------------------------------------------------
def _step(tp, key):
    """The annotation reached from ``tp`` by one location element ``key`` (None if unknown)."""
    for t in union_members(tp):
        if isinstance(t, type) and issubclass(t, BaseModel):
            if isinstance(key, str) and key in t.model_fields:
                return t.model_fields[key].annotation
            continue
        origin = typing.get_origin(t)
        args = typing.get_args(t)
        if origin in (list, tuple) and isinstance(key, int) and args:
            return args[0]
        if origin is dict and len(args) == 2:
            return args[1]
    # a tagged-union tag in the location (pydantic puts the discriminator value there)
    for t in union_members(tp):
        if isinstance(t, type) and issubclass(t, BaseModel) and isinstance(key, str):
            f = t.model_fields.get("kind")
            if f is not None and typing.get_args(f.annotation) == (key,):
                return t
    return None


def model_at(model_cls: type, loc: tuple) -> type | None:
    """The pydantic model class at an error location ``loc`` below ``model_cls`` (or None).

    Parameters
    ----------
    model_cls : type
        Root pydantic model (a config class).
    loc : tuple
        pydantic error location: field names and list indices, from the root.

    Returns
    -------
    type or None
        The one model class the location leads to; None when unknown or ambiguous.
    """
    tp = model_cls
    for key in loc:
        tp = _step(tp, key)
        if tp is None:
            return None
    models = [t for t in union_members(tp) if isinstance(t, type) and issubclass(t, BaseModel)]
    return models[0] if len(models) == 1 else None


def valid_keys(model_cls: type, loc: tuple) -> list[str]:
    """Field names of the model holding ``loc[-1]`` (the parent of an unknown key).

    Parameters
    ----------
    model_cls : type
        Root pydantic model.
    loc : tuple
        Error location of the unknown key, from the root.

    Returns
    -------
    list of str
        The parent model's field names (empty when it is not known).
    """
    m = model_at(model_cls, tuple(loc[:-1]))
    return [] if m is None else list(m.model_fields)


def closest(word: str, candidates: list[str]) -> str | None:
    """The candidate closest to ``word`` (case-insensitive difflib ratio ≥ 0.6), or None.

    Parameters
    ----------
    word : str
        The misspelt word.
    candidates : list of str
        Valid spellings.

    Returns
    -------
    str or None
        The closest candidate, in its own spelling.
    """
    lower = {c.lower(): c for c in candidates}
    m = difflib.get_close_matches(str(word).lower(), list(lower), n=1, cutoff=0.6)
    return lower[m[0]] if m else None


def unknown_key_hint(model_cls: type, loc: tuple) -> str:
    """`` (did you mean `x`?)`` or `` (valid keys: a, b, c)`` for an unknown key at ``loc``.

    Parameters
    ----------
    model_cls : type
        Root pydantic model.
    loc : tuple
        Error location of the unknown key.

    Returns
    -------
    str
        The hint, with a leading space; empty when the parent model is not known.
    """
    keys = valid_keys(model_cls, loc)
    if not keys:
        return ""
    best = closest(str(loc[-1]), keys)
    if best is not None:
        return f" (did you mean `{best}`?)"
    return " (valid keys: " + ", ".join(keys) + ")"


def prioritize(errors: list[dict]) -> list[dict]:
    """Errors in reporting order: unknown keys first (they usually cause the 'missing' ones).

    Parameters
    ----------
    errors : list of dict
        pydantic's ``ValidationError.errors()``.

    Returns
    -------
    list of dict
        The same errors, ``extra_forbidden`` ones first (stable order otherwise).
    """
    return sorted(errors, key=lambda e: 0 if e.get("type") == "extra_forbidden" else 1)


# ---------------------------------------------------------------------------------------------
# packaged config names
# ---------------------------------------------------------------------------------------------
def packaged_names(package: str) -> list[str]:
    """Names of the configs shipped with the package (without ``.yaml``).

    Parameters
    ----------
    package : str
        The data package of the packaged configs.

    Returns
    -------
    list of str
        Sorted names; empty when the data package cannot be read.
    """
    try:
        return sorted(Path(p.name).stem for p in resources.files(package).iterdir()
                      if p.name.endswith(".yaml"))
    except (OSError, ModuleNotFoundError):  # pragma: no cover
        return []


def missing_config_message(path, package: str) -> str:
    """``config file not found: x (not a packaged config either; did you mean `y`? packaged: ...)``.

    Parameters
    ----------
    path : str or path-like
        The config as the user gave it.
    package : str
        The data package of the packaged configs.

    Returns
    -------
    str
        The one-line message.
    """
    names = packaged_names(package)
    msg = f"config file not found: {path}"
    p = Path(str(path))
    if len(p.parts) == 1 and names:
        best = closest(p.stem, names)
        hint = f"did you mean `{best}`? " if best else ""
        msg += f" (not a packaged config either; {hint}packaged configs: {', '.join(names)})"
    elif names:
        msg += f" (packaged configs, usable by name: {', '.join(names)})"
    return msg
