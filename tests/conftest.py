"""Shared test fixtures: a scratch working directory and a CLI runner; the repository's root.

Test modules import the constants and helpers of this file as ``from tests.conftest import REPO``
(``tests`` is a package: see ``tests/__init__.py``)."""
from __future__ import annotations

import functools
import importlib.util
import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

#: Root of the source tree (the directory holding ``configs/``, ``README.md`` and the packages),
#: whatever the depth of the test file that needs it.
REPO = Path(__file__).resolve().parent.parent
CONFIGS = REPO / "configs"

#: The overrides that design a packaged stair-case on the report's route (sector LQR with pole
#: shifting, a fraction of a second a point) instead of the shipped regional LMI (seconds a point),
#: checked on 201 path TEAs instead of 1 001 (seconds less a design): the tests of the pipeline's
#: mechanics use them (``load_config("staircase", [*LQR_ROUTE])``); the shipped design is tested
#: in the slow group.
LQR_ROUTE = ("design.pole_method=shift", "schedule.refine_points=0", "schedule.n_check=201")


#: The costly session fixtures, in the order a test file that names several is grouped by.
SHARED_FIXTURES = ("readme_stages", "fast_report", "staircase_shipped")

#: The work units handed out first: the two longest of ``make test-slow`` (its critical path).
FIRST_UNITS = ("readme_stages", "tests/test_determinism.py")


@functools.cache
def work_unit(path: Path, test_file: str) -> str:
    """The pytest-xdist work unit of the tests of a file: the first of :data:`SHARED_FIXTURES` the
    file's text names, so that the files that share one run on the worker that computes it, once;
    else the file itself (read from ``path``; a file that cannot be read is its own unit), so that
    a module fixture is computed once too.  A file that reaches one only through another fixture
    is not grouped with the others (none does).

    Parameters
    ----------
    path : pathlib.Path
        The file.
    test_file : str
        Its node id's first part.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return test_file
    return next((name for name in SHARED_FIXTURES if name in text), test_file)


@pytest.hookimpl(optionalhook=True)       # a hook of pytest-xdist: unknown where it is not installed
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup`` (``make test-slow``) by :func:`work_unit`, :data:`FIRST_UNITS` first:
    pytest-xdist's own reads ``xdist_group`` marks off node ids that pytest 9.2 no longer lets it
    rewrite, and so groups nothing (pytest-dev/pytest-xdist#1386)."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling      # pytest-xdist: only where it runs the tests

    class SharedFixtureScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            test_file = nodeid.split("::", 1)[0]
            return work_unit(config.rootpath / test_file, test_file)

        def _assign_work_unit(self, node) -> None:
            for unit in reversed(FIRST_UNITS):
                if unit in self.workqueue:
                    self.workqueue.move_to_end(unit, last=False)
            super()._assign_work_unit(node)

    return SharedFixtureScheduling(config, log)


@pytest.fixture
def tmp_runs(tmp_path, monkeypatch) -> Path:
    """Run the test inside an empty ``tmp_path`` (so ``runs/`` lands there)."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def invoke(app, *args: str):
    """Run a typer ``app`` in-process with ``args``; returns the click ``Result``
    (``exit_code``, ``stdout``, ``stderr``, ``output``, ``exception``)."""
    from typer.testing import CliRunner

    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture
def run_acmm():
    """``run_acmm("tea", "configs/mb3.yaml")`` runs the ``acmm`` CLI in-process."""
    from acmm.cli.app import app

    return lambda *args: invoke(app, *args)


def readme_script():
    """``scripts/readme_numbers.py`` as a module (``scripts/`` is no package)."""
    spec = importlib.util.spec_from_file_location("readme_numbers", REPO / "scripts" / "readme_numbers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="session")
def readme_root(tmp_path_factory) -> Path:
    """The results root the README's stages run into (:func:`readme_stages`)."""
    return tmp_path_factory.mktemp("readme-root")


@pytest.fixture(scope="session")
def readme_stages(readme_root) -> dict:
    """The stages the README and the guide quote (:func:`acmm.report.pages.run_stages`), run
    once a session into :func:`readme_root` in this process (several minutes): the README numbers'
    tests read them and the qpp family tests check their search design by design."""
    from acmm.report.pages import run_stages           # the report layer: only for the slow tests

    readme_script().use_this_trees_configs()
    return run_stages(readme_root)
