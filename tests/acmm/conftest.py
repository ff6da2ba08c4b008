"""Fixtures and helpers of the acmm tests in several folders: the packaged stair-case designed on
the report's route (``staircase_lqr``; ``staircase_lqr_h5`` with its ``design.h5``) and as shipped
(``staircase_shipped``, slow tests), the figures a test draws (``captured``) with the check that
every axis names a quantity and a unit, and a sweep config file written for a test
(``_sweep_yaml``)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from acmm.io.config import load_config
from acmm.stages.design import compute_design, run_design
from acmm.plots import base as plot_base
from acmm.plots import design as design_plots
from acmm.plots import simulation as sim_plots

from tests.conftest import LQR_ROUTE, CONFIGS


@pytest.fixture(scope="session")
def staircase_lqr():
    """The packaged stair-case designed on the report's route (:data:`tests.conftest.LQR_ROUTE`)."""
    return compute_design(load_config("staircase", [*LQR_ROUTE]))


@pytest.fixture(scope="session")
def staircase_lqr_h5(tmp_path_factory):
    """The packaged stair-case on the report's route as ``acmm design`` writes it, dwell-time
    certificate included (about ten seconds): its :class:`~acmm.stages.design.DesignResult` and
    ``design.h5``.  A test that needs the file in a run folder of its own copies it; none may
    change it."""
    root = tmp_path_factory.mktemp("lqr")
    return run_design(load_config("staircase", [*LQR_ROUTE, f"output.root={root}"]), figures=False)


@pytest.fixture(scope="session")
def staircase_shipped(tmp_path_factory):
    """The packaged stair-case as shipped (regional LMI points, seconds each on the process pool): its
    :class:`~acmm.stages.design.DesignResult` and the ``design.h5`` written for it (slow tests)."""
    root = tmp_path_factory.mktemp("shipped")
    return run_design(load_config("staircase", [f"output.root={root}"]), figures=False)


UNIT = re.compile(r"^(?P<quantity>.{3,}?)\s*\((?P<unit>[^()]*(\([^()]*\))?[^()]*)\)\s*$")


@pytest.fixture
def captured(monkeypatch):
    figs = []

    def fake_save(fig, path, vector=False, tight=True, rc=None):
        import matplotlib

        with matplotlib.rc_context(rc or {}):
            fig.canvas.draw()                  # renders: a figure that cannot draw fails here
        figs.append(fig)
        return [path]

    monkeypatch.setattr(plot_base, "write_figure", fake_save)         # acmm.sweep.output imports it from there
    monkeypatch.setattr(design_plots, "write_figure", fake_save)      # the figures live in these two
    monkeypatch.setattr(sim_plots, "write_figure", fake_save)
    return figs


def _same_column(fig, ax):
    x0 = ax.get_position().x0
    return [a for a in fig.axes if a.axison and abs(a.get_position().x0 - x0) < 1e-6]


def _check_panel_labels(grid):
    """A panel grid (acmm.plots.panel_grid): each panel's y label (or its title when it has none)
    names the quantity and its unit, each column has an x label with its unit."""
    for p in grid.panels:
        ylab = p.ylabel or p.title
        m = UNIT.match(ylab)
        assert m and m["unit"].strip(), f"panel y label (or title) without quantity and unit: {ylab!r}"
    for c in range(grid.cols):
        labels = [p.xlabel for p in grid.panels[c::grid.cols] if p.xlabel]
        assert labels, f"no x label in column {c}"
        for lab in labels:
            m = UNIT.match(lab)
            assert m and m["unit"].strip(), f"x label without quantity and unit: {lab!r}"


def _check_labels(fig):
    if hasattr(fig, "panel_grid"):
        _check_panel_labels(fig.panel_grid)
        return
    axes = [ax for ax in fig.axes if ax.axison]
    assert axes
    for ax in axes:
        # the y quantity and unit: the y label, or the panel title when there is no y label
        ylab = ax.get_ylabel() or ax.get_title()
        m = UNIT.match(ylab)
        assert m and m["unit"].strip(), f"y label (or title) without quantity and unit: {ylab!r}"
        siblings = set(ax.get_shared_x_axes().get_siblings(ax)) | set(_same_column(fig, ax))
        labelled = [a.get_xlabel() for a in siblings if a.get_xlabel()]
        assert labelled, f"no x label on the column of {ax.get_title()!r}"
        for lab in labelled:
            m = UNIT.match(lab)
            assert m and m["unit"].strip(), f"x label without quantity and unit: {lab!r}"
        for lab in (ax.get_xlabel(), ax.get_ylabel()):
            assert "[1]" not in lab


def _sweep_yaml(tmp: Path, name: str, sort_keys: bool = True, **over) -> Path:
    spec = {"base": str(CONFIGS / "ac.yaml"), "monte_carlo": {"inertia": {"percent": 10}},
            "n_runs": 6, "seed": 11, "orbits": 1.0}
    spec.update(over)
    data = {"name": name, "sweep": spec, "output": {"root": str(tmp / "runs"), "figures": False}}
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=sort_keys))
    return p
