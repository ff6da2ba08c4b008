"""The qpp stages' figures (:mod:`qpp.io.stages`): a figure that cannot be written is one
OutputError, with the results and the other figures written."""
from __future__ import annotations

import pytest

from acmm_qpp.errors import OutputError
from qpp.io.config import load_config


def _cfg(root, name="qpp_siso"):
    return load_config(name, [f"output.root={root}", "simulation.t_final=3.0"])


def test_a_qpp_figure_that_cannot_be_written_is_one_output_error(tmp_path):
    """One OutputError naming the figure; the results file and the other figures written."""
    from qpp.io import stages

    cfg = _cfg(tmp_path)
    (cfg.run_dir() / "qpp_iterations.png").mkdir(parents=True)      # a directory in its place
    with pytest.raises(OutputError, match="qpp_iterations"):
        stages.run_design(cfg, figures=True)
    assert (cfg.run_dir() / "qpp_design.h5").exists()
    assert (cfg.run_dir() / "qpp_circle_ch1.png").exists()              # the other figure was drawn
    (cfg.run_dir() / "qpp_sim_sin10.png").mkdir()
    with pytest.raises(OutputError, match="qpp_sim_sin10"):
        stages.run_simulate(cfg, figures=True)
    assert (cfg.run_dir() / "qpp_sim.h5").exists() and (cfg.run_dir() / "qpp_sim_step_offset.png").exists()
