"""Docstring conventions of the public API, enforced (issue 12, item 7).

In the style of python-control's ``control/tests/docstrings_test.py``: every public function,
class and method (name not starting with ``_``) of every module of the packages ``acmm``,
``qpp`` and ``acmm_qpp`` -- found by
:func:`pkgutil.walk_packages`, so a new module is checked from the moment it exists -- has a
docstring in numpydoc layout; every parameter in its signature is documented in a ``Parameters``
section and every name listed there is a parameter (for a class: a constructor parameter).
Excluded, each with its reason: compatibility shims that only re-export (:data:`SHIMS`, verified
by :func:`test_exclusions_are_justified`).  On top of that, for this project:

* numeric entries (``float``, ``complex``, arrays) of ``Parameters``, ``Returns`` and
  ``Attributes`` state their unit (or say ``dimensionless`` / name the units they follow);
* a function that returns a value has a ``Returns`` section, and every exception class it
  raises itself is listed under ``Raises``;
* a dataclass documents every field under ``Attributes``;
* a typer command of ``cli`` (a function registered on a ``typer.Typer`` app, also from a
  ``register(app)`` function) needs a summary line -- it is the command's ``--help`` text -- and
  a non-empty ``help=`` on every ``typer.Option``/``typer.Argument``: typer documents the
  parameters in ``--help``, so a numpydoc ``Parameters`` section would only repeat it (one that
  is present anyway must name real parameters).  Other public functions of ``cli`` follow the
  numpydoc rules above;
* each module docstring cites the report's equations or chapters (CR-185644);
* docstrings cite no file outside the repository (``NOTES.md``, ``shared/reference``, absolute
  paths); conventions and misprints are cited as ``docs/ERRATA.md § <section>`` with a section
  that exists in that document, and any other ``docs/*.md`` cited must exist.

The numpydoc parser is a small one written here (sections, ``name : type`` entries), so the test
needs no extra dependency.  A module without the report's mathematics is listed, with the
reason, in :data:`NO_REPORT_CITATION`.  The checker is exercised on deliberately faulty code in :func:`test_checker_reports_each_defect`.
"""
from __future__ import annotations

import ast
import dataclasses
import importlib
import importlib.util
import inspect
import pkgutil
import re
import textwrap
from pathlib import Path

import pytest

from tests.conftest import REPO


#: The packages whose every module is checked; their modules are found by
#: :func:`pkgutil.walk_packages` (:func:`discover_modules`), so a new module is checked from the
#: moment it exists.
PACKAGES = ["acmm", "qpp", "acmm_qpp"]

#: Compatibility shims: old import paths that only re-export another module (the code, and so the
#: docstrings, live in the target, which is checked).  :func:`test_exclusions_are_justified`
#: verifies that each one's source holds nothing but a docstring, imports and the re-export.
SHIMS: dict = {}


def discover_modules() -> list:
    """Every module of :data:`PACKAGES` (the packages themselves included), sorted."""
    names = []
    for package in PACKAGES:
        pkg = importlib.import_module(package)
        names.append(package)
        for info in pkgutil.walk_packages(pkg.__path__, prefix=package + "."):
            names.append(info.name)
    return sorted(names)


#: Modules whose public API is checked: every module of :data:`PACKAGES` but the exclusions.
CHECKED_MODULES = [m for m in discover_modules() if m not in SHIMS]

