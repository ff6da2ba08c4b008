"""Docstring conventions of the public API, enforced (issue 12 item 7; numpydoc's since issue 42).

Every public function, class and method of every module of ``acmm``, ``qpp`` and ``acmm_qpp``
(found by :func:`pkgutil.walk_packages`) passes :func:`numpydoc.validate.validate` on the codes
of :data:`CODES`.  The project's own rules, which numpydoc has no code for, are checked on its
parsed docstring (:mod:`numpydoc.docscrape`): numeric entries of ``Parameters``, ``Returns`` and
``Attributes`` state their unit (:func:`unit_problems`); the exceptions a function raises itself
are listed under ``Raises``; a dataclass documents its fields under ``Attributes`` (a class
without an ``__init__`` of its own need not document its generated constructor); a typer command
has a summary (its ``--help``) and ``help=`` on every parameter instead of a ``Parameters``
section; a module docstring cites the report's equations or chapters (CR-185644) unless listed in
:data:`NO_REPORT_CITATION`; docstrings cite no file outside the repository, and the errata as
``docs/ERRATA.md § <section>`` with a section that exists.  The checker is exercised on faulty
code in :func:`test_checker_reports_each_defect`.
"""
import ast
import dataclasses
import importlib
import importlib.util
import inspect
import pkgutil
import re
import textwrap
import warnings

import pytest
import typer
from numpydoc.docscrape import get_doc_object
from numpydoc.validate import validate
from typer.models import ParameterInfo

from tests.conftest import REPO

#: The packages whose every module is checked (:func:`discover_modules`).
PACKAGES = ["acmm", "qpp", "acmm_qpp"]


def discover_modules() -> list:
    """Every module of :data:`PACKAGES` (the packages themselves included), sorted."""
    names = list(PACKAGES)
    for package in PACKAGES:
        pkg = importlib.import_module(package)
        names += [info.name for info in pkgutil.walk_packages(pkg.__path__, prefix=package + ".")]
    return sorted(names)


#: Modules whose public API is checked.
CHECKED_MODULES = discover_modules()

#: Modules whose docstring need not cite the report's equations, grouped by the reason.
NO_REPORT_CITATION = {module: reason for reason, modules in {
    "the shared base (files, locks, signals, errors, configs, units, figure style): "
    "no mathematics of the report": """acmm_qpp acmm_qpp.config_model
        acmm_qpp.configio acmm_qpp.errors acmm_qpp.limits
        acmm_qpp.outputs acmm_qpp.plot_style acmm_qpp.provenance
        acmm_qpp.results
        acmm_qpp.signals acmm_qpp.units""",
    "config schemas and checks, stage plumbing, numba's compilation: no mathematics of the report":
        """acmm.io.schema acmm.stages.common acmm.stages.pool
        acmm.simulate.warmup acmm.model.compiled_cache""",
    "a package of modules: no mathematics of its own":
        "acmm.io acmm.plots acmm.stages qpp.io acmm.report.sections acmm_qpp.cli",
    "the sweep's machinery (bounds, draws, tasks, executors, journal, output): no mathematics":
        """acmm.sweep.limits acmm.sweep.cases acmm.sweep.journal
        acmm.sweep.output acmm.sweep.run
        acmm.sweep.dask_settings""",
    "the report's machinery (document, figures, task graph, hashes, printed numbers): no mathematics":
        """acmm.report.constants acmm.report.publish acmm.report.context acmm.report.document acmm.report.numbers
        acmm.report.figure_style acmm.report.manifest acmm.report.runner acmm.report.ledger""",
    "command line: parses, calls and prints, no mathematics (the layer rule)": """acmm.cli
        acmm.cli.compile_note acmm.cli.redraw acmm.cli.command acmm.cli.configkinds acmm.cli.app acmm.cli.sweep acmm.cli.report
        acmm.cli.steps
        qpp.cli acmm_qpp.cli.plumbing acmm_qpp.cli.progress""",
}.items() for module in modules.split()}

