"""The house's structure (issue 31), read from the source: the AST of every module, imports
inside functions included, so that a lazy import cannot hide a dependency.

* no import cycle between the project's modules, counting function-level imports;
* no import from a lower layer into a higher one: ``cli`` → ``report`` → stages (``acmm.stages``,
  ``acmm.sweep``, ``acmm.api``, ``qpp.io.stages``) → cores (``model``, ``design``, ``simulate``,
  ``plots``, ``io``) → the shared base ``acmm_qpp``; ``qpp`` imports nothing of ``acmm``;
* no alias module (a module whose body is only imports), no module ``__getattr__``;
* the installed top-level import names (pyproject's packages list) are this project's own;
* the tests mirror the packages (``tests/acmm/design/test_sector_lqr.py`` tests
  ``acmm/design/sector_lqr.py``), and every test file the documents and sources cite exists.
"""
from __future__ import annotations

import ast
import sys
import tomllib
from pathlib import Path

import pytest

from tests.conftest import REPO

PACKAGES = ("acmm", "qpp", "acmm_qpp")


def _modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the three packages (a package is its ``__init__``)."""
    mods = {}
    for pkg in PACKAGES:
        for path in (REPO / pkg).rglob("*.py"):
            parts = path.relative_to(REPO).with_suffix("").parts
            mods[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return mods


def imported_modules(path: Path, modules: dict[str, Path]) -> set[str]:
    """The project modules ``path`` imports anywhere (module level, functions, ``TYPE_CHECKING``),
    relative imports resolved; ``from p import x`` counts as ``p.x`` when that is a module, else ``p``."""
    parts = path.relative_to(REPO).with_suffix("").parts
    package = ".".join(parts[:-1])
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            targets = [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in modules:
                t = t.rpartition(".")[0]
            if t:
                found.add(t)
    me = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
    found.discard(me)
    return found


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    return {m: imported_modules(p, mods) for m, p in mods.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_reader_sees_lazy_relative_and_type_checking_imports():
    mods = {"qpp.a": None, "qpp.b": None, "acmm_qpp.errors": None, "acmm.x": None}
    probe = REPO / "qpp" / "_layers_probe_tmp.py"
    probe.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import acmm.x\n"
                     "def f():\n    from acmm_qpp.errors import E\n    from . import b\n")
    try:
        names = imported_modules(probe, mods)
    finally:
        probe.unlink()
    assert names == {"acmm.x", "acmm_qpp.errors", "qpp.b"}


def test_cycle_finder_finds_a_function_level_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycle_counting_function_level_imports():
    assert _cycles(_graph()) == []


#: Layer of a module: the longest matching prefix; a module may import modules of its own layer or
#: lower ones only.  Within the cores and the stages the layers are finer (issue 42 item 4): the
#: model is below what designs, simulates and draws with it, the config files (``acmm.io``) above
#: the design settings they hold; the sweep and the API run the stages.
LAYERS = {
    "acmm_qpp": 0,
    "acmm.model": 1,
    "acmm.design": 1.1, "acmm.simulate": 1.1, "acmm.plots": 1.1,
    "acmm.io": 1.2,
    "qpp.model": 1, "qpp.design": 1, "qpp.simulate": 1, "qpp.io": 1, "qpp.plots": 1,
    "acmm.stages": 2, "qpp.io.stages": 2,
    "acmm.sweep": 2.1, "acmm.api": 2.1,
    "acmm.report": 3,
    "acmm.cli": 4, "qpp.cli": 4,
    "acmm": 4, "qpp": 4,            # the packages' own __init__ (docstring, version, constants)
}


def layer(module: str) -> float:
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in LAYERS:
            return LAYERS[".".join(parts[:k])]
    raise KeyError(module)


def test_every_module_has_a_layer():
    assert [m for m in _modules() if not isinstance(layer(m), (int, float))] == []


def upward_imports(graph: dict[str, set[str]]) -> list[str]:
    """The imports of a module of a higher layer by one of a lower layer (the packages' own
    ``__init__``, which holds only the packaged-config names, the work limits and the version, aside)."""
    return [f"{m} (layer {layer(m)}) imports {d} (layer {layer(d)})"
            for m, deps in sorted(graph.items()) for d in sorted(deps)
            if layer(d) > layer(m) and d not in ("acmm", "qpp")]


def test_no_upward_import_between_layers():
    assert upward_imports(_graph()) == []


def test_upward_import_finder_fails_on_the_known_old_ones():
    """The two upward imports issue 42 found (the model's compiled TEA on the simulator's numba
    cache, the stages' redraw on the sweep's figures) are caught, and a downward one is not."""
    assert upward_imports({"acmm.model.tea_compiled": {"acmm.simulate.compiled_cache"},
                           "acmm.stages.runners": {"acmm.sweep.output", "acmm.model.tea"},
                           "acmm.sweep.run": {"acmm.stages.design"}}) == [
        "acmm.model.tea_compiled (layer 1) imports acmm.simulate.compiled_cache (layer 1.1)",
        "acmm.stages.runners (layer 2) imports acmm.sweep.output (layer 2.1)"]


def test_qpp_imports_nothing_of_acmm_and_the_base_neither():
    graph = _graph()
    assert [f"{m} -> {d}" for m, deps in graph.items() if m.split(".")[0] == "qpp"
            for d in deps if d.split(".")[0] == "acmm"] == []
    assert [f"{m} -> {d}" for m, deps in graph.items() if m.split(".")[0] == "acmm_qpp"
            for d in deps if d.split(".")[0] in ("acmm", "qpp")] == []


_CLI_START = "start-up: `--help` imports no numpy, scipy, pydantic: the command imports its stage when it runs"
_MPL = "start-up: matplotlib only where figures are drawn"
#: The only imports allowed inside a function (issue 42 item 4), each deferring the start-up of a
#: heavy or optional dependency, ``(module, imported module) -> reason``; every other import goes
#: at the top of its module.  Each of these carries a ``# deferred: ...`` comment in the source.
LAZY_IMPORTS = {
    ("acmm.cli.app", "acmm.cli.configkinds"): _CLI_START,
    ("acmm.cli.app", "acmm.io.config"): _CLI_START,
    ("acmm.cli.app", "acmm.stages.runners"): _CLI_START,
    ("acmm.cli.app", "acmm.stages.design"): _CLI_START,
    ("acmm.cli.app", "acmm.stages.certify"): _CLI_START,
    ("acmm.cli.app", "acmm.stages.simulate"): _CLI_START,
    ("acmm.cli.app", "acmm.cli.redraw"): _CLI_START,
    ("acmm.cli.app", "acmm.cli.compile_note"): "start-up: numba only when a command simulates",
    ("acmm.cli.report", "acmm.report.build"): _CLI_START,
    ("acmm.cli.sweep", "numpy"): _CLI_START,
    ("acmm.cli.sweep", "acmm.cli.compile_note"): "start-up: numba only when a command simulates",
    ("acmm.cli.sweep", "acmm.sweep.config"): _CLI_START,
    ("acmm.cli.sweep", "acmm.sweep.run"): _CLI_START,
    ("acmm.cli.sweep", "distributed"): "optional dependency (acmm-qpp[dask]), only with --scheduler",
    ("qpp.cli", "qpp.io.config"): _CLI_START,
    ("qpp.cli", "qpp.io.stages"): _CLI_START,
    ("qpp.cli", "acmm_qpp.configio"): "start-up: `--help` imports no pydantic or yaml",
    ("acmm.stages.design_output", "acmm.plots.base"): _MPL,
    ("acmm.stages.design_output", "acmm.plots.design"): _MPL,
    ("acmm.stages.sim_output", "acmm.plots.simulation"): _MPL,
    ("acmm.sweep.output", "acmm.plots.base"): _MPL,
    ("acmm.sweep.output", "matplotlib.ticker"): _MPL,
    ("qpp.plots", "matplotlib.collections"): _MPL,
    ("acmm_qpp.plot_style", "matplotlib"): _MPL,
    ("acmm_qpp.plot_style", "matplotlib.pyplot"): _MPL,
    ("acmm.api", "control"): "start-up: python-control (~1.5 s) only for a StateSpace",
    ("acmm.model.linearize", "control"): "start-up: python-control (~1.5 s) only for a StateSpace",
    ("acmm.design.regional_lmi", "cvxpy"): "start-up: cvxpy (~1 s) only on the reference LMI route",
    ("acmm.design.riccati", "slycot"): "start-up: slycot only for design.riccati_method: slycot",
    ("qpp.model.expression_parser", "sympy"): "start-up: sympy only for an expression nonlinearity",
    ("acmm.sweep.run", "distributed"): "optional dependency (acmm-qpp[dask]), only with --scheduler",
    ("acmm.sweep.run", "distributed.worker"): "optional dependency (acmm-qpp[dask]), only in a Dask worker",
    ("acmm_qpp.errors", "numpy"): "the CLI sets its BLAS thread defaults before numpy is first imported",
    ("acmm_qpp.units", "pint"): "start-up: pint (~0.3 s) only when a unit is converted",
    ("acmm_qpp.cli.progress", "rich.console"): "start-up: rich only on a terminal",
    ("acmm.cli.steps", "rich.progress"): "start-up: rich only on a terminal",
    ("acmm_qpp.cli.plumbing", "importlib.metadata"): "start-up: the distribution's metadata for --version only",
}
#: At most this many import statements inside functions in the three packages.
MAX_LAZY_IMPORTS = 60


def function_imports(source: str, modules=None) -> list[tuple[str, int, bool]]:
    """The imports a module's source makes inside a function: ``(imported module, line, marked)``
    per statement, ``from p import x`` counting as ``p.x`` when that is one of ``modules`` (a
    project module), else as ``p``; ``marked``: the statement carries a ``# deferred:`` comment."""
    modules = modules or {}
    lines = source.splitlines()
    found, seen = [], set()
    for fn in ast.walk(ast.parse(source)):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                if not isinstance(node, (ast.Import, ast.ImportFrom)) or id(node) in seen:
                    continue
                seen.add(id(node))
                marked = "# deferred:" in "\n".join(lines[node.lineno - 1:node.end_lineno])
                if isinstance(node, ast.Import):
                    found += [(a.name, node.lineno, marked) for a in node.names]
                else:
                    base = ("." * node.level) + (node.module or "")
                    subs = sorted({f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in modules})
                    found += [(t, node.lineno, marked) for t in (subs or [base])]
    return found