#: Modules whose docstring need not cite the report's equations, with the reason.
NO_REPORT_CITATION = {
    "acmm_qpp.atomic_write": "atomic file writing: no mathematics of the report",
    "acmm_qpp.provenance": "git commit, config hash and creation time of results: no mathematics of the report",
    "acmm_qpp.quantity_fields": "unit conversion of config fields (pydantic validators): no mathematics of the report",
    "acmm_qpp.errors": "exception classes and exit codes: no mathematics of the report",
    "acmm_qpp.schema": "JSON-schema generation of config files: no mathematics of the report",
    "acmm.io.schema": "JSON schemas of config files: no mathematics of the report",
    "qpp.io.schema": "JSON schema of config files: no mathematics of the report",
    "acmm.cli.configkinds": "config-kind dispatch: no mathematics of the report",
    "acmm_qpp.results": "atomic HDF5/text/figure writing and provenance: no mathematics of the report",
    "acmm_qpp.hdf5_lowlevel": "HDF5 datasets and attributes through h5py's low-level API: no mathematics of the report",
    "acmm_qpp.units": "unit conversion of config values and outputs (pint): no mathematics of the report",
    "acmm_qpp.limits": "work and size limits of the programs: no mathematics of the report",
    "acmm_qpp.runlock": "per-run-directory file lock: no mathematics of the report",
    "acmm_qpp.signals": "termination signals unwound like Ctrl-C: no mathematics of the report",
    "acmm_qpp.config_model": "the strict pydantic base of the config sections: no mathematics of the report",
    "acmm_qpp.configio": "bounded YAML reading and pydantic validation of configs: no mathematics of the report",
    "acmm_qpp": "the shared base package: no mathematics of the report",
    "acmm_qpp.cli": "the shared command-line plumbing package: no mathematics of the report",
    "acmm.io": "package of configs, schemas and stage files: no mathematics of its own",
    "acmm.plots": "package of the stage figures: no mathematics of its own",
    "acmm.stages": "package of the stages: no mathematics of its own",
    "qpp.io": "package of the qpp config, schema and stage runners: no mathematics of its own",
    "acmm_qpp.hints": "hints attached to error messages: no mathematics of the report",
    "acmm_qpp.outputs": "which files a stage owns, config.yaml: no mathematics of the report",
    "acmm_qpp.overrides": "command-line key=value overrides: no mathematics of the report",
    "acmm_qpp.pool": "the local process pool and its workers: no mathematics of the report",
    "acmm_qpp.plot_style": "matplotlib style of all figures: no mathematics of the report",
    "acmm.simulate.warmup": "compiling the numba kernels ahead of time: no mathematics of the report",
    "acmm.simulate.compiled_cache": "numba's on-disk cache of the compiled kernels: no mathematics of the report",
    "acmm.sweep.limits": "work bounds of a sweep config: no mathematics of the report",
    "acmm.sweep.cases": "random draws and grid points of a sweep's cases: no mathematics of the report",
    "acmm.sweep.journal": "the sweep's append-only journal file: no mathematics of the report",
    "acmm.sweep.output": "the sweep's HDF5/CSV/figure output: no mathematics of the report",
    "acmm.sweep.run": "the sweep driver (tasks, executor, journal): no mathematics of the report",
    "acmm.stages.common": "config reading and output unit conversion shared by the stages: no mathematics of the report",
    "acmm.sweep.executors": "executors of the sweep's tasks: no mathematics of the report",
    "acmm.sweep.chunking": "chunk sizes of the sweep's tasks: no mathematics of the report",
    "acmm.sweep.dask_settings": "Dask configuration for a sweep cluster: no mathematics of the report",
    "qpp.io.config_checks": "validation of a qpp config's fields and work bounds: no mathematics of the report",
    "acmm.sweep.journal_records": "the fields of a sweep journal's records: no mathematics of the report",
    "acmm.report.constants": "section keys and titles of the report document: no mathematics",
    "acmm.report.publish": "moving a finished report's files into place: no mathematics",
    "acmm.report.context": "what a report section receives and writes: no mathematics",
    "acmm.report.document": "the report's document model and its HTML/Markdown renderers: no mathematics",
    "acmm.report.figure_style": "the report's figure writer: no mathematics",
    "acmm.report.manifest": "dataset hashes and the determinism manifest: no mathematics",
    "acmm.report.sections": "package of the report's sections: no mathematics of its own",
    "acmm.report.sections.determinism": "dataset hashes compared between runs: no mathematics",
    "acmm.report.sections.printed": "the table of every printed number: no mathematics of its own",
    "acmm.report.sections.provenance": "software versions and stage files used: no mathematics",
    "acmm.report.runner": "the report's task graph run serially or on a process pool: no mathematics of the report",
    "acmm.report.ledger": "comparison of printed and computed numbers: no mathematics of the report",
    **{m: "command line: parses, calls and prints, no mathematics (the layer rule)" for m in (
        "acmm.cli", "acmm.cli.compile_note", "acmm.cli.configkinds", "acmm.cli.app", "qpp.cli", "acmm.cli.sweep", "acmm.cli.report", "acmm_qpp.cli.plumbing",
        "acmm_qpp.cli.progress", "acmm_qpp.cli.failures")},
}

