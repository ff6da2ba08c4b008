"""The design pipeline on explicit arguments (acmm.design.design_core): the table schedule's
refinement (``schedule.refine_points``, issue 41 item 3) — nodes added between the stair-case
levels where the scheduled loop leaves the sector, the levels kept as the stair-case.

The fast tests run the report's route on a 3-point blend (its gains are chosen discretely, so the
refinement spends its whole budget: the bookkeeping is what they check); the slow test checks the
shipped stair-case in the sector at every path TEA, re-evaluated from ``design.h5`` on a path of
our own with our own sector test.
"""
from __future__ import annotations

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from acmm.cli.app import app
from acmm.io.config import load_config
from acmm.io.design_file import load_design_table
from acmm.model import linearize as lin
from acmm.model.tea import solve_tea_near
from acmm.simulate.scenario import scenario_from_config
from acmm.stages.design import run_design
from acmm_qpp.errors import ConfigError

N = 0.0011
SMALL = ("design.pole_method=shift", "schedule.n_points=3", "schedule.n_check=41", "schedule.refine_points=3",
         "simulation.orbits=3")


def _in_sector(poles, n, sigma=0.5, half_angle_deg=45.0) -> bool:
    re, im = poles.real, np.abs(poles.imag)
    return bool(np.all(re <= -sigma * n) and np.all(im <= np.tan(np.radians(half_angle_deg)) * -re))


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    root = tmp_path_factory.mktemp("refine")
    return run_design(load_config("staircase", [*SMALL, f"output.root={root}"]), figures=False)


def test_refinement_adds_nodes_not_levels(small):
    """3 levels, 3 nodes added (the budget: the report's route does not converge under bisection);
    the rows in the order of s with θ2* increasing; the levels are the blend's 3 points."""
    r, path = small
    rf = r.refinement
    assert (rf.added, rf.limit, rf.margin) == (3, 3, 0.05) and rf.rounds >= 1 and not rf.met
    assert len(r.points) == 6
    s = np.array([p.spec.s for p in r.points])
    assert np.all(np.diff(s) > 0) and s[0] == 0.0 and s[-1] == 1.0
    assert np.all(np.diff([p.tea.theta[1] for p in r.points]) > 0)
    level = np.array([p.spec.level for p in r.points])
    assert level.sum() == 3 and level[0] and level[-1]
    th = np.degrees([p.tea.theta[1] for p in r.points])
    assert np.allclose(th[level], [-44.7, -24.85, -5.0], atol=0.05)   # the levels: spaced in TEA (81-point track)
    nodes = [p for p in r.points if not p.spec.level]
    assert all(p.spec.name.startswith("node_s") for p in nodes)
    # each node is the middle, in s, of two neighbours at the time it was added
    for p in nodes:
        assert any(abs(p.spec.s - 0.5 * (a + b)) < 1e-12 for a in s for b in s if a < p.spec.s < b)


def test_levels_survive_design_h5(small):
    """design.h5 keeps which rows are levels (its digest covers them); the stair-case simulated
    from it has the 3 levels, with their own TEAs and the schedule at those TEAs."""
    r, path = small
    with h5py.File(path) as f:
        assert list(f["level"][()]) == [int(p.spec.level) for p in r.points]
        assert int(f["schedule/refine_added"][()]) == 3
    table = load_design_table(path)
    rows = table.level_rows()
    assert rows.tolist() == [k for k, p in enumerate(r.points) if p.spec.level]
    sc = scenario_from_config(r.config, table)
    assert sc.theta_est.shape == (3, 3)
    assert np.array_equal(sc.theta_est, np.array([p.tea.theta for p in r.points if p.spec.level]))
    # the table at a level's TEA is the level's own gain
    assert np.allclose(sc.gain, np.array([p.gain.K for p in r.points if p.spec.level]), rtol=0, atol=1e-12)
    # an edited level mask is refused (designed again), as an edited gain is
    with h5py.File(path, "r+") as f:
        lv = f["level"][()]
        lv[1] = 1 - lv[1]
        f["level"][...] = lv
    with pytest.raises(ValueError, match="digest"):
        load_design_table(path)


def test_refinement_config_errors():
    # a polynomial has no nodes: the packaged table's refine_points is not asked of it
    assert load_config("staircase", ["schedule.form=polynomial"]).schedule.refine_points == 24
    with pytest.raises(ConfigError, match="refine_points"):
        load_config("staircase", ["schedule.refine_points=-1"])


def test_refinement_reported_by_acmm_design(tmp_path):
    """The CLI names the nodes, the path's count in the sector and a refinement that ran out."""
    res = CliRunner().invoke(app, ["design", "staircase", *SMALL, f"output.root={tmp_path}", "--no-figures"])
    assert res.exit_code == 0, res.output
    assert "6 design points (3 levels and 3 node(s) added" in res.output
    assert "refinement stopped after 3 of at most 3 node(s)" in res.output
    assert "along the path (41 TEAs): every pole in the sector at" in res.output


@pytest.mark.slow
def test_shipped_schedule_in_the_sector_on_the_whole_path(staircase_shipped):
    """Issue 41 item 3: the packaged stair-case's table keeps every pole in the sector at every
    one of its 1 001 path TEAs (margin ≥ refine_margin = 0.05n, by the design's own check), and on
    a path of our own — 1 201 evenly spaced s, TEA by Newton continuation, K by np.interp of the
    rows of design.h5 — by our own sector test; the stair-case still has the config's 12 levels."""
    r, path = staircase_shipped
    assert r.refinement.met and 0 < r.refinement.added <= r.config.schedule.refine_points
    assert r.path_check.theta2.size == 1001 and r.path_check.margin.min() >= 0.05
    with h5py.File(path) as f:
        th = f["tea"][()][:, 1]
        K = f["K"][()]
        level = f["level"][()]
        inertia, bias = f["inertia"][()], f["bias"][()]
    assert int(level.sum()) == 12 and np.all(np.diff(th) > 0)
    a, b = 0, len(th) - 1
    theta = load_design_table(path).tea[0]
    bad = []
    for s in np.linspace(0.0, 1.0, 1201):
        I = (1 - s) * inertia[a] + s * inertia[b]
        theta = solve_tea_near(I, N, (1 - s) * bias[a] + s * bias[b], theta).theta
        Ks = np.array([[np.interp(theta[1], th, K[:, i, j]) for j in range(24)] for i in range(3)])
        m = lin.design_point(I, theta, N, model="coupled", drf_mode="attitude_hold")
        if not _in_sector(np.linalg.eigvals(m.A - m.B @ Ks), N):
            bad.append(s)
    assert not bad, f"out of the sector at s = {bad[:5]}"
    assert len(scenario_from_config(r.config, load_design_table(path)).level_start) == 12