def lazy_import_problems(module: str, source: str, modules=None, allowed=None) -> list[str]:
    """Imports inside functions that are not on the allow-list (:data:`LAZY_IMPORTS`) or do not
    say why they are deferred."""
    allowed = LAZY_IMPORTS if allowed is None else allowed
    out = []
    for target, line, marked in function_imports(source, modules):
        if (module, target) not in allowed:
            out.append(f"{module}:{line} imports {target} inside a function")
        elif not marked:
            out.append(f"{module}:{line} defers {target} without a `# deferred: <why>` comment")
    return out


def test_imports_are_at_the_top_but_for_a_short_list_of_deferred_heavy_ones():
    mods = _modules()
    bad, used, count = [], set(), 0
    for m, path in sorted(mods.items()):
        source = path.read_text(encoding="utf-8")
        bad += lazy_import_problems(m, source, mods)
        found = function_imports(source, mods)
        used |= {(m, t) for t, _, _ in found}
        count += len({line for _, line, _ in found})
    assert bad == []
    assert sorted(set(LAZY_IMPORTS) - used) == []          # no stale entry keeps the list long
    assert count <= MAX_LAZY_IMPORTS, count


def test_the_function_import_check_fails_on_an_unlisted_or_unmarked_import():
    source = ("import os\n\ndef f():\n    import numpy\n    from . import errors\n"
              "    from acmm_qpp.units import x\n    import pint  # deferred: pint start-up\n"
              "    import cycler\n")
    found = function_imports(source, {"acmm_qpp.errors": None})
    assert [(t, line) for t, line, _ in found] == [("numpy", 4), (".", 5), ("acmm_qpp.units", 6),
                                                   ("pint", 7), ("cycler", 8)]
    allowed = {("m", "pint"): "start-up", ("m", "cycler"): "start-up"}
    assert lazy_import_problems("m", source, allowed=allowed) == [
        "m:4 imports numpy inside a function", "m:5 imports . inside a function",
        "m:6 imports acmm_qpp.units inside a function",
        "m:8 defers cycler without a `# deferred: <why>` comment"]
    assert lazy_import_problems("m", "import numpy\n\ndef f():\n    return numpy.pi\n", allowed={}) == []