#: Section headers numpydoc knows (a misspelt header is reported).
NUMPYDOC_SECTIONS = {
    "Parameters", "Other Parameters", "Returns", "Yields", "Receives", "Raises", "Warns",
    "Warnings", "See Also", "Notes", "References", "Examples", "Attributes", "Methods",
}

#: An entry's type marks it numeric (so it must state a unit).
NUMERIC_RE = re.compile(r"\b(float|complex|array|ndarray)s?\b")
#: ...unless it is an array of integers, booleans or strings (indices, flags, names).
NON_PHYSICAL_RE = re.compile(r"\b(int|bool|str)\s+arrays?\b|\barrays? of (int|bool|str)")
#: What counts as a unit statement.
UNIT_RE = re.compile(
    r"\brad\b|(?<![\w'’])s\b|ft·lbf|slug·ft²|ft\*lbf|slug\*ft|\bkg\b|N·m|\bdeg\b|°|"
    r"[Dd]imensionless|\b[Uu]nits?\b|\borbits\b")
#: A report citation in a module docstring: an equation, a chapter or a table.
REPORT_RE = re.compile(r"\beqs?\.? ?\d+\.\d+|\bch\. ?\d+|\bTable \d+")
#: Citations of files outside the repository.
FORBIDDEN_RE = re.compile(r"NOTES\.md|shared/reference|/work/|reference/")
ERRATA = "docs/ERRATA.md"


# ------------------------------------------------------------------------------------------------
# a small numpydoc reader
# ------------------------------------------------------------------------------------------------
@dataclasses.dataclass
class Entry:
    """One ``name : type`` entry of a numpydoc list section, with its description lines."""

    names: list
    type: str
    desc: list

    @property
    def text(self) -> str:
        return " ".join([self.type] + self.desc)


def parse_sections(doc: str) -> tuple[dict, list]:
    """Split a cleaned docstring into {header: lines}; the text before any header is 'Summary'."""
    lines = inspect.cleandoc(doc).splitlines()
    sections, problems, current = {"Summary": []}, [], "Summary"
    i = 0
    while i < len(lines):
        line = lines[i]
        if (i + 1 < len(lines) and line.strip() and not line.startswith(" ")
                and re.fullmatch(r"-{3,}", lines[i + 1].strip())):
            current = line.strip()
            if current not in NUMPYDOC_SECTIONS:
                problems.append(f"unknown section {current!r}")
            if len(lines[i + 1].strip()) != len(current):
                problems.append(f"underline of section {current!r} has the wrong length")
            if current in sections:
                problems.append(f"section {current!r} appears twice")
            sections[current] = []
            i += 2
            continue
        sections[current].append(line)
        i += 1
    return sections, problems


def parse_entries(lines: list, *, named: bool = True) -> tuple[list, list]:
    """The entries of a list section (Parameters, Returns, Attributes, Raises).

    ``named``: entries are ``name : type`` (Parameters, Attributes); otherwise (Returns, Raises)
    a bare ``type`` line is also an entry.
    """
    entries, problems = [], []
    for line in lines:
        if not line.strip():
            continue
        if line.startswith(" "):
            if not entries:
                problems.append(f"indented text before the first entry: {line.strip()!r}")
                continue
            entries[-1].desc.append(line.strip())
            continue
        head, sep, typ = line.partition(" : ")
        if sep:
            names = [n.strip().lstrip("*") for n in head.split(",")]
            entries.append(Entry(names, typ.strip(), []))
        elif named and not line.rstrip().endswith(":"):
            names = [n.strip().lstrip("*") for n in line.split(",")]
            entries.append(Entry(names, "", []))
            problems.append(f"entry {line.strip()!r} has no ' : type'")
        else:
            entries.append(Entry([], line.strip(), []))
    return entries, problems


