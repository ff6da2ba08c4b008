"""The qpp stages (:mod:`qpp.io.stages`): a figure that cannot be written is one OutputError, with
the results and the other figures written; ``qpp simulate`` reuses the gains ``qpp design`` stored
for the same config and code."""
from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from acmm_qpp.errors import OutputError
from qpp.cli import app
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


@pytest.mark.slow
def test_qpp_simulate_reuses_the_gains_qpp_design_wrote(tmp_path, monkeypatch):
    """Same config and code: the stored K1, Kc, H (no second ch. 12.1 design) and a qpp_sim.h5
    identical to the one a simulation designing for itself writes; another config: a design."""
    from qpp.io import stages
    from qpp.design import procedure as procedure_mod
    from qpp.io.config import load_config as qpp_config
    from acmm.report.manifest import dataset_hashes

    import h5py

    over = [f"output.root={tmp_path}", "simulation.t_final=3.0"]
    alone = stages.run_simulate(qpp_config("qpp_siso", over + ["name=alone"]), figures=False)
    cfg = qpp_config("qpp_siso", over + ["name=pair"])
    _, designed, dpath = stages.run_design(cfg, figures=False)
    real_design = procedure_mod.design
    monkeypatch.setattr(stages, "_source_unchanged", lambda: True)     # as in a clean checkout
    monkeypatch.setattr(stages, "design", lambda c: pytest.fail("designed again"))
    _, reused, _, path = stages.run_simulate(cfg, figures=False)
    assert isinstance(reused, stages.StoredDesign) and reused.verdict == designed.verdict
    assert reused.horizon_note == designed.horizon_note != ""         # T = 0.5 s, settling later
    r = CliRunner().invoke(app, ["simulate", "qpp_siso", *over, "name=pair", "--no-figures"])
    assert r.exit_code == 0 and f"note: {designed.horizon_note}" in r.output, r.output
    for name in ("K1", "Kc", "H"):
        assert np.array_equal(getattr(reused, name), getattr(designed, name))
    assert dataset_hashes(path) == dataset_hashes(alone[3])
    called = []
    monkeypatch.setattr(stages, "design", lambda c: called.append(1) or real_design(c))
    stages.run_simulate(qpp_config("qpp_siso", over + ["name=pair", "simulation.t_final=2.0"]), figures=False)
    assert called == [1]                       # the config changed: designed
    monkeypatch.setattr(stages, "_source_unchanged", lambda: False)    # edited source: designed
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1]
    monkeypatch.setattr(stages, "_source_unchanged", lambda: True)
    with h5py.File(dpath, "r+") as f:          # gains edited in the file: designed
        f["K1"][0, 0] = 50.0 * f["K1"][0, 0]
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1, 1]


@pytest.mark.parametrize("commit, dirty, unchanged", [("abc", "no", True), ("abc", "yes", False),
                                                      ("abc", "unknown", False), ("unknown", "no", False)])
def test_the_source_is_unchanged_only_in_a_clean_checkout(monkeypatch, commit, dirty, unchanged):
    """Stored gains are reused only when the code running is a commit without uncommitted changes
    (git's answers as :mod:`acmm_qpp.provenance` gives them)."""
    from qpp.io import stages

    monkeypatch.setattr(stages, "git_commit", lambda: commit)
    monkeypatch.setattr(stages, "git_dirty", lambda: dirty)
    assert stages._source_unchanged() is unchanged


def test_the_figures_drawn_from_the_file_show_what_the_stage_computed(tmp_path):
    """The stages draw their figures from the file they wrote (:func:`figure_calls_from_file`, as
    ``qpp plot`` does): the iteration figure's β1 and m are the design's own (m of its bookkeeping,
    ``printed`` here, not the consistent one), and a scenario's parameters are titled in the
    expression's order (``k`` before ``c``), with the values it ran with."""
    from qpp.io import stages

    cfg = _cfg(tmp_path)
    _, r, path = stages.run_design(cfg, figures=False)
    res = stages.figure_calls_from_file(path, tmp_path)[1].args[0]
    assert (res.beta1_ref, res.m_ref, [i["beta1"] for i in res.iterations]) == \
        (r.beta1_ref, r.m_ref, [i["beta1"] for i in r.iterations])
    over = [f"output.root={tmp_path}", "name=two", "simulation.t_final=0.5", "simulation.n_samples=51",
            'nonlinearity.f1=[{form: cubic, output: 1, gain: "-c*k"}, "0"]',
            "nonlinearity.parameters={k: {min: 0.5, max: 2.0, nominal: 1.0}, c: {min: 0.9, max: 1.1, nominal: 1.0}}",
            "simulation.scenarios=[{name: s, parameters: {k: 1.5, c: 0.95}}]"]
    _, _, sims, spath = stages.run_simulate(load_config("qpp_cubic2", over), figures=False)
    drawn = stages.figure_calls_from_file(spath, tmp_path)[0].args[0]
    assert list(drawn.parameters.items()) == list(sims[0].parameters.items()) == [("k", 1.5), ("c", 0.95)]