def private_imports(source: str) -> list[str]:
    """``from <project module> import _name`` in a module's source, relative imports included
    (dunder names such as ``__version__`` are not private)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").split(".")[0] in PACKAGES):
            out += [f"{'.' * node.level}{node.module or ''}.{a.name}" for a in node.names
                    if a.name.startswith("_") and not (a.name.startswith("__") and a.name.endswith("__"))]
    return out


def test_no_private_name_is_imported_by_another_module():
    """A name a module keeps private stays in it: what another module needs is public."""
    bad = [f"{m} imports {name}" for m, path in sorted(_modules().items())
           for name in private_imports(path.read_text(encoding="utf-8"))]
    assert bad == []


def test_the_private_import_check_fails_on_one():
    source = ("from acmm.plots.base import _save, state_units\nfrom .kernel import _rhs\n"
              "from acmm import __version__\nfrom numpy import _NoValue\n\n"
              "def f():\n    from qpp.io.config_fields import _Model\n")
    assert private_imports(source) == ["acmm.plots.base._save", ".kernel._rhs", "qpp.io.config_fields._Model"]


def registry_fills(source: str) -> list[str]:
    """Module-level statements that fill a container imported from another project module
    (``BUILDERS.update(...)``, ``REGISTRY[key] = ...``, ``HOOKS.append(...)``): a registry that
    one module keeps and others fill at import, so that what a module holds depends on what else
    was imported."""
    tree = ast.parse(source)
    imported = {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom)
                and (n.level or (n.module or "").split(".")[0] in PACKAGES) for a in n.names}
    out = []
    for n in tree.body:
        if isinstance(n, ast.Expr) and isinstance(n.value, ast.Call) and isinstance(n.value.func, ast.Attribute):
            f = n.value.func
            if isinstance(f.value, ast.Name) and f.value.id in imported and f.attr in (
                    "update", "append", "extend", "add", "setdefault", "insert"):
                out.append(f"{f.value.id}.{f.attr}(...)")
        targets = n.targets if isinstance(n, ast.Assign) else [n.target] if isinstance(n, ast.AugAssign) else []
        for t in targets:
            if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) and t.value.id in imported:
                out.append(f"{t.value.id}[...] =")
    return out


def test_no_module_fills_another_modules_registry_at_import():
    assert [f"{m}: {r}" for m, path in sorted(_modules().items())
            for r in registry_fills(path.read_text(encoding="utf-8"))] == []


def test_the_registry_check_fails_on_one():
    source = ("from acmm.plots.base import BUILDERS, HOOKS, TABLE\nfrom numpy import x\nimport acmm\n\n"
              "BUILDERS.update({'a': 1})\nHOOKS.append(print)\nTABLE['k'] = 2\nx.update(1)\nlocal = {}\n"
              "local.update(a=1)\n\ndef f():\n    BUILDERS.update({})\n")
    assert registry_fills(source) == ["BUILDERS.update(...)", "HOOKS.append(...)", "TABLE[...] ="]


def _is_alias(tree: ast.Module) -> bool:
    """A module whose body (docstring aside) is only imports and ``sys.modules`` / ``globals()``
    rebinding: it defines nothing of its own."""
    body = [n for n in tree.body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
    if not body:
        return False                      # a docstring-only package face is no alias
    for n in body:
        if isinstance(n, (ast.Import, ast.ImportFrom)):
            continue
        src = ast.unparse(n)
        if "sys.modules" in src or "globals()" in src or src.startswith("__all__"):
            continue
        return False
    return True


def test_no_alias_module_and_no_module_getattr():
    aliases, getattrs = [], []
    for m, path in _modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        if _is_alias(tree):
            aliases.append(m)
        if any(isinstance(n, ast.FunctionDef) and n.name in ("__getattr__", "__dir__") for n in tree.body):
            getattrs.append(m)
    assert aliases == [] and getattrs == []


def test_alias_detector():
    assert _is_alias(ast.parse('"""Moved."""\nimport sys\nimport x as _m\nsys.modules[__name__] = _m\n'))
    assert _is_alias(ast.parse("from x import *  # noqa\n"))
    assert not _is_alias(ast.parse('"""A package."""\n'))
    assert not _is_alias(ast.parse("import numpy as np\n\ndef f():\n    return np.pi\n"))


def test_no_star_import_and_no_reexport_noqa():
    bad = []
    for m, path in _modules().items():
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if "import *" in line or "re-export" in line and "noqa" in line:
                bad.append(f"{m}:{k}: {line.strip()}")
    assert bad == []


def test_installed_top_level_names_are_the_projects_own():
    cfg = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]
    tops = {p.split(".")[0] for p in cfg["packages"]}
    assert tops == set(PACKAGES)
    listed = set(cfg["packages"])
    on_disk = {m for m, p in _modules().items() if p.name == "__init__.py"}
    assert on_disk <= listed, sorted(on_disk - listed)
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["scripts"]
    assert {v.split(":")[0].split(".")[0] for v in scripts.values()} <= set(PACKAGES)


def test_importing_every_qpp_module_loads_no_acmm_module():
    """At run time too: importing all of qpp and the base in a fresh interpreter loads no acmm."""
    import os
    import subprocess
    import sys

    mods = sorted(m for m in _modules() if m.split(".")[0] in ("qpp", "acmm_qpp"))
    code = ("import importlib, sys\n"
            f"for m in {mods!r}: importlib.import_module(m)\n"
            "print(sorted(m for m in sys.modules if m == 'acmm' or m.startswith('acmm.')))\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                         timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_sources_cite_no_file_outside_the_repository():
    """Docstrings and comments cite ``docs/ERRATA.md § <section>``, never NOTES.md or a path
    outside the repository."""
    import re

    forbidden = re.compile(r"NOTES\.md|NOTES\b|shared/reference|/work/")
    bad = []
    for package in PACKAGES + ("scripts", "tests"):
        for path in sorted((REPO / package).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if rel in ("tests/test_docstrings.py", "tests/test_layers.py"):
                continue
            for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if forbidden.search(line):
                    bad.append(f"{rel}:{k}: {line.strip()}")
    assert bad == []


#: The guide's page that holds the module map (the tables of modules and their equations).
MODULE_MAP = REPO / "docs" / "architecture.md"


def _readme_module_rows() -> list[str]:
    """The rows of the module tables of the guide's module map (``| `path` | content | … |``)."""
    return [line for line in MODULE_MAP.read_text(encoding="utf-8").splitlines()
            if line.startswith("| `") and ("acmm" in line or "qpp" in line)]


