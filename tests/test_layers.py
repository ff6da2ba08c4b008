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


#: Layer of a module: the longest matching prefix; higher numbers may import lower ones only.
LAYERS = {
    "acmm_qpp": 0,
    "acmm.model": 1, "acmm.design": 1, "acmm.simulate": 1, "acmm.plots": 1, "acmm.io": 1,
    "qpp.model": 1, "qpp.design": 1, "qpp.simulate": 1, "qpp.io": 1, "qpp.plots": 1,
    "acmm.stages": 2, "acmm.sweep": 2, "acmm.api": 2, "qpp.io.stages": 2,
    "acmm.report": 3,
    "acmm.cli": 4, "qpp.cli": 4,
    "acmm": 4, "qpp": 4,            # the packages' own __init__ (docstring and version)
}


def layer(module: str) -> int:
    parts = module.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in LAYERS:
            return LAYERS[".".join(parts[:k])]
    raise KeyError(module)


def test_every_module_has_a_layer():
    assert [m for m in _modules() if not isinstance(layer(m), int)] == []


def test_no_upward_import_between_layers():
    bad = [f"{m} (layer {layer(m)}) imports {d} (layer {layer(d)})"
           for m, deps in sorted(_graph().items()) for d in sorted(deps)
           if layer(d) > layer(m) and d not in ("acmm", "qpp")]
    assert bad == []


def test_qpp_imports_nothing_of_acmm_and_the_base_neither():
    graph = _graph()
    assert [f"{m} -> {d}" for m, deps in graph.items() if m.split(".")[0] == "qpp"
            for d in deps if d.split(".")[0] == "acmm"] == []
    assert [f"{m} -> {d}" for m, deps in graph.items() if m.split(".")[0] == "acmm_qpp"
            for d in deps if d.split(".")[0] in ("acmm", "qpp")] == []


#: The imports the shared base may make inside a function, each for a reason of start-up time or
#: import order (issue 42 item 4); any other import of ``acmm_qpp`` goes at the top of its module.
#: The product packages are not held to this yet (their function-level imports remain to be moved).
BASE_LAZY_IMPORTS = {
    ("acmm_qpp.errors", "numpy"): "the CLI sets its BLAS thread defaults before numpy is first imported",
    ("acmm_qpp.units", "pint"): "start-up: pint (~0.3 s) only when a unit is converted",
    ("acmm_qpp.plot_style", "matplotlib"): "start-up: matplotlib only when a figure is drawn",
    ("acmm_qpp.plot_style", "matplotlib.pyplot"): "start-up: matplotlib only when a figure is drawn",
    ("acmm_qpp.plot_style", "cycler"): "start-up: matplotlib's cycler with matplotlib",
    ("acmm_qpp.cli.progress", "rich.console"): "start-up: rich only on a terminal",
    ("acmm_qpp.cli.progress", "rich.progress"): "start-up: rich only on a terminal",
    ("acmm_qpp.cli.plumbing", "acmm_qpp.hints"): "start-up: the hints bring pydantic, which `--help` needs not",
    ("acmm_qpp.cli.plumbing", "typer._click"): "typer's vendored click, else click (a version switch)",
    ("acmm_qpp.cli.plumbing", "click"): "typer's vendored click, else click (a version switch)",
    ("acmm_qpp.cli.plumbing", "importlib.metadata"): "start-up: the distribution's metadata for --version only",
}


def _function_imports(path: Path) -> list[str]:
    """The modules a file imports inside a function (``from x import y`` → ``x``)."""
    found = []
    for fn in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    found += [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    found.append(("." * node.level) + (node.module or ""))
    return found


def test_the_base_imports_at_the_top_of_its_modules():
    bad = [f"{m} imports {imp} inside a function" for m, path in sorted(_modules().items())
           if m.split(".")[0] == "acmm_qpp" for imp in _function_imports(path)
           if (m, imp) not in BASE_LAZY_IMPORTS]
    assert bad == []


def test_function_import_finder():
    probe = REPO / "acmm_qpp" / "_layers_probe_tmp.py"
    probe.write_text("import os\n\ndef f():\n    import numpy\n    from . import errors\n"
                     "    from acmm_qpp.units import x\n")
    try:
        assert _function_imports(probe) == ["numpy", ".", "acmm_qpp.units"]
    finally:
        probe.unlink()


def _private_imports(path: Path) -> list[str]:
    """``from <project module> import _name`` in a file (dunder names such as ``__version__`` are
    not private)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").split(".")[0] in PACKAGES):
            out += [f"{node.module}.{a.name}" for a in node.names
                    if a.name.startswith("_") and not (a.name.startswith("__") and a.name.endswith("__"))]
    return out


def test_no_private_name_of_the_base_is_imported_by_another_module():
    """A name the base keeps private stays in its module: what another module needs is public.
    (Private names imported between product modules remain to be made public.)"""
    bad = [f"{m} imports {name}" for m, path in sorted(_modules().items())
           for name in _private_imports(path) if name.startswith("acmm_qpp")]
    assert bad == []


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
