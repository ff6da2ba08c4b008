"""YAML config files: bounded reading, structure checks, duplicate keys, pydantic validation.

Shared by the acmm and qpp configs (:mod:`acmm.io.config`, :mod:`qpp.io.config`) and the sweep spec:
:func:`read_yaml` reads a file (or a config packaged with the distribution) with the bounds of
:mod:`acmm_qpp.limits`, :func:`validate_model` turns a mapping into a pydantic model, and any
failure becomes one :class:`~acmm_qpp.errors.ConfigError` line naming the file, field or cause.

YAML that would be expensive or recursive to build is refused before it is built: the parser's
event stream is scanned first (iteratively, so deep nesting cannot overflow the stack), and
nesting deeper than ``YAML_DEPTH``, more than ``YAML_NODES`` nodes with aliases expanded (so
"billion laughs" alias bombs count at their expanded size) or an alias to a collection that
contains it (a cycle) raise :class:`~acmm_qpp.errors.ConfigError`; so do a list or mapping as a
key and an integer of more than 4300 digits (PyYAML's own failures besides syntax).

Command-line overrides in the dotted ``key=value`` style of Hydra / OmegaConf
(:func:`apply_overrides`): a command given ``CONFIG a.b=1 c.d=0.6`` reads CONFIG, sets the two
values in the raw mapping and only then validates it, so an override is checked exactly like the
same value written in the file (a misspelt key gets the file's "unknown key (did you mean …)"
message).  Rules:

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
import errno
import os
import re
import stat
from importlib import resources
from pathlib import Path

import yaml
from pydantic import ValidationError

from acmm_qpp.config_model import BOOLEAN_AS_NUMBER, closest
from acmm_qpp.errors import EXIT_USAGE, ConfigError
from acmm_qpp.limits import how_to_raise, limit


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that rejects duplicate keys (PyYAML silently keeps the last one)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":     # `<<: *anchor`, merged by SafeLoader
                continue                                       # (its keys may be overridden here)
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


#: the type names pydantic puts in an error's location for the members of a union
_UNION_MEMBERS = frozenset({"str", "float", "int", "bool", "list", "dict", "none", "bytes"})


def _user_path(loc: tuple, data: object) -> tuple:
    """The part of a pydantic error location ``loc`` on the input ``data`` that names the user's
    field: pydantic's own steps (``function-after[…]``, ``tagged-union[…]``, a union member's type
    name) and a discriminated union's tag value left out, so
    ``nonlinearity.expression.f1.0.function-after[…, LibraryForm].bogus`` reads ``nonlinearity.f1.0.bogus``."""
    out, cur = [], data
    for p in loc:
        if isinstance(cur, dict) and p in cur:               # the user's own key, whatever it looks like
            out.append(p)
            cur = cur[p]
            continue
        if isinstance(p, str) and any(c in p for c in "[](),"):
            continue                                        # a validator's own step
        if p in _UNION_MEMBERS:
            continue                                        # a union member's type (str | float | …)
        if isinstance(cur, dict):
            if p == cur.get("kind"):                        # a discriminated union's tag value
                continue
            out.append(p)                                   # a key the user did not write (missing)
            cur = None
        elif isinstance(cur, list) and isinstance(p, int) and 0 <= p < len(cur):
            out.append(p)
            cur = cur[p]
        elif cur is None or not (isinstance(p, str) and p[:1].isupper()):   # (a union member's class)
            out.append(p)
            cur = None
    return tuple(out)


def _format_error(exc: ValidationError, data: object = None) -> str:
    # unknown keys first: a misspelt key of a section is one typo, not also a missing field for
    # each of its required ones
    errors = sorted(exc.errors(), key=lambda e: e["type"] != "extra_forbidden")
    paths = [_user_path(tuple(e["loc"]), data) for e in errors]
    err, path = errors[0], paths[0]
    # a mapping where a union also allows a string or a number: the mapping member's own error,
    # deeper in the user's data, says more than "should be a valid string"
    deeper = [(e, q) for e, q in zip(errors[1:], paths[1:]) if len(q) > len(path) and q[:len(path)] == path]
    if deeper and err["type"] in ("string_type", "float_type", "int_type", "float_parsing", "bool_type"):
        err, path = deeper[0]
    loc = ".".join(str(p) for p in path)
    if err["type"] == BOOLEAN_AS_NUMBER:                     # a model-level check naming its field
        loc = f"{loc}.{err['ctx']['field']}" if loc else err["ctx"]["field"]
    loc = loc or "config"
    msg = err["msg"].removeprefix("Value error, ").removeprefix("Assertion failed, ")
    # other fields in error (the union's other members at the same place are not other errors)
    others = {q for q in paths[1:] if q != path[:len(q)]}
    extra = f" (and {len(others)} more)" if others else ""
    return f"{loc}: {msg}{extra}"


def require_mapping(data: object, source: str = "config") -> dict:
    """``data`` if it is a mapping, else a one-line :class:`ConfigError`.

    Parameters
    ----------
    data : object
        Parsed YAML.
    source : str
        Name of the file or section, for the message.

    Returns
    -------
    dict
        ``data``.

    Raises
    ------
    ConfigError
        ``data`` is not a mapping.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"{source}: the top level must be a mapping of keys to values")
    return data