def test_the_readme_module_map_names_every_module_and_no_missing_one():
    """The guide's module map (docs/architecture.md) matches the tree: every module file it names exists, and every
    module of the three packages is named, by its path or, in a row naming its folder
    (``acmm/sweep/``), by its module name."""
    import re

    rows = _readme_module_rows()
    text = "\n".join(rows)
    named = set(re.findall(r"`((?:acmm|qpp|acmm_qpp)/[\w/]+\.py)`", text))
    assert sorted(p for p in named if not (REPO / p).is_file()) == []
    missing = []
    for path in _modules().values():
        rel = path.relative_to(REPO).as_posix()
        if path.name == "__init__.py" or rel in named:
            continue
        folder = rel.rsplit("/", 1)[0] + "/"
        in_folder_rows = [r for r in rows if f"`{folder}`" in r or f"`{folder}" in r.split("|")[1]]
        parent = folder.rstrip("/").rsplit("/", 1)
        star = [r for r in rows if len(parent) == 2 and f"`{parent[1]}/*`" in r and f"`{parent[0]}/`" in r]
        if not any(f"`{path.stem}`" in r or f"`{path.name}`" in r for r in in_folder_rows) and not star:
            missing.append(rel)
    assert missing == []


def test_the_readme_module_map_check_fails_on_a_missing_or_unknown_module(tmp_path, monkeypatch):
    rows = _readme_module_rows()
    monkeypatch.setattr(sys.modules[__name__], "_readme_module_rows",
                        lambda: [r.replace("`acmm/design/sector_lqr.py`", "`acmm/design/lqr.py`") for r in rows])
    with pytest.raises(AssertionError):
        test_the_readme_module_map_names_every_module_and_no_missing_one()


