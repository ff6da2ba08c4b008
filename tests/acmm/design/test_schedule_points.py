"""The design points of a gain schedule (acmm.design.schedule_points): a blend whose end is on
another branch of equilibria, or that has none, or whose branch folds, is named as such."""
import re

import numpy as np
import pytest

from acmm.io.config import load_config
from acmm.stages.design import compute_design

from tests.conftest import LQR_ROUTE


@pytest.mark.parametrize("spacing", ["tea", "blend"])
def test_a_blend_whose_end_is_on_another_branch_of_equilibria_is_flagged(tmp_runs, run_acmm, spacing):
    """TEA-spaced points follow the branch continued from the start (it reaches −35° at the end
    station); the end station asks for −55° (bias_from_tea), a root of another branch: the points
    jumped −36.25° → −55° and a polynomial was fitted across the jump without a word (a review's
    case).  The end keeps its asked TEA (tests/acmm/model/test_tea.py: the schedule's end gets its
    asked attitude); the design says so, and --strict fails it."""
    from acmm.model.tea import solve_tea, solve_tea_near, bias_for_attitude

    end_inertia = np.diag([10e6, 3e6, 12e6])
    n = 0.0011
    # independent: continuation from the start's −40° root along the blend ends far from −55°
    start_inertia = np.diag([10e6, 3e6, 11e6])
    b0 = bias_for_attitude(np.radians([0, -40, 0]), start_inertia, n)
    b1 = bias_for_attitude(np.radians([0, -55, 0]), end_inertia, n)
    t = solve_tea(start_inertia, n, b0, expected=np.radians([0, -40, 0])).theta
    for s in np.linspace(0, 1, 81):
        t = solve_tea_near((1 - s) * start_inertia + s * end_inertia, n, (1 - s) * b0 + s * b1, t).theta
    assert abs(np.degrees(t[1]) + 55) > 5
    (tmp_runs / "fold.yaml").write_text(
        "name: fold\ninertia: {I11: 10.0e6, I22: 3.0e6, I33: 11.0e6}\norbit_rate: 0.0011\n"
        "disturbance: {bias_from_tea: [0, -40.0, 0]}\n"
        "schedule:\n  to: {name: fend, inertia: {I11: 10.0e6, I22: 3.0e6, I33: 12.0e6}, "
        f"disturbance: {{bias_from_tea: [0, -55.0, 0]}}}}\n  n_points: 5\n  spacing: {spacing}\n  fit: least_squares\n"
        "output: {figures: false}\n")
    r = run_acmm("design", "fold.yaml")
    assert r.exit_code == 0, r.output         # the end keeps the TEA it asks for (a result) ...
    assert "warning: the end station's TEA [+0.00, -55.00, +0.00] deg (as asked) is not on the branch" in r.stdout
    assert "fitted across the jump" in r.stdout
    branch = re.search(r"which reaches \[([^]]*)\] deg there", r.stdout).group(1)
    assert np.allclose([float(x) for x in branch.split(",")], np.degrees(t), atol=0.006)
    r = run_acmm("design", "fold.yaml", "--strict")
    assert r.exit_code == 1 and "another branch of equilibria" in r.output      # ... failed by --strict


@pytest.mark.parametrize("spacing", ["tea", "blend"])
def test_no_equilibrium_on_the_blend_names_the_blend(tmp_runs, run_acmm, spacing):
    """The message gave a blended bias the user never wrote and hinted at disturbance.bias only."""
    (tmp_runs / "s.yaml").write_text(
        "name: s\ninertia: {I11: 10.0e6, I22: 3.0e6, I33: 11.0e6}\norbit_rate: 0.0011\n"
        "disturbance: {bias_from_tea: [1.0, -30.0, 1.5]}\n"
        "schedule:\n  to: {name: endst, inertia: {I11: 30.0e6, I22: 9.0e6, I33: 36.0e6}, "
        f"disturbance: {{bias: [0, 500, 0]}}}}\n  n_points: 5\n  spacing: {spacing}\n  fit: least_squares\noutput: {{figures: false}}\n")
    r = run_acmm("design", "s.yaml")
    assert r.exit_code == 2, r.output
    assert "on the blend toward schedule.to" in r.stderr and "no torque-equilibrium" in r.stderr
    assert "hint: reduce the bias of disturbance or of schedule.to" in r.stderr
    assert not (tmp_runs / "runs").exists()


@pytest.mark.slow
def test_a_branch_that_folds_on_the_blend_blames_the_first_point_beyond_the_fold(monkeypatch):
    """When the continuation from the start failed, every point was judged against no branch,
    so the warning named the blend's start (s = 0) (a review).  The points before the fold are
    checked against the branch up to it; the first point beyond is named."""
    import acmm.design.schedule_points as sp_mod
    from acmm.model import tea as tea_mod
    from acmm.design.schedule_points import off_branch_point, point_specs

    cfg = load_config("staircase", [*LQR_ROUTE])
    n = cfg.orbit_rate
    specs = point_specs(cfg)
    teas = [compute_design(cfg).points[k].tea.theta for k in range(len(specs))]
    assert off_branch_point(specs, teas, n) is None
    blend = [p for p in specs if np.isfinite(p.s)]
    i0, i1 = blend[0].inertia[0, 0], blend[-1].inertia[0, 0]
    real = tea_mod.solve_tea_near

    def folds_at_0_6(inertia, n_, bias, guess, **kw):          # no equilibrium beyond s = 0.6
        if (inertia[0, 0] - i0) / (i1 - i0) > 0.6:
            raise tea_mod.NoEquilibriumError("folds")
        return real(inertia, n_, bias, guess, **kw)

    monkeypatch.setattr(sp_mod, "solve_tea_near", folds_at_0_6)
    jump = off_branch_point(specs, teas, n)
    first_beyond = next(p for p in blend if p.s > 0.6)
    assert jump is not None and jump.name == first_beyond.name and jump.branch is None