# ------------------------------------------------------------------------------------------------
# the checks
# ------------------------------------------------------------------------------------------------
def errata_sections() -> set:
    """Section names of ``docs/ERRATA.md`` (its ``###`` headings)."""
    text = (REPO / ERRATA).read_text(encoding="utf-8")
    return {m.group(1).strip() for m in re.finditer(r"^###\s+(.+)$", text, re.M)}


def citation_problems(doc: str) -> list:
    """Citations outside the repository, malformed ERRATA citations, missing docs files."""
    problems = []
    for m in FORBIDDEN_RE.finditer(doc):
        problems.append(f"cites a file outside the repository ({m.group(0)!r}); cite {ERRATA}")
    flat = " ".join(doc.split())
    for m in re.finditer(r"(\S*)ERRATA\.md`*\s*(§?)", flat):
        if not m.group(1).endswith("docs/") or not m.group(2):
            problems.append(f"cite the errata as '{ERRATA} § <section>', not {m.group(0)!r}")
    known = errata_sections()
    for m in re.finditer(r"§\s*([^§]*)", flat):
        if not any(m.group(1).startswith(name) for name in known):
            problems.append(f"'§ {m.group(1)[:30]}' is no section of {ERRATA}")
    for m in re.finditer(r"\bdocs/[\w./-]+\.md", flat):
        if not (REPO / m.group(0)).is_file():
            problems.append(f"cites {m.group(0)}, which is not in the repository")
    return problems


def unit_problems(entries: list, section: str) -> list:
    """Numeric entries that state no unit."""
    return [f"{section} entry {', '.join(e.names) or e.type!r} states no unit"
            for e in entries if NUMERIC_RE.search(e.type) and not NON_PHYSICAL_RE.search(e.type)
            and not UNIT_RE.search(e.text)]


def _own_nodes(func_node):
    """AST nodes of a function body, not descending into nested functions or classes."""
    stack = [n for n in func_node.body
             if not isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda,
                                      ast.ClassDef)):
                stack.append(child)


def _function_ast(func):
    """The ``FunctionDef`` node of a function (None when its source is not available)."""
    try:
        source = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return None
    node = ast.parse(source).body[0]
    return node if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) else None


def returns_value(func) -> bool:
    """Does the function (not a nested one) ``return`` something other than None?"""
    node = _function_ast(func)
    if node is None:
        return False
    return any(isinstance(n, ast.Return) and n.value is not None
               and not (isinstance(n.value, ast.Constant) and n.value.value is None)
               for n in _own_nodes(node))


def raised_names(func) -> set:
    """Names of the exception classes the function raises itself (``raise Name(...)``).

    ``raise factory(...)`` with a lower-case name calls a function that builds the exception
    (e.g. :func:`acmm_qpp.results.output_error`), whose class the AST cannot tell: not counted.
    """
    node = _function_ast(func)
    out = set()
    for n in (_own_nodes(node) if node is not None else ()):
        if isinstance(n, ast.Raise) and n.exc is not None:
            exc = n.exc.func if isinstance(n.exc, ast.Call) else n.exc
            if isinstance(exc, ast.Name):
                out.add(exc.id)
            elif isinstance(exc, ast.Attribute):
                out.add(exc.attr)
    return {name for name in out if not name[:1].islower()}


