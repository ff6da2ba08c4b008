"""The qpp stages draw their figures in the shared figure worker (issue 16,
:mod:`acmm_qpp.figure_worker`): the same PNG bytes as drawn in place, and a figure that cannot be
written is one OutputError with nothing left running."""
from __future__ import annotations

import os

import pytest

from acmm_qpp import figure_worker
from acmm_qpp.errors import OutputError
from qpp.io.config import load_config

pytestmark = pytest.mark.skipif(not figure_worker.usable(), reason="no fork, one CPU or other threads")


def _cfg(root, name="qpp_siso"):
    return load_config(name, [f"output.root={root}", "simulation.t_final=3.0"])


def _pngs(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.glob("*.png"))}


@pytest.mark.slow
def test_qpp_figures_in_the_worker_are_the_figures_drawn_in_place(tmp_path, monkeypatch):
    from qpp.io import stages

    out = {}
    for mode in ("worker", "in_place"):
        if mode == "in_place":
            monkeypatch.setenv("ACMM_FIGURE_WORKER", "0")
        cfg = _cfg(tmp_path / mode)
        stages.run_design(cfg, figures=True)
        stages.run_simulate(cfg, figures=True)
        assert not figure_worker.active()
        out[mode] = _pngs(cfg.run_dir())
    assert set(out["worker"]) == {"qpp_circle_ch1.png", "qpp_iterations.png", "qpp_sim_sin10.png",
                                  "qpp_sim_step_offset.png"}
    assert out["worker"] == out["in_place"]


@pytest.mark.parametrize("mode", ["worker", "in_place"])
def test_a_qpp_figure_that_cannot_be_written_is_one_output_error(tmp_path, monkeypatch, mode):
    """With or without the worker: one OutputError, the results file and the other figures
    written, nothing left running."""
    from qpp.io import stages

    if mode == "in_place":
        monkeypatch.setenv("ACMM_FIGURE_WORKER", "0")
    cfg = _cfg(tmp_path)
    (cfg.run_dir() / "qpp_iterations.png").mkdir(parents=True)      # a directory in its place
    with pytest.raises(OutputError, match="qpp_iterations"):
        stages.run_design(cfg, figures=True)
    assert not figure_worker.active()
    assert (cfg.run_dir() / "qpp_design.h5").exists()
    assert (cfg.run_dir() / "qpp_circle_ch1.png").exists()              # the other figure was drawn
    (cfg.run_dir() / "qpp_sim_sin10.png").mkdir()
    with pytest.raises(OutputError, match="qpp_sim_sin10"):
        stages.run_simulate(cfg, figures=True)
    assert (cfg.run_dir() / "qpp_sim.h5").exists() and (cfg.run_dir() / "qpp_sim_step_offset.png").exists()
    left = [int(p) for p in os.listdir("/proc") if p.isdigit()] if os.path.isdir("/proc") else []
    assert not [p for p in left if _parent(p) == os.getpid()]          # no worker or writer left


def _parent(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return int(f.read().rsplit(")", 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return -1


def test_the_warm_ups_are_named_right():
    """The CLI's early worker and the stages name the same acmm warm-up; both products' warm-ups
    resolve; qpp's leaves the rcParams (the look of its figures) as they are."""
    import importlib

    import matplotlib

    from acmm.stages import common as stage_common
    from acmm.cli import app as acmm_app
    from acmm_qpp.figure_process import _warm
    from qpp import plots

    assert acmm_app.FIGURE_WARM == stage_common.FIGURE_WARM
    for spec in (stage_common.FIGURE_WARM, plots.FIGURE_WARM):
        module, _, name = spec.partition(":")
        assert callable(getattr(importlib.import_module(module), name))
    rc = {k: v for k, v in matplotlib.rcParams.items() if k != "backend"}
    _warm(plots.FIGURE_WARM)
    _warm(None)
    assert {k: v for k, v in matplotlib.rcParams.items() if k != "backend"} == rc
