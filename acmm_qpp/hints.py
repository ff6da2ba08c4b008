"""Hints attached to user-facing error messages.

* :func:`unknown_key_hint` — the closest valid key of the model at an error's location
  ("did you mean `orbits`?", :mod:`difflib`), or the list of valid keys when none is close;
* :func:`prioritize` — the error to report first: an unknown key explains the "missing field"
  errors it causes (``Ixx:`` instead of ``I11:`` is one typo, not six missing fields);
* :func:`missing_config_message` — a config that is neither a file nor a packaged name lists the
  packaged names (closest first);
* :func:`numerical_hint` — which setting to change when a solver or a design fails.
"""
from __future__ import annotations

import difflib
import re
import types
import typing
from importlib import resources
from pathlib import Path

from pydantic import BaseModel

from acmm_qpp.errors import EXIT_NUMERICAL, NoEquilibriumError


# ---------------------------------------------------------------------------------------------
# unknown keys
# ---------------------------------------------------------------------------------------------
def _unwrap(tp) -> list:
    """The types an annotation can hold, with Optional/Union/Annotated removed."""
    origin = typing.get_origin(tp)
    if origin is typing.Annotated:
        return _unwrap(typing.get_args(tp)[0])
    if origin is typing.Union or origin is types.UnionType:
        return [x for a in typing.get_args(tp) for x in _unwrap(a)]
    return [tp]


def _step(tp, key):
    """The annotation reached from ``tp`` by one location element ``key`` (None if unknown)."""
    for t in _unwrap(tp):
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
    for t in _unwrap(tp):
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
    models = [t for t in _unwrap(tp) if isinstance(t, type) and issubclass(t, BaseModel)]
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
    """``config file not found: x (not a packaged config either; did you mean `mb3`? packaged: ...)``.

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


# ---------------------------------------------------------------------------------------------
# numerical failures
# ---------------------------------------------------------------------------------------------
#: (product, words that must all occur in the message, hint) — first match of the product's
#: entries wins; case-insensitive.  Each hint names settings of that product's configs only.
_NUMERICAL_HINTS: list[tuple[str, tuple[str, ...], str]] = [
    ("qpp", ("riccati 11.1",), "change hinf.rho or hinf.nu (larger values relax the H∞ problem), "
                               "or set hinf.search: true"),
    ("qpp", ("converge",), "change hinf.rho or hinf.nu, or loosen simulation.rtol / simulation.atol"),
    ("qpp", ("closed loop of these gains is unstable",),
     "these gains do not stabilize the plant: let the procedure find gains (design.gains: design)"),
    ("qpp", ("no certified design", "m < 1"), "no tracking loop meets these spheres: widen spheres.beta_o or "
                                              "narrow spheres.beta_ri"),
    ("qpp", ("no certified design", "β1 > m"), "widen spheres.beta_o, narrow spheres.beta_ri or the "
                                               "nonlinearity's parameter ranges, or allow a smaller "
                                               "design.rho_min (with design.wider_search)"),
    ("qpp", ("no certified design", "circle criterion"), "narrow the nonlinearity's sector (its parameter "
                                                         "ranges or y_range), or widen the search of a "
                                                         "(design.a_min, design.a_max)"),
    ("qpp", ("no stabilizing",), "change hinf.rho or hinf.nu, or set hinf.search: true"),
    ("qpp", ("required step size",), "the loop is stiff or escapes: check the gains, or loosen "
                                     "simulation.rtol / simulation.atol"),
    ("acmm", ("cannot shift the poles",), "widen design.sector.half_angle_deg or lower design.sector.sigma "
                                          "(a narrow sector leaves the moved poles a sliver of the plane), or "
                                          "try design.pole_method: uniform; a nearly uncontrollable model (see "
                                          "`acmm linearize`) needs another design.model or design.drf_mode"),
    ("acmm", ("residual",), "raise design.residual_tol or try design.riccati_method: {other}; a nearly "
                            "uncontrollable model (see `acmm linearize`) needs another design.model or design.drf_mode"),
    ("acmm", ("matrix sign",), "use design.riccati_method: {other} (the sign iteration needs a well-conditioned model)"),
    ("acmm", ("sector lqr", "riccati", "failed"), "lower design.sector.sigma (the shift α asked of the LQR may "
                                                  "be too large), or try another design.riccati_method ({other})"),
    ("acmm", ("riccati",), "try another design.riccati_method ({other})"),
    ("acmm", ("uncontrollable", "λ/n = 0+0j"), "no gain moves that pole and no sector (σ > 0) holds λ = 0: "
                                               "change design.model or design.drf_mode (an axisymmetric "
                                               "station's neutral mode, say)"),
    ("acmm", ("uncontrollable",), "no gain moves that pole: lower design.sector.sigma, or change design.model / "
                                  "design.drf_mode"),
    ("acmm", ("not positive semidefinite",), "change design.Q0 or design.R"),
    ("acmm", ("sector",), "lower design.sector.sigma, widen design.sector.half_angle_deg, or try "
                          "design.pole_method: uniform / shift"),
    ("acmm", ("blend toward schedule.to", "no torque-equilibrium"),
     "reduce the bias of disturbance or of schedule.to (their blend must balance at every s), or "
     "give each as its bias_from_tea"),
    ("acmm", ("no torque-equilibrium",), "reduce disturbance.bias (or use disturbance.bias_from_tea with the "
                                         "attitude you want)"),
    ("acmm", ("tea continuation",), "check the products of inertia (inertia.I12, I13, I23) or give the bias as "
                                    "disturbance.bias_from_tea"),
    ("acmm", ("converge",), "loosen the tolerance (design.residual_tol, simulation.rtol) or change "
                            "design.riccati_method ({other})"),
]


def numerical_hint(message: str, product: str = "acmm") -> str:
    """A "which setting to change" hint for a numerical failure message (empty if none applies).

    Parameters
    ----------
    message : str
        The failure message.
    product : {"acmm", "qpp"}, optional
        The command that failed: only its own settings are suggested.

    Returns
    -------
    str
        The first matching hint; empty when none applies or the message already has a hint.
    """
    low = message.lower()
    if "hint:" in low:
        return ""                      # already has one
    for prod, words, hint in _NUMERICAL_HINTS:
        if prod == product and all(w in low for w in words):
            return hint.replace("{other}", _other_riccati_methods(low))
    return ""


#: the values of design.riccati_method
_RICCATI_METHODS = ("scipy", "sign", "slycot")


def _other_riccati_methods(low_message: str) -> str:
    """The Riccati methods to suggest: all but the one the message says failed (``method='…'``)."""
    m = re.search(r"method='(\w+)'", low_message)
    used = m.group(1) if m else None
    return " or ".join(x for x in _RICCATI_METHODS if x != used)


def with_hint(exc: Exception, product: str = "acmm") -> str:
    """The message of a user-facing error, with a numerical hint appended when one applies
    (solver/design failures, exit 3, and a missing equilibrium).

    Parameters
    ----------
    exc : Exception
        The user-facing error.
    product : {"acmm", "qpp"}, optional
        The command that failed (:func:`numerical_hint`).

    Returns
    -------
    str
        ``str(exc)``, followed by ``; hint: ...`` when one applies.
    """
    msg = str(exc)
    if getattr(exc, "exit_code", None) == EXIT_NUMERICAL or isinstance(exc, NoEquilibriumError):
        hint = numerical_hint(msg, product)
        if hint:
            msg = f"{msg}; hint: {hint}"
    return msg