def function_problems(func, *, method: bool = False) -> list:
    """Problems of one function's (or method's) docstring."""
    func = getattr(func, "py_func", func)   # numba dispatchers
    doc = func.__doc__
    if not doc or not doc.strip():
        return ["has no docstring"]
    sections, problems = parse_sections(doc)
    if not "".join(sections["Summary"]).strip():
        problems.append("has no summary line")
    problems += citation_problems(doc)

    params = [p for name, p in inspect.signature(func).parameters.items()
              if not (method and name in ("self", "cls"))]
    entries, probs = parse_entries(sections.get("Parameters", []))
    problems += probs + unit_problems(entries, "Parameters")
    documented = {name for e in entries for name in e.names}
    if params and "Parameters" not in sections:
        problems.append("has parameters but no 'Parameters' section")
    for p in params:
        if p.name not in documented:
            problems.append(f"parameter {p.name!r} is not documented")
    for name in sorted(documented - {p.name for p in params}):
        problems.append(f"documents {name!r}, which is not in the signature")

    if returns_value(func):
        if "Returns" not in sections and "Yields" not in sections:
            problems.append("returns a value but has no 'Returns' section")
    entries, probs = parse_entries(sections.get("Returns", []), named=False)
    problems += probs + unit_problems(entries, "Returns")

    raises, _ = parse_entries(sections.get("Raises", []), named=False)
    listed = {name.strip().split(".")[-1] for e in raises for name in e.type.split(",")}
    for name in sorted(raised_names(func) - listed):
        problems.append(f"raises {name} but does not list it under 'Raises'")
    return problems


def class_problems(cls) -> list:
    """Problems of a class docstring and of its public methods and properties."""
    doc = cls.__doc__
    if not doc or not doc.strip():
        return ["has no docstring"]
    sections, problems = parse_sections(doc)
    problems += citation_problems(doc)
    if issubclass(cls, BaseException):
        return problems
    attrs, probs = parse_entries(sections.get("Attributes", []))
    params, probs2 = parse_entries(sections.get("Parameters", []))
    problems += probs + probs2 + unit_problems(attrs, "Attributes") + unit_problems(params, "Parameters")
    documented = {name for e in attrs + params for name in e.names}
    if dataclasses.is_dataclass(cls):
        for f in dataclasses.fields(cls):
            if f.name not in documented:
                problems.append(f"field {f.name!r} is not documented under 'Attributes'")
    elif "__init__" in vars(cls):
        for name in list(inspect.signature(cls.__init__).parameters)[1:]:
            if name not in documented:
                problems.append(f"constructor parameter {name!r} is not documented")
    if params:      # what 'Parameters' lists must be a constructor parameter (python-control)
        try:
            accepted = set(inspect.signature(cls).parameters)
        except (TypeError, ValueError):
            accepted = set()
        for name in sorted({n for e in params for n in e.names} - accepted):
            problems.append(f"documents {name!r} under 'Parameters', which is no constructor parameter")
    for name, member in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(member, property):
            if not member.fget.__doc__ or not member.fget.__doc__.strip():
                problems.append(f"property {name!r} has no docstring")
            else:
                problems += [f"property {name!r}: {p}" for p in citation_problems(member.fget.__doc__)]
        elif isinstance(member, (staticmethod, classmethod)):
            problems += [f"{name}: {p}" for p in function_problems(member.__func__, method=True)]
        elif inspect.isfunction(member):
            problems += [f"{name}: {p}" for p in function_problems(member, method=True)]
    return problems


def typer_commands(module) -> dict:
    """{callback: command name} of every command registered on a typer app of ``module``."""
    import typer

    out = {}
    for obj in vars(module).values():
        if isinstance(obj, typer.Typer):
            for command in obj.registered_commands:
                out[command.callback] = command.name or command.callback.__name__
    return out


