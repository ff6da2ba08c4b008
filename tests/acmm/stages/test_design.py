"""The design stage (acmm.stages.design, issue 4): sector LQR at every stair-case point, the gain
schedule along the whole path, design.h5 written, reused and designed again.

Every pole is re-checked against the sector with an independent formula, and K is re-derived
from the returned Q with scipy's CARE solver directly (not through acmm.design.riccati).
"""
from __future__ import annotations

import os
import shutil

import h5py
import mpmath as mp
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.cli.app import app
from acmm.io.config import load_config
from acmm.stages.design import design_for, run_design
from acmm.stages.pool import pool_map, process_pool, stop_pool
from acmm.io.design_file import load_design_table

from tests.conftest import LQR_ROUTE, invoke

N = 0.0011


def _inside_sector(poles, n, sigma=0.5, half_angle_deg=45.0):
    re, im = poles.real, np.abs(poles.imag)
    return bool(np.all(re <= -sigma * n) and np.all(im <= np.tan(np.radians(half_angle_deg)) * -re))


def test_staircase_points_span_the_report_range(staircase_lqr):
    th2 = np.degrees(staircase_lqr.table.tea[:, 1])
    assert len(th2) >= 10
    assert th2[0] == pytest.approx(-44.7, abs=0.01) and th2[-1] == pytest.approx(-5.0, abs=0.01)
    # evenly spaced in pitch TEA (schedule.spacing: tea; s interpolated on an 81-point track)
    assert np.allclose(np.diff(th2), np.diff(th2).mean(), rtol=1e-2)


def test_every_design_point_in_sector_with_exact_lqr_gain(staircase_lqr):
    for p in staircase_lqr.points:
        m, res = p.model, p.gain.riccati           # the report's route: the gain is the LQR's
        assert np.array_equal(p.gain.K, res.K)
        poles = np.linalg.eigvals(m.A - m.B @ res.K)
        assert _inside_sector(poles, N), p.spec.name
        assert res.residual <= 1e-9
        # Q is PSD and K is the exact LQR gain of the 0.5n-shifted problem with that Q:
        d = m.scales
        a = m.A * (1 / d)[:, None] * d[None, :] + 0.5 * N * np.eye(24)
        b = m.B / d[:, None]
        q = res.Q * d[:, None] * d[None, :]
        q = 0.5 * (q + q.T)
        assert np.linalg.eigvalsh(q).min() >= -1e-9 * np.abs(q).max()
        x = sla.solve_continuous_are(a, b, q, res.R)
        k_again = np.linalg.solve(res.R, b.T @ x) / d[None, :]
        assert np.max(np.abs(k_again - res.K)) <= 1e-8 * np.max(np.abs(res.K))


def _kappa_mp(acl: np.ndarray) -> np.ndarray:
    """Eigenvalue condition numbers ‖w_i‖‖v_i‖ (W = V⁻¹) of ``acl`` in 30-digit arithmetic (mpmath)."""
    with mp.workdps(30):
        _, vr = mp.eig(mp.matrix(acl.tolist()), left=False, right=True)
        vl = mp.inverse(vr)
        return np.array([float(mp.norm(vl[i, :], 2) * mp.norm(vr[:, i], 2)) for i in range(vr.rows)])


def test_design_points_well_conditioned_with_margin(staircase_lqr):
    """Every stair-case point (MB3 and AC are its ends): every pole ≥ 0.1n inside the sector and
    the largest eigenvalue condition number in the stored state scaling ≤ 1e5, recomputed with
    scipy's left/right eigenvectors and, where either estimate is largest, in 30 digits: the
    points have nearly double eigenvalues, where pairing LAPACK's left and right eigenvectors by
    index fails on some kernels (on an AVX-512 machine 98 872 at a point where 30 digits give
    44 188, as the design stores)."""
    ours, theirs, loops = [], [], []
    for p in staircase_lqr.points:
        m, res = p.model, p.gain
        d = m.scales
        acl = (m.A - m.B @ res.K) / d[:, None] * d[None, :]
        w, vl, vr = sla.eig(acl, left=True, right=True)
        vl, vr = vl / np.linalg.norm(vl, axis=0), vr / np.linalg.norm(vr, axis=0)
        ours.append(res.max_eig_condition)
        theirs.append(np.max(1.0 / np.abs(np.sum(vl.conj() * vr, axis=0))))
        loops.append(acl)
        assert _inside_sector(w, N, 0.5 + 0.1) and _inside_sector(w + 0.1 * np.sqrt(2) * N, N), p.spec.name
        assert 0 < res.robustness_radius < 1 and 0 < res.robustness_radius_elementwise < 1
    for k in {int(np.argmax(ours)), int(np.argmax(theirs))}:
        exact = _kappa_mp(loops[k])
        assert exact.max() <= 1e5 and ours[k] == pytest.approx(exact.max(), rel=1e-4)
    assert max(ours) <= 1e5


