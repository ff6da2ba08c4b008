"""What the design stage writes besides design.h5 (acmm.stages.design_output): its four figures."""
from __future__ import annotations

from acmm.io.config import load_config

from tests.conftest import LQR_ROUTE


def test_design_figures_of_a_finished_design(tmp_runs):
    # the four figures of a finished design, drawn by the stage from the design.h5 it wrote
    from acmm.stages.design import run_design

    _, path = run_design(load_config("staircase", [*LQR_ROUTE]), figures=True)
    names = sorted(p.name for p in path.parent.glob("*.png"))
    assert names == ["design_gains.png", "design_path_margins.png", "design_path_poles.png", "design_poles.png"]
    assert all((path.parent / n).stat().st_size > 10_000 for n in names)
