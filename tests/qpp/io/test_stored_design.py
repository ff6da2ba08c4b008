"""``qpp simulate`` reuses the gains ``qpp design`` stored for the same config and code
(:func:`qpp.io.stored_design.load_stored_design`)."""
from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from qpp.cli import app


@pytest.mark.slow
def test_qpp_simulate_reuses_the_gains_qpp_design_wrote(tmp_path, monkeypatch):
    """Same config and code: the stored K1, Kc, H (no second ch. 12.1 design) and a qpp_sim.h5
    identical to the one a simulation designing for itself writes; another config: a design."""
    from qpp.io import stages
    from qpp.design import procedure as procedure_mod
    from qpp.io.config import load_config as qpp_config
    from qpp.io.stored_design import StoredDesign
    from acmm.report.manifest import dataset_hashes

    import h5py

    from qpp.io import stored_design          # it imports source_unchanged: patched where it is read

    over = [f"output.root={tmp_path}", "simulation.t_final=3.0"]
    alone = stages.run_simulate(qpp_config("qpp_siso", over + ["name=alone"]), figures=False)
    cfg = qpp_config("qpp_siso", over + ["name=pair"])
    _, designed, dpath = stages.run_design(cfg, figures=False)
    real_design = procedure_mod.design
    monkeypatch.setattr(stored_design, "source_unchanged", lambda: True)     # as in a clean checkout
    monkeypatch.setattr(stages, "design", lambda c: pytest.fail("designed again"))
    _, reused, _, path = stages.run_simulate(cfg, figures=False)
    assert isinstance(reused, StoredDesign) and reused.verdict == designed.verdict
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
    monkeypatch.setattr(stored_design, "source_unchanged", lambda: False)    # edited source: designed
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1]
    monkeypatch.setattr(stored_design, "source_unchanged", lambda: True)
    with h5py.File(dpath, "r+") as f:          # gains edited in the file: designed
        f["K1"][0, 0] = 50.0 * f["K1"][0, 0]
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1, 1]


@pytest.mark.parametrize("commit, dirty, unchanged", [("abc", "no", True), ("abc", "yes", False),
                                                      ("abc", "unknown", False), ("unknown", "no", False)])
def test_the_source_is_unchanged_only_in_a_clean_checkout(monkeypatch, commit, dirty, unchanged):
    """Stored gains are reused only when the code running is a commit without uncommitted changes
    (git's answers as :mod:`acmm_qpp.provenance` gives them)."""
    from qpp.io import stored_design

    monkeypatch.setattr(stored_design, "git_commit", lambda: commit)
    monkeypatch.setattr(stored_design, "git_dirty", lambda: dirty)
    assert stored_design.source_unchanged() is unchanged