def validate_model(model_cls, data: object, source: str = "config"):
    """Validate a mapping (e.g. parsed YAML) into a pydantic ``model_cls``; a
    :class:`ConfigError` naming the offending field otherwise.

    Parameters
    ----------
    model_cls : type
        The pydantic model class.
    data : object
        The mapping to validate.
    source : str
        Name of the file or section, for the message.

    Returns
    -------
    pydantic.BaseModel
        The validated ``model_cls`` instance.

    Raises
    ------
    ConfigError
        ``data`` is not a mapping or fails validation.
    """
    require_mapping(data, source)
    try:
        return model_cls.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(f"{source}: {_format_error(exc, data)}") from None


def packaged_config_path(name: str, package: str) -> Path:
    """Path of a config shipped inside the distribution (``configs/`` in the source tree).

    Parameters
    ----------
    name : str
        File name of the config.
    package : str
        The data package of the packaged configs (each product's ``PACKAGED_CONFIGS``),
        looked up with :mod:`importlib.resources`.

    Returns
    -------
    Path
        Its path (which need not exist).
    """
    return Path(str(resources.files(package).joinpath(name)))


def read_yaml(path: str | Path, package: str) -> tuple[object, Path]:
    """Read a YAML config file; returns (data, path).

    A bare name such as ``name`` or ``name.yaml`` that is not a file in the working directory (absent,
    or a folder: a results root holds run folders named like the configs) is looked up among the
    packaged configs; a path (``./name``, ``dir/name.yaml``) is only ever that file.  Duplicate keys
    are rejected.

    Parameters
    ----------
    path : path-like
        The config file or a packaged config's name.
    package : str
        The data package of the packaged configs (:func:`packaged_config_path`).

    Returns
    -------
    data : object
        The parsed YAML.
    path : Path
        The file read.

    Raises
    ------
    ConfigError
        Missing (listing the packaged names, the closest first), unreadable (not a regular file, larger than ``CONFIG_BYTES`` of
        :mod:`acmm_qpp.limits`, not UTF-8) or invalid YAML (with line and column).
    """
    if not str(path).strip():
        raise ConfigError("config path is empty: give a YAML file or the name of a packaged config")
    p = Path(path)
    try:
        present = p.exists()
    except (OSError, ValueError) as exc:   # name too long, NUL byte, ...
        raise ConfigError(f"cannot read config file {str(path)[:200]}: {getattr(exc, 'strerror', None) or exc}") from None
    # a bare name (``name``, not ``./name`` or ``dir/name``: Path drops the ``./``) that is not a
    # file here (absent, or a folder such as a run folder named like it): a packaged config
    bare = len(p.parts) == 1 and not any(sep and sep in str(path) for sep in ("/", os.sep, os.altsep))
    if bare and (not present or p.is_dir()):
        candidate = packaged_config_path(p.name if p.suffix else p.name + ".yaml", package)
        if candidate.exists():
            p, present = candidate, True
    if present and p.is_dir():
        raise ConfigError(f"config path is a directory, not a file: {str(path)[:200]}")
    if not present and p.is_symlink():     # a link to nothing, or a loop of links
        raise ConfigError(f"cannot read config file {str(path)[:200]}: {_link_problem(p)}")
    if not present:               # the packaged names, the closest first
        try:
            names = sorted(Path(q.name).stem for q in resources.files(package).iterdir() if q.name.endswith(".yaml"))
        except (OSError, ModuleNotFoundError):  # pragma: no cover (a broken installation)
            names = []
        msg = f"config file not found: {path}"
        if len(p.parts) == 1 and names:
            best = closest(p.stem, names)
            msg += (f" (not a packaged config either; {f'did you mean `{best}`? ' if best else ''}"
                    f"packaged configs: {', '.join(names)})")
        elif names:
            msg += f" (packaged configs, usable by name: {', '.join(names)})"
        raise ConfigError(msg)
    raw = read_regular_file(p, "config", int(limit("CONFIG_BYTES")), how_to_raise("CONFIG_BYTES"))
    try:
        data = _load_yaml_text(raw.decode("utf-8"), p)
    except UnicodeDecodeError as exc:
        raise ConfigError(f"cannot read config file {p}: not UTF-8 text (byte {exc.start})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        what = getattr(exc, "problem", None) or "not valid YAML"
        raise ConfigError(f"{p}: not valid YAML: {what}{where}") from None
    return data, p


def _link_problem(p: Path) -> str:
    """Why the symbolic link ``p`` leads to no file: a loop, or a target that does not exist."""
    try:
        os.stat(p)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a loop of symbolic links"
        return f"symbolic link to a missing target ({os.readlink(p)[:200]})"
    return "symbolic link to no file"


def _load_yaml_text(text: str, source: object = "config") -> object:
    """YAML ``text`` (a file, or an override's value; ``source`` names it in messages) → Python
    objects, within the bounds of the module docstring (:class:`ConfigError`) and without
    duplicate keys (``yaml.YAMLError``, as for a syntax error)."""
    max_depth, max_nodes = int(limit("YAML_DEPTH")), int(limit("YAML_NODES"))
    stack: list[tuple[str | None, int]] = []
    sizes: dict[str, int] = {}
    open_anchors: set[str] = set()
    count = 0
    for ev in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(ev, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            count += 1
            stack.append((ev.anchor, count))
            if ev.anchor:
                open_anchors.add(ev.anchor)
            if len(stack) > max_depth:
                line = ev.start_mark.line + 1 if ev.start_mark else "?"
                raise ConfigError(f"{source}: YAML nested deeper than {max_depth} levels at line {line} "
                                  f"({how_to_raise('YAML_DEPTH')})")
        elif isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            anchor, start = stack.pop()
            if anchor:
                sizes[anchor] = count - start + 1
                open_anchors.discard(anchor)
        elif isinstance(ev, yaml.ScalarEvent):
            count += 1
            if ev.anchor:
                sizes[ev.anchor] = 1
        elif isinstance(ev, yaml.AliasEvent):
            if ev.anchor in open_anchors:
                raise ConfigError(f"{source}: YAML alias *{ev.anchor} refers to a collection that contains it "
                                  "(a cycle)")
            count += sizes.get(ev.anchor, 1)
        if count > max_nodes:
            raise ConfigError(f"{source}: YAML has more than {max_nodes} values (aliases expanded) "
                              f"({how_to_raise('YAML_NODES')})")
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 (a SafeLoader subclass)
    except TypeError as exc:          # e.g. "unhashable type: 'list'" for ? [a, b]
        raise ConfigError(f"{source}: not valid as a config: a key must be a plain value, not a list or a "
                          f"mapping ({exc})") from None
    except ValueError as exc:         # Python's int-string limit: "Exceeds the limit (4300 digits) ..."
        raise ConfigError(f"{source}: not valid as a config: {str(exc).split(';')[0]}") from None


def read_regular_file(p: Path, what: str = "config", cap: int | None = None,
                      raise_how: str = "") -> bytes:
    """The bytes of ``p``, read with bounds (issue 13): only a regular file (a FIFO, a device
    such as ``/dev/zero`` or a directory is refused without blocking), at most ``cap`` bytes.

    Parameters
    ----------
    p : Path
        The file.
    what : str, optional
        What the file is, for the messages (``"config"``, a journal).
    cap : int, optional
        Largest size accepted, bytes (None: any size a regular file has).
    raise_how : str, optional
        How to raise ``cap``, added to the "too large" message.

    Returns
    -------
    bytes
        Its contents.

    Raises
    ------
    ConfigError
        Not a readable regular file, or larger than ``cap``.
    """
    too_large = f"{what} file {p} is too large: {{}} bytes" + (f" ({raise_how})" if raise_how else "")
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise ConfigError(f"cannot read {what} file {p}: {exc.strerror or exc}") from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise ConfigError(f"{what} path is a directory, not a file: {p}")
        if not stat.S_ISREG(st.st_mode):
            raise ConfigError(f"{what} path is not a regular file (a FIFO, device or socket): {p}")
        if cap is not None and st.st_size > cap:
            raise ConfigError(too_large.format(st.st_size))
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read() if cap is None else f.read(cap + 1)
    except OSError as exc:
        raise ConfigError(f"cannot read {what} file {p}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if cap is not None and len(data) > cap:          # grew while being read
        raise ConfigError(too_large.format(f"over {cap}"))
    return data


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
    if not overrides or not isinstance(data, dict):
        return data                       # (a malformed top level: the loader reports it itself)
    out = copy.deepcopy(data)
    for text in overrides:
        text = str(text)
        if not looks_like_override(text):
            raise OverrideSyntaxError(f"unexpected argument {text!r}: an override must read dotted.key=value "
                                      "or ~dotted.key to remove a key")
        dotted, _, raw = text.partition("=")
        delete = text.startswith("~")
        try:   # the value: YAML, with the bounds of a config file (depth, nodes with aliases expanded)
            value = _load_yaml_text(raw, f"override {dotted}") if raw.strip() else None
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