def _worst_on_own_blend(r, gain_at, count: int = 25):
    """Largest Re λ / n of the scheduled local loop at ``count`` blend points of our own: TEA of the
    blended inertia, local model, ``gain_at(θ2*)``, numpy eigenvalues."""
    from acmm.model import linearize as lin
    from acmm.model.tea import solve_tea_near

    cfg = r.config
    a, b = r.points[0].spec, r.points[-1].spec
    theta = r.points[0].tea.theta
    worst = -np.inf
    for s in np.linspace(0.0, 1.0, count):
        inertia = (1 - s) * a.inertia + s * b.inertia
        bias = (1 - s) * a.bias + s * b.bias
        theta = solve_tea_near(inertia, N, bias, theta).theta
        m = lin.design_point(inertia, theta, N, model=cfg.design.model, drf_mode=cfg.design.drf_mode)
        worst = max(worst, np.linalg.eigvals(m.A - m.B @ gain_at(theta[1])).real.max() / N)
    return worst


def test_table_schedule_is_stable_along_the_whole_path(staircase_lqr):
    """The packaged schedule's form, the table look-up (K linear in θ2* between the 12 design
    points, report ch. 6), with the report's route's points: every local loop has Re λ ≤ −0.25n at
    ≥ 200 TEAs.  Recomputed here
    with np.interp of the point gains at 25 blend points of our own."""
    r = staircase_lqr
    assert r.fit.form == "table"
    pc = r.path_check
    assert pc.theta2.size >= 200 and pc.max_real.max() <= -0.25
    assert np.allclose(np.diff(pc.theta2), np.diff(pc.theta2).mean(), rtol=0.05)
    th = np.array([p.tea.theta[1] for p in r.points])
    Ks = np.array([p.gain.K for p in r.points])
    assert np.all(np.diff(th) > 0)

    def table(t2):
        return np.array([[np.interp(t2, th, Ks[:, i, j]) for j in range(24)] for i in range(3)])

    assert _worst_on_own_blend(r, table) <= -0.25


@pytest.mark.slow
def test_shipped_schedule_is_stable_on_a_thousand_teas_of_the_path(staircase_shipped):
    """Judged on 1 001 TEAs of the path (issue 32 item 2), not only at the design points: the
    shipped stair-case (regional LMI points, table look-up) is checked on ≥ 1 000 path TEAs by the
    design itself, and every local loop has Re λ ≤ −0.25n by the numpy eigenvalues of our own
    blend (~5 s)."""
    staircase = staircase_shipped[0]
    assert staircase.config.design.pole_method == "lmi" and staircase.fit.form == "table"
    assert staircase.path_check.theta2.size >= 1000 and staircase.path_check.max_real.max() <= -0.25
    th = np.array([p.tea.theta[1] for p in staircase.points])
    Ks = np.array([p.gain.K for p in staircase.points])

    def table(t2):
        return np.array([[np.interp(t2, th, Ks[:, i, j]) for j in range(24)] for i in range(3)])

    assert _worst_on_own_blend(staircase, table, count=1001) <= -0.25


@pytest.fixture(scope="module", params=["imperial", pytest.param("SI", marks=pytest.mark.slow)])
def designed_staircase(request, tmp_path_factory):
    """(units, the stair-case's design.h5 written by `acmm design` in those units), once per module
    (imperial: the session's :func:`tests.acmm.conftest.staircase_lqr_h5`)."""
    if request.param == "imperial":
        return "imperial", request.getfixturevalue("staircase_lqr_h5")[1]
    root = tmp_path_factory.mktemp(f"designed_{request.param}")
    r = invoke(app, "design", "staircase", *LQR_ROUTE, f"output.units={request.param}", "--no-figures",
               f"output.root={root / 'runs'}")
    assert r.exit_code == 0, r.output
    return request.param, root / "runs" / "staircase" / "design.h5"