#: numpydoc's error codes enforced, with what each asks.  Left out: its style codes (GL01-GL03,
#: SS02-SS06, PR05-PR09, RT02-RT05: blank lines, capitals, full stops, one-line summaries, verb
#: forms) and the sections this project does not ask for (ES01 extended summary, SA01 See Also,
#: EX01 Examples, YD01 Yields).
CODES = {
    "GL08": "the object has a docstring",
    "GL06": "sections have numpydoc's names (a misspelt header is reported)",
    "SS01": "the docstring has a summary line",
    "PR01": "every parameter of the signature is documented",
    "PR02": "every documented parameter is in the signature",
    "PR03": "parameters are documented in the signature's order",
    "PR04": "every parameter entry is 'name : type'",
    "PR10": "'name : type' has a space before the colon",
    "RT01": "a function that returns a value has a 'Returns' section",
}
#: What a typer command is held to (typer documents its parameters in ``--help``).
COMMAND_CODES = {"GL08", "GL06", "SS01", "PR02", "PR04", "PR10"}

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
# the checks: numpydoc's validator, then the project's own rules on numpydoc's parsed docstring
# ------------------------------------------------------------------------------------------------
def numpydoc_problems(obj, codes) -> tuple[list, object]:
    """numpydoc's errors of ``codes`` for ``obj``, and its parsed docstring (None if unparsable)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # docscrape warns of unknown sections: GL06
        try:
            doc = get_doc_object(obj, config={"show_class_members": False})
            errors = validate(doc)["errors"]
        except Exception as exc:                # e.g. a section that appears twice
            return [f"numpydoc cannot parse the docstring: {str(exc).splitlines()[0]}"], None
    return [f"{code} {message}" for code, message in errors if code in codes], doc


def unit_problems(doc) -> list:
    """The units rule: numeric entries that state no unit."""
    return [f"{section} entry {entry.name or entry.type!r} states no unit"
            for section in ("Parameters", "Returns", "Attributes") for entry in doc[section]
            if NUMERIC_RE.search(entry.type) and not NON_PHYSICAL_RE.search(entry.type)
            and not UNIT_RE.search(" ".join([entry.type, *entry.desc]))]


def raises_problems(func, doc) -> list:
    """Exception classes the function raises itself (``raise Name(...)``, not in a nested
    function) that ``Raises`` does not list.  ``raise factory(...)`` with a lower-case name calls
    a function that builds the exception, whose class the AST cannot tell: not counted."""
    try:
        node = ast.parse(textwrap.dedent(inspect.getsource(func))).body[0]
    except (OSError, TypeError):
        return []
    raised, stack = set(), list(getattr(node, "body", []))
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        if isinstance(node, ast.Raise) and node.exc is not None:
            exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            raised.add(getattr(exc, "id", getattr(exc, "attr", "")))
        stack += ast.iter_child_nodes(node)
    listed = {name.strip().split(".")[-1] for entry in doc["Raises"]
              for name in (entry.name or entry.type).split(",")}
    return [f"raises {name} but does not list it under 'Raises'"
            for name in sorted(raised - listed) if name[:1].isupper()]


def errata_sections() -> set:
    """Section names of ``docs/ERRATA.md`` (its ``###`` headings)."""
    text = (REPO / ERRATA).read_text(encoding="utf-8")
    return {m.group(1).strip() for m in re.finditer(r"^###\s+(.+)$", text, re.M)}


def citation_problems(doc: str) -> list:
    """Citations outside the repository, malformed ERRATA citations, missing docs files."""
    problems = [f"cites a file outside the repository ({m.group(0)!r}); cite {ERRATA}"
                for m in FORBIDDEN_RE.finditer(doc)]
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


def function_problems(func) -> list:
    """Problems of a function's (or method's) docstring."""
    func = getattr(func, "py_func", func)       # numba dispatchers
    problems, doc = numpydoc_problems(func, CODES)
    if doc is None or not func.__doc__:
        return problems
    return problems + unit_problems(doc) + raises_problems(func, doc) + citation_problems(func.__doc__)


def class_problems(cls) -> list:
    """Problems of a class docstring and of its public methods and properties."""
    generated_init = dataclasses.is_dataclass(cls) or "__init__" not in vars(cls)
    problems, doc = numpydoc_problems(cls, CODES.keys() - ({"PR01", "PR03"} if generated_init else set()))
    if doc is not None and cls.__doc__:
        problems += unit_problems(doc) + citation_problems(cls.__doc__)
        documented = {name.strip() for section in ("Attributes", "Parameters")
                      for entry in doc[section] for name in entry.name.split(",")}
        problems += [f"field {f.name!r} is not documented under 'Attributes'"
                     for f in (dataclasses.fields(cls) if dataclasses.is_dataclass(cls) else ())
                     if f.name not in documented]
    for name, member in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(member, property):        # a property needs a docstring only
            found = numpydoc_problems(member.fget, {"GL08"})[0] + citation_problems(member.fget.__doc__ or "")
        elif isinstance(member, (staticmethod, classmethod)) or inspect.isfunction(member):
            found = function_problems(getattr(member, "__func__", member))
        else:
            continue
        problems += [f"{name}: {p}" for p in found]
    return problems


def typer_commands(module) -> dict:
    """{callback: command name} of every command registered on a typer app of ``module``."""
    return {command.callback: command.name or command.callback.__name__
            for obj in vars(module).values() if isinstance(obj, typer.Typer)
            for command in obj.registered_commands}


def command_problems(func) -> list:
    """Problems of a typer command: :data:`COMMAND_CODES`, and a ``help=`` on every parameter."""
    problems = numpydoc_problems(func, COMMAND_CODES)[0] + citation_problems(func.__doc__ or "")
    for name, p in inspect.signature(func).parameters.items():
        if not isinstance(p.default, ParameterInfo):
            problems.append(f"parameter {name!r} is no typer Option/Argument (so has no --help text)")
        elif not (p.default.help or "").strip():
            problems.append(f"parameter {name!r} has no help= text")
    return problems


def module_problems(module) -> list:
    """Every problem of a module's docstrings, as 'module.object: problem' lines."""
    name, doc, commands = module.__name__, module.__doc__ or "", typer_commands(module)
    problems = [f"{name}: {p}" for p in citation_problems(doc)]
    if not doc.strip():
        problems.append(f"{name}: module has no docstring")
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
    for name in ("acmm.model.tea", "acmm.sweep.run", "acmm.report.sections.errata", "acmm.cli.app",
                 "acmm.cli.configkinds", "acmm_qpp.units", "qpp.model.lure"):
        assert name in CHECKED_MODULES
    assert len(CHECKED_MODULES) >= 100


def test_errata_sections_are_read():
    assert {"Units", "Frames", "Kinematics", "Momentum balance", "TEA", "Linearization",
            "Saturation"} <= errata_sections()


FAULTY = '''"""One defect per rule (cites reference/NOTES.md)."""
import dataclasses
import typer


def no_doc(x):
    return x


def faulty(a, b):
    """Sum, ``docs/ERRATA.md`` § Nonexistent and ``ERRATA.md`` without its folder.

    Parameters
    ----------
    a : float
        A number.
    c : int
        Not in the signature.

    Notez
    -----
    """
    if a:
        raise ValueError(a)
    return a + b


class WrongParameters:
    """Its 'Parameters' name no constructor parameter.

    Parameters
    ----------
    size : int
        Not a parameter.
    """

    def __init__(self, n):
        self.n = n


@dataclasses.dataclass
class Fields:
    """A dataclass with an undocumented field."""

    theta: float


app = typer.Typer()


@app.command()
def helpless(config: str = typer.Argument(..., help="A config."), fast: bool = typer.Option(False), plain=1):
    """A command."""
'''

GOOD = '''"""A module that follows every rule (eq 3.1; ``docs/ERRATA.md`` § Momentum balance)."""
import dataclasses


def torque(omega, *, scale=1.0):
    """Gyroscopic torque, eq 3.2.

    Parameters
    ----------
    omega : (3,) array
        Angular velocity, rad/s.
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
    return scale * omega


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


def _problems(tmp_path, name, source) -> list:
    (tmp_path / f"{name}.py").write_text(source, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, tmp_path / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module_problems(module)


def test_checker_reports_each_defect(tmp_path):
    problems = "\n".join(_problems(tmp_path, "faulty_docs", FAULTY))
    for expected in [
        "faulty_docs: cites a file outside the repository", "faulty_docs: module docstring cites no",
        "no_doc: GL08", "faulty: PR01 Parameters {'b'} not documented",
        "faulty: PR02 Unknown parameters {'c'}", "faulty: RT01 No Returns section found",
        'faulty: GL06 Found unknown section "Notez"', "faulty: Parameters entry 'a' states no unit",
        "faulty: raises ValueError but does not list it", "faulty: '§ Nonexistent",
        "faulty: cite the errata as", "WrongParameters: PR01 Parameters {'n'} not documented",
        "WrongParameters: PR02 Unknown parameters {'size'}",
        "Fields: field 'theta' is not documented under 'Attributes'",
        "helpless: parameter 'fast' has no help= text", "helpless: parameter 'plain' is no typer",
    ]:
        assert expected in problems, f"checker missed: {expected}\n{problems}"


def test_checker_accepts_conforming_code(tmp_path):
    assert _problems(tmp_path, "good_docs", GOOD) == []