#: The test folders that mirror a package; a file directly in ``tests/`` is about the project as a
#: whole (the layers, the lock, the docstrings, the README's numbers, the adversarial suites, ...).
MIRRORED = PACKAGES
#: Test-support modules that mirror no module on purpose (not collected: no test_ prefix): the
#: independent verifier of the qpp certificate must not be named after the code it checks.
TEST_HELPERS = ("tests/qpp/independent_verifier.py",)


def _misnamed_test_files(files: list[str]) -> list[str]:
    """The test files (paths relative to the repository) that do not mirror a module: under
    ``tests/<package>/<folder>/`` only ``__init__.py``, ``conftest.py`` and ``test_<module>.py``
    for a module ``<package>/<folder>/<module>.py``; in ``tests/`` itself no other folder."""
    bad = []
    for rel in files:
        parts = rel.split("/")
        if parts[0] != "tests" or len(parts) == 2:
            continue                              # tests/test_layers.py etc.: about the project
        folder, name = "/".join(parts[1:-1]), parts[-1]
        if parts[1] not in MIRRORED or not (REPO / folder).is_dir():
            bad.append(f"{rel}: tests/{folder} mirrors no package folder")
        elif name in ("__init__.py", "conftest.py") or rel in TEST_HELPERS:
            continue
        elif not name.startswith("test_"):
            bad.append(f"{rel}: not test_<module>.py")
        elif not (REPO / folder / name[5:]).is_file():
            bad.append(f"{rel}: no module {folder}/{name[5:]} of that name")
    return bad