def _edit(path, edit: str) -> np.ndarray:
    """Edit the design.h5 at ``path`` as ``edit`` says; returns its K before the edit."""
    with h5py.File(path, "r+") as f:
        K0 = f["K"][()]
        if edit == "K of another shape":
            del f["K"]
            f["K"] = np.zeros((2, 5))
        elif edit == "K scaled":
            f["K"][...] = K0 * 1e6
        elif edit == "K non-finite":
            f["K"][0, 0, 0] = np.nan
        else:
            f["schedule/coef"][0, 0, 0] += 1e-9
    return K0


@pytest.mark.parametrize("edit,why", [("K of another shape", r"K has shape \(2, 5\)"), ("K scaled", "digest"),
                                      ("K non-finite", r"K has shape \(\d+, 3, 24\) or non-finite"),
                                      ("a coefficient changed", "digest")])
def test_an_edited_design_h5_is_refused_where_reuse_is_decided(tmp_path, edit, why, designed_staircase):
    """A review: a design.h5 whose K had another shape reached the compiled simulator (a numba
    traceback, exit 1); one whose K was scaled by 1e6 under the right design_hash was simulated
    (52 M steps).  The design is now reused only when its arrays have the points' shapes, are
    finite and match the digest written with them: :func:`load_design_table`, by which
    :func:`design_for` decides, reads the file as written and refuses every edit, naming why."""
    units, written = designed_staircase
    path = tmp_path / "design.h5"
    shutil.copyfile(written, path)
    assert load_design_table(path).gain.shape[1:] == (3, 24)
    _edit(path, edit)
    with pytest.raises(ValueError, match=why):
        load_design_table(path)


def test_an_edited_design_h5_is_designed_again_not_simulated(tmp_runs, run_acmm, designed_staircase):
    """End to end, the refusal above makes ``acmm simulate`` design again (the same gains) instead
    of simulating the edited gains."""
    units, written = designed_staircase
    path = tmp_runs / "runs" / "staircase" / "design.h5"
    path.parent.mkdir(parents=True)
    shutil.copyfile(written, path)
    assert design_for(load_config("staircase", [*LQR_ROUTE, f"output.units={units}"]))[1].startswith("reused")
    K0 = _edit(path, "K scaled")
    r = run_acmm("simulate", "staircase", *LQR_ROUTE, f"output.units={units}", "simulation.orbits=1",
                 "--no-figures")
    assert r.exit_code == 0 and "Traceback" not in r.output, r.output
    assert "designed" in r.stdout and "design reused" not in r.stdout, r.stdout
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["K"][()], K0)            # designed again, the same gains


def test_design_h5_is_self_describing_and_reused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = load_config("ac")
    r, path = run_design(cfg, figures=True)
    assert path.resolve() == tmp_path / "runs" / "ac" / "design.h5"
    assert (tmp_path / "runs" / "ac" / "design_poles.png").exists()
    with h5py.File(path) as f:
        missing = []
        f.visititems(lambda name, obj: missing.append(name)
                     if isinstance(obj, h5py.Dataset) and "units" not in obj.attrs else None)
        assert not missing
        assert f.attrs["design_hash"] and f.attrs["config"] and f.attrs["package_version"]
    table = load_design_table(path)
    with h5py.File(path) as f:
        k = sorted(f["points"])[0]
        assert f[f"points/{k}/max_eig_condition"][()] == pytest.approx(r.points[0].gain.max_eig_condition)
        assert f[f"points/{k}/robustness_radius"].attrs["units"] == "1"
    assert np.array_equal(table.gain[0], r.points[0].gain.K)
    _, note = design_for(cfg)
    assert note.startswith("reused")
    # a design-relevant change invalidates the cached design
    cfg2 = cfg.model_copy(update={"design": cfg.design.model_copy(update={"R": 2e-4})})
    _, note2 = design_for(cfg2)
    assert note2.startswith("designed")


def test_table_form_prints_the_check_that_strict_judges(tmp_runs, run_acmm):
    """schedule.form: table printed no check lines, yet --strict failed on the check's margin."""
    r = run_acmm("design", "staircase", *LQR_ROUTE, "schedule.form=table", "schedule.fit=least_squares",
                 "schedule.n_points=4", "--no-figures")
    assert r.exit_code == 0, r.output
    assert "scheduled gain (table) on the local models" in r.stdout and "scheduled closed loops:" in r.stdout


