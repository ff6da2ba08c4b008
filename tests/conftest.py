"""Shared test fixtures: a scratch working directory and a CLI runner; the repository's root.

Test modules import the constants and helpers of this file as ``from tests.conftest import REPO``
(``tests`` is a package: see ``tests/__init__.py``)."""
from __future__ import annotations

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