def test_test_files_mirror_the_modules_and_every_cited_test_file_exists():
    """tests/acmm/design/test_sector_lqr.py tests acmm/design/sector_lqr.py (python-control's
    layout): every file under tests/acmm, tests/qpp and tests/acmm_qpp is named after a module of
    the package folder it mirrors; the test files the README, every page of docs/ (docs/ERRATA.md
    included), the sources, the scripts, the Makefile and the tests themselves cite exist (a moved
    test leaves no stale path)."""
    import re

    files = sorted(p.relative_to(REPO).as_posix() for p in (REPO / "tests").rglob("*.py")
                   if "__pycache__" not in p.parts)
    assert len(files) > 100 and _misnamed_test_files(files) == []
    assert _misnamed_test_files(["tests/acmm/design/test_lqr.py", "tests/acmm/desing/test_riccati.py",
                                 "tests/qpp/test_qpp_core.py", "tests/acmm/design/helpers.py",
                                 "tests/acmm/design/test_riccati.py", "tests/test_whole_project.py"]) == [
        "tests/acmm/design/test_lqr.py: no module acmm/design/lqr.py of that name",
        "tests/acmm/desing/test_riccati.py: tests/acmm/desing mirrors no package folder",
        "tests/qpp/test_qpp_core.py: no module qpp/qpp_core.py of that name",
        "tests/acmm/design/helpers.py: not test_<module>.py"]
    citing = [REPO / "README.md", REPO / "Makefile"] + sorted((REPO / "docs").rglob("*.md"))
    assert REPO / "docs" / "ERRATA.md" in citing
    for folder in PACKAGES + ("scripts", "tests"):
        citing += sorted(p for p in (REPO / folder).rglob("*.py") if p.name != "test_layers.py")   # (examples above)
    cited = {(path.relative_to(REPO).as_posix(), m) for path in citing
             for m in re.findall(r"\btests/(?:\w+/)*test_\w+\.py", path.read_text(encoding="utf-8"))}
    assert len(cited) > 30
    assert sorted(f"{src} cites {m}" for src, m in cited if not (REPO / m).is_file()) == []