def command_problems(func) -> list:
    """Problems of a typer command function (the ``cli`` apps' commands).

    A command's docstring is its ``--help`` text and its parameters are documented by typer: each
    is a ``typer.Option``/``typer.Argument`` whose ``help=`` is printed by ``--help``.  So a
    command needs a summary line and a non-empty ``help=`` on every parameter, not a numpydoc
    ``Parameters`` section (which would repeat ``--help``); if it has one anyway, it is checked
    against the signature like any other.
    """
    from typer.models import ParameterInfo

    doc = func.__doc__
    if not doc or not doc.strip():
        return ["has no docstring (its summary is the command's --help text)"]
    sections, problems = parse_sections(doc)
    if not "".join(sections["Summary"]).strip():
        problems.append("has no summary line")
    problems += citation_problems(doc)
    params = inspect.signature(func).parameters
    for name, p in params.items():
        if not isinstance(p.default, ParameterInfo):
            problems.append(f"parameter {name!r} is no typer Option/Argument (so has no --help text)")
        elif not (p.default.help or "").strip():
            problems.append(f"parameter {name!r} has no help= text")
    if "Parameters" in sections:
        entries, probs = parse_entries(sections["Parameters"])
        problems += probs
        for doc_name in sorted({n for e in entries for n in e.names} - set(params)):
            problems.append(f"documents {doc_name!r}, which is not in the signature")
    return problems


def module_problems(module) -> list:
    """Every problem of a module's docstrings, as 'module.object: problem' lines.

    Functions registered as typer commands on an app of the module are checked by
    :func:`command_problems` (also those defined inside a ``register(app)`` function elsewhere);
    every other public function, class and method by :func:`function_problems` /
    :func:`class_problems`.
    """
    name = module.__name__
    problems = []
    commands = typer_commands(module)
    doc = module.__doc__ or ""
    if not doc.strip():
        problems.append(f"{name}: module has no docstring")
    problems += [f"{name}: {p}" for p in citation_problems(doc)]
    if name not in NO_REPORT_CITATION and not REPORT_RE.search(doc):
        problems.append(f"{name}: module docstring cites no equation or chapter of the report")
    for attr, obj in vars(module).items():
        if attr.startswith("_") or getattr(obj, "__module__", None) != name:
            continue
        if inspect.isclass(obj):
            found = class_problems(obj)
        elif obj in commands:
            found = command_problems(obj)
        elif inspect.isfunction(obj) or inspect.isfunction(getattr(obj, "py_func", None)):
            found = function_problems(obj)
        else:
            continue
        problems += [f"{name}.{attr}: {p}" for p in found]
    for callback, command in commands.items():
        if vars(module).get(callback.__name__) is not callback:     # registered from elsewhere
            problems += [f"{name}: command {command!r}: {p}" for p in command_problems(callback)]
    return problems


# ------------------------------------------------------------------------------------------------
# tests
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("module_name", CHECKED_MODULES)
def test_docstrings(module_name):
    problems = module_problems(importlib.import_module(module_name))
    assert not problems, f"{len(problems)} docstring problem(s):\n" + "\n".join(problems)


def test_every_module_is_found():
    """Discovery reaches into subpackages, and the known modules are among those checked."""
    found = discover_modules()
    for name in ("acmm.model.tea", "acmm.sweep.run", "acmm.report.sections.errata", "acmm.cli.app",
                 "acmm.cli.configkinds", "acmm_qpp.units", "qpp.model.lure"):
        assert name in found
    assert len(found) >= 100


def _only_reexports(path: Path) -> bool:
    """Does a module's source hold nothing but its docstring, imports and a re-export
    (``sys.modules[__name__] = ...`` or ``globals().update(...)``)?"""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            continue                                                     # the docstring
        if isinstance(node, ast.Assign) and ast.unparse(node.targets[0]) == "sys.modules[__name__]":
            continue
        if (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)
                and ast.unparse(node.value.func) == "globals().update"):
            continue
        return False
    return True


def test_exclusions_are_justified():
    """Each shim only re-exports a module that is itself checked."""
    found = set(discover_modules())
    for shim, target in SHIMS.items():
        assert shim in found, f"{shim} no longer exists: drop it from SHIMS"
        parent, _, leaf = shim.rpartition(".")     # not find_spec: some shims replace themselves
        path = Path(importlib.import_module(parent).__path__[0]) / f"{leaf}.py"   # in sys.modules
        assert _only_reexports(path), f"{shim} defines code of its own: check it, it is no shim"
        assert target in CHECKED_MODULES, target


