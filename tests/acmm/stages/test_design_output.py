"""What the design stage writes besides design.h5 (acmm.stages.design_output): its four figures."""
from __future__ import annotations

from acmm.io.config import load_config

from tests.conftest import LQR_ROUTE


def test_design_figures_of_a_finished_design(tmp_path):
    # the four figures of a finished design, drawn by the stage after design.h5
    from acmm.io.config import load_config
    from acmm.stages.design_output import design_figures
    from acmm_qpp.results import draw_figures
    from acmm.design.settings import design_settings
    from acmm.stages.design import compute_design

    cfg = load_config("staircase", [*LQR_ROUTE])
    r = compute_design(cfg)
    draw_figures(design_figures(r, design_settings(cfg), tmp_path, "imperial"))
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["design_gains.png", "design_path_margins.png", "design_path_poles.png", "design_poles.png"]
    assert all((tmp_path / n).stat().st_size > 10_000 for n in names)