def test_a_fifo_in_place_of_design_h5_is_designed_again_not_a_hang(tmp_path, monkeypatch):
    """``acmm simulate`` reuses ``design.h5`` when it matches: a FIFO (or a device) there used to
    block it for ever; it is not a design file, so the stage designs again and replaces it."""
    from acmm.io.config import load_config
    from acmm.stages.design import design_for

    monkeypatch.chdir(tmp_path)
    cfg = load_config("mb3", ["output.figures=false"])
    run = cfg.run_dir()
    run.mkdir(parents=True)
    os.mkfifo(run / "design.h5")
    table, note = design_for(cfg)
    assert note.startswith("designed") and (run / "design.h5").is_file()
    assert design_for(cfg)[1].startswith("reused")


def _sdp(size: int) -> float:
    """A semidefinite program solved by Clarabel with the regional LMI route's options:
    min tr X s.t. X ⪰ I (optimum = size)."""
    import cvxpy as cp

    from acmm.design.regional_lmi import CLARABEL_OPTIONS

    X = cp.Variable((size, size), symmetric=True)
    prob = cp.Problem(cp.Minimize(cp.trace(X)), [X >> np.eye(size)])
    prob.solve(solver=cp.CLARABEL, **CLARABEL_OPTIONS)
    return float(prob.value)


def test_pool_workers_solve_lmis_after_the_parent_has():
    """With Clarabel's default threads a forked child of a process that had solved a 60 × 60 SDP
    hung in its next solve (the LMI stair-case's points on the design stage's pool after an
    in-process LMI design, in the test session); with the route's options (one thread) the forked
    workers of the same pool solve."""
    assert _sdp(60) == pytest.approx(60.0, rel=1e-6)
    pool = process_pool(2)
    try:
        futures = [pool.submit(_sdp, 60) for _ in range(2)]
        assert [f.result(timeout=120) for f in futures] == pytest.approx([60.0, 60.0], rel=1e-6)
        assert list(pool_map(pool, _sdp, [3, 4])) == pytest.approx([3.0, 4.0], rel=1e-6)
    finally:
        stop_pool(pool, abort=True)


def _warns(x):
    import warnings

    warnings.warn(f"point {x}", RuntimeWarning)
    return x * 2


def test_pooled_points_equal_the_serial_ones_and_their_warnings_reach_the_parent():
    """The design stage maps LMI points onto the pool (``map_points``); the result does not depend
    on where a point is designed: here four points of the report's route, bit for bit, and a
    worker's warning is raised in the parent (where filters and pytest.warns see it)."""
    from functools import partial

    from acmm.design import schedule_points as sp
    from acmm.design.design_core import design_schedule
    from acmm.design.settings import design_settings, schedule_settings

    cfg = load_config("staircase", [*LQR_ROUTE, "schedule.n_points=4", "schedule.n_check=11"])
    specs, s, sched = sp.point_specs(cfg), design_settings(cfg), schedule_settings(cfg)
    serial = design_schedule(specs, s, sched)
    pool = process_pool(2)
    try:
        pooled = design_schedule(specs, s, sched, map_points=partial(pool_map, pool))
        with pytest.warns(RuntimeWarning, match=r"point [13]") as rec:
            assert list(pool_map(pool, _warns, [1, 3])) == [2, 6]
        assert sorted(str(w.message) for w in rec) == ["point 1", "point 3"]
    finally:
        stop_pool(pool, abort=True)
    for a, b in zip(serial.points, pooled.points):
        np.testing.assert_array_equal(a.gain.K, b.gain.K)


def test_lmi_points_are_designed_in_this_process_beside_other_threads(monkeypatch):
    """A fork beside a running thread (a terminal's progress bar) can deadlock the child: the
    LMI points then go serial; inside a pool worker too; the report's route never uses the pool."""
    import threading

    from acmm.stages.design import _point_workers

    assert _point_workers(False, 12) == 1 and _point_workers(True, 1) == 1
    monkeypatch.setattr(threading, "active_count", lambda: 1)
    assert _point_workers(True, 12) == min(12, len(os.sched_getaffinity(0)))
    monkeypatch.setattr(threading, "active_count", lambda: 2)
    assert _point_workers(True, 12) == 1


def _dies(x):
    os._exit(1)


def test_a_dead_pool_worker_is_one_output_error():
    """A worker killed mid-task (here it exits) is an OutputError (exit 4, one line), not a traceback."""
    from acmm_qpp.errors import OutputError

    pool = process_pool(1)
    try:
        with pytest.raises(OutputError, match="worker process died"):
            list(pool_map(pool, _dies, [1]))
    finally:
        stop_pool(pool, abort=True)