def test_errata_sections_are_read():
    names = errata_sections()
    assert {"Units", "Frames", "Kinematics", "Momentum balance", "TEA", "Linearization",
            "Saturation"} <= names


FAULTY = '''
"""A module with one faulty object per rule (cites reference/NOTES.md)."""


def no_doc(x):
    return x


def undocumented_param(a, b):
    """Sum.

    Parameters
    ----------
    a : float
        First, rad.
    c : float
        Not in the signature, rad.

    Returns
    -------
    float
        Sum, rad.
    """
    return a + b


def no_returns(a):
    """Twice.

    Parameters
    ----------
    a : float
        Value, rad.
    """
    return 2 * a


def no_unit(a):
    """Nothing.

    Parameters
    ----------
    a : float
        A number.
    """


def unlisted_raise(a):
    """Check ``docs/ERRATA.md`` § Nonexistent and ``docs/ERRATA.md`` without section.

    Parameters
    ----------
    a : int
        Anything.

    Raises
    ------
    KeyError
        Never.
    """
    if a:
        raise ValueError("a")


def misspelt(a):
    """Misspelt header.

    Parameter
    ---------
    a : int
        Anything.
    """


class Undocumented:
    pass


class WrongParameters:
    """A class whose 'Parameters' name no constructor parameter.

    Parameters
    ----------
    size : int
        Not a parameter.
    """

    def __init__(self, n):
        self.n = n


import typer  # noqa: E402

app = typer.Typer()


@app.command()
def helpless(config: str = typer.Argument(..., help="a config"),
             fast: bool = typer.Option(False, "--fast"), plain=1):
    """A command."""
'''

GOOD = '''
"""A module that follows every rule (eq 3.1; ``docs/ERRATA.md`` § Momentum balance)."""
import dataclasses


def torque(omega, inertia, *, scale=1.0):
    """Gyroscopic torque, eq 3.2.

    Parameters
    ----------
    omega : (3,) array
        Angular velocity, rad/s.
    inertia : (3, 3) array
        Inertia, slug·ft².
    scale : float, optional
        Dimensionless factor.

    Returns
    -------
    (3,) array
        Torque, ft·lbf.

    Raises
    ------
    ValueError
        When ``scale`` is negative.
    """
    if scale < 0:
        raise ValueError("scale")
    return scale * omega @ inertia


@dataclasses.dataclass
class Point:
    """A point.

    Attributes
    ----------
    theta : (3,) array
        Attitude, rad.
    """

    theta: object

    @property
    def theta_deg(self):
        """Attitude in degrees."""
        return self.theta
'''


def _load(tmp_path, name, source):
    path = tmp_path / f"{name}.py"
    path.write_text(source, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_checker_reports_each_defect(tmp_path):
    problems = "\n".join(module_problems(_load(tmp_path, "faulty_docs", FAULTY)))
    for expected in [
        "faulty_docs: cites a file outside the repository",
        "faulty_docs: module docstring cites no equation",
        "no_doc: has no docstring",
        "undocumented_param: parameter 'b' is not documented",
        "undocumented_param: documents 'c', which is not in the signature",
        "no_returns: returns a value but has no 'Returns' section",
        "no_unit: Parameters entry 'a' states no unit",
        "unlisted_raise: raises ValueError but does not list it",
        "unlisted_raise: '§ Nonexistent",
        "unlisted_raise: cite the errata as",
        "misspelt: unknown section 'Parameter'",
        "misspelt: has parameters but no 'Parameters' section",
        "Undocumented: has no docstring",
        "WrongParameters: constructor parameter 'n' is not documented",
        "WrongParameters: documents 'size' under 'Parameters', which is no constructor parameter",
        "helpless: parameter 'fast' has no help= text",
        "helpless: parameter 'plain' is no typer Option/Argument",
    ]:
        assert expected in problems, f"checker missed: {expected}\n{problems}"


def test_checker_accepts_conforming_code(tmp_path):
    assert module_problems(_load(tmp_path, "good_docs", GOOD)) == []
