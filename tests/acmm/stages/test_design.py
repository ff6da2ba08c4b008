"""Design stage (issue 4): sector LQR at every stair-case point, the gain schedule, design.h5.

Every pole is re-checked against the sector with an independent formula, and K is re-derived
from the returned Q with scipy's CARE solver directly (not through acmm.design.riccati).
"""
import h5py
import re

import numpy as np
import pytest
import scipy.linalg as sla

from acmm.io.config import load_config
from acmm.design.schedule import fit_schedule, schedule_gain
from acmm.design.settings import design_settings
from acmm.stages.design import compute_design, design_for, run_design
from acmm.io.design_file import load_design_table

N = 0.0011


@pytest.fixture(scope="module")
def staircase():
    return compute_design(load_config("staircase"))


def _inside_sector(poles, n, sigma=0.5, half_angle_deg=45.0):
    re, im = poles.real, np.abs(poles.imag)
    return bool(np.all(re <= -sigma * n) and np.all(im <= np.tan(np.radians(half_angle_deg)) * -re))


def test_staircase_points_span_the_report_range(staircase):
    th2 = np.degrees(staircase.table.tea[:, 1])
    assert len(th2) >= 10
    assert th2[0] == pytest.approx(-44.7, abs=0.01) and th2[-1] == pytest.approx(-5.0, abs=0.01)
    # evenly spaced in pitch TEA (schedule.spacing: tea; s interpolated on an 81-point track)
    assert np.allclose(np.diff(th2), np.diff(th2).mean(), rtol=1e-2)


def test_every_design_point_in_sector_with_exact_lqr_gain(staircase):
    for p in staircase.points:
        m, res = p.model, p.lqr
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


def test_design_points_well_conditioned_with_margin(staircase):
    """Every stair-case point (MB3 and AC are its ends): every pole ≥ 0.1n inside the sector and
    the largest eigenvalue condition number in the stored state scaling ≤ 1e5, both recomputed
    with scipy's left/right eigenvectors."""
    ours, theirs = [], []
    for p in staircase.points:
        m, res = p.model, p.lqr
        d = m.scales
        acl = (m.A - m.B @ res.K) / d[:, None] * d[None, :]
        w, vl, vr = sla.eig(acl, left=True, right=True)
        vl, vr = vl / np.linalg.norm(vl, axis=0), vr / np.linalg.norm(vr, axis=0)
        kappa = 1.0 / np.abs(np.sum(vl.conj() * vr, axis=0))
        assert kappa.max() <= 1e5, (p.spec.name, kappa.max())
        ours.append(res.max_eig_condition)
        theirs.append(kappa.max())
        assert _inside_sector(w, N, 0.5 + 0.1) and _inside_sector(w + 0.1 * np.sqrt(2) * N, N), p.spec.name
        assert 0 < res.robustness_radius < 1 and 0 < res.robustness_radius_elementwise < 1
    # κ of nearly clustered poles moves by ~10-20 % with the rounding of A − BK; the maxima agree
    assert max(ours) == pytest.approx(max(theirs), rel=0.05) and max(ours) <= 1e5


def _worst_on_own_blend(r, gain_at):
    """Largest Re λ / n of the scheduled local loop at 25 blend points of our own: TEA of the
    blended inertia, local model, ``gain_at(θ2*)``, numpy eigenvalues."""
    from acmm.model import linearize as lin
    from acmm.model.tea import solve_tea_near

    cfg = r.config
    a, b = r.points[0].spec, r.points[-1].spec
    theta = r.points[0].tea.theta
    worst = -np.inf
    for s in np.linspace(0.0, 1.0, 25):
        inertia = (1 - s) * a.inertia + s * b.inertia
        bias = (1 - s) * a.bias + s * b.bias
        theta = solve_tea_near(inertia, N, bias, theta).theta
        m = lin.design_point(inertia, theta, N, model=cfg.design.model, drf_mode=cfg.design.drf_mode)
        worst = max(worst, np.linalg.eigvals(m.A - m.B @ gain_at(theta[1])).real.max() / N)
    return worst


def test_table_schedule_is_stable_along_the_whole_path(staircase):
    """The shipped schedule is the table look-up (K linear in θ2* between the 12 design points,
    report ch. 6); with it every local loop has Re λ ≤ −0.25n at ≥ 200 TEAs.  Recomputed here
    with np.interp of the point gains at 25 blend points of our own."""
    r = staircase
    assert r.fit.form == "table"
    pc = r.path_check
    assert pc.theta2.size >= 200 and pc.max_real.max() <= -0.25
    assert np.allclose(np.diff(pc.theta2), np.diff(pc.theta2).mean(), rtol=0.05)
    th = np.array([p.tea.theta[1] for p in r.points])
    Ks = np.array([p.lqr.K for p in r.points])
    assert np.all(np.diff(th) > 0)

    def table(t2):
        return np.array([[np.interp(t2, th, Ks[:, i, j]) for j in range(24)] for i in range(3)])

    assert _worst_on_own_blend(r, table) <= -0.25


@pytest.fixture(scope="module")
def staircase_polynomial():
    return compute_design(load_config("staircase", ["schedule.form=polynomial", "schedule.fit=closed_loop"]))


def test_quadratic_schedule_is_stable_along_the_whole_path(staircase_polynomial):
    """The report's form (order 2 in θ2*, refined against the closed loop until SLSQP's own
    convergence test): every local loop has Re λ ≤ −0.25n at ≥ 200 TEAs, recomputed here with
    np.polyval at 25 blend points of our own."""
    r = staircase_polynomial
    assert r.fit.order == 2 and r.fit.coef.shape[0] == 3
    assert r.fit.refit_info["accepted"] and r.fit.refit_info["iterations"] < 2000
    pc = r.path_check
    assert pc.theta2.size >= 200 and pc.max_real.max() <= -0.25

    def poly(t2):
        return np.array([[np.polyval(r.fit.coef[::-1, i, j], t2) for j in range(24)] for i in range(3)])

    assert _worst_on_own_blend(r, poly) <= -0.25


def test_path_disk_margin_agrees_with_python_control(staircase):
    """Disk margin at the plant input (loop broken at u) against control.disk_margins (SLICOT
    AB13MD) on the same local loops, in the scaled realization."""
    import control

    from acmm.design import schedule as sch
    from acmm.design import path_check as path_check_mod

    if not hasattr(control, "disk_margins"):       # python-control < 0.10.2
        pytest.skip("this python-control has no disk_margins")
    pc = staircase.path_check
    path = path_check_mod.path_models(staircase.points, design_settings(staircase.config), pc.theta2.size)
    d = path.scales
    for j in (0, pc.theta2.size // 2, pc.theta2.size - 1):
        K = staircase.fit.gain(pc.theta2[j]) * d[None, :]
        L = control.ss(path.A[j] / d[:, None] * d[None, :], path.B[j] / d[:, None], K, np.zeros((3, 3)))
        dm, dgm, dpm = control.disk_margins(L, N * path_check_mod.DISK_OMEGA_N)
        assert pc.disk_margin[j] == pytest.approx(dm, rel=1e-3)
        assert pc.disk_gain_margin_db[j] == pytest.approx(dgm, rel=1e-3)
        assert pc.disk_phase_margin_deg[j] == pytest.approx(dpm, rel=1e-3)
    assert pc.disk_margin.min() > 0


def test_fit_recovers_a_known_quadratic_and_table_is_exact_at_nodes():
    rng = np.random.default_rng(1)
    th = np.radians(np.linspace(-45, -5, 9))
    coef = rng.normal(size=(3, 3, 24))
    gains = np.array([coef[0] + coef[1] * t + coef[2] * t * t for t in th])
    fit = fit_schedule(th, gains, 2)
    assert np.allclose(fit.coef, coef, rtol=1e-9, atol=1e-9)
    assert fit.rel_residual.max() < 1e-10
    for k, t in enumerate(th):
        assert np.allclose(schedule_gain("table", fit.coef, th, gains, t), gains[k])
    mid = 0.5 * (th[2] + th[3])
    assert np.allclose(schedule_gain("table", fit.coef, th, gains, mid), 0.5 * (gains[2] + gains[3]))


@pytest.mark.parametrize("units", ["imperial", "SI"])
@pytest.mark.parametrize("edit", ["K of another shape", "K scaled", "K non-finite", "a coefficient changed"])
def test_an_edited_design_h5_is_designed_again_not_simulated(tmp_runs, run_acmm, edit, units):
    """A review: a design.h5 whose K had another shape reached the compiled simulator (a numba
    traceback, exit 1); one whose K was scaled by 1e6 under the right design_hash was simulated
    (52 M steps).  The design is now reused only when its arrays have the points' shapes, are
    finite and match the digest written with them; else it is designed again."""
    r = run_acmm("design", "staircase", f"output.units={units}", "--no-figures")
    assert r.exit_code == 0, r.output
    path = tmp_runs / "runs" / "staircase" / "design.h5"
    with h5py.File(path, "r") as f:
        K0 = f["K"][()]
    assert design_for(load_config("staircase", [f"output.units={units}"]))[1].startswith("reused")
    with h5py.File(path, "r+") as f:
        if edit == "K of another shape":
            del f["K"]
            f["K"] = np.zeros((2, 5))
        elif edit == "K scaled":
            f["K"][...] = K0 * 1e6
        elif edit == "K non-finite":
            f["K"][0, 0, 0] = np.nan
        else:
            f["schedule/coef"][0, 0, 0] += 1e-9
    r = run_acmm("simulate", "staircase", f"output.units={units}", "simulation.orbits=1", "--no-figures")
    assert r.exit_code == 0 and "Traceback" not in r.output, r.output
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
        assert f[f"points/{k}/max_eig_condition"][()] == pytest.approx(r.points[0].lqr.max_eig_condition)
        assert f[f"points/{k}/robustness_radius"].attrs["units"] == "1"
    assert np.array_equal(table.gain[0], r.points[0].lqr.K)
    _, note = design_for(cfg)
    assert note.startswith("reused")
    # a design-relevant change invalidates the cached design
    cfg2 = cfg.model_copy(update={"design": cfg.design.model_copy(update={"R": 2e-4})})
    _, note2 = design_for(cfg2)
    assert note2.startswith("designed")


def test_config_q0_is_a_weight_on_the_scaled_states():
    """design.Q0 = q means Q̃ = q·I on x̃ = D⁻¹x: the returned physical Q satisfies D Q D ⪰ q I
    (pole shifting only adds positive semidefinite terms)."""
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs

    cfg = load_config("ac")
    cfg = cfg.model_copy(update={"design": cfg.design.model_copy(
        update={"Q0": 1e-3, "Q0_groups": None, "min_margin": 0.01})})
    p = design_one(point_specs(cfg)[0], design_settings(cfg))
    d = p.model.scales
    q_scaled = p.lqr.Q * d[:, None] * d[None, :]
    assert np.linalg.eigvalsh(0.5 * (q_scaled + q_scaled.T) - 1e-3 * np.eye(24)).min() > -1e-9
    assert np.linalg.eigvalsh(q_scaled).max() < 10.0      # not the 1/d² blow-up of a physical q·I


def test_config_q0_groups_are_diagonal_weights_on_the_scaled_states():
    """Q0_groups = per-group diagonal on x̃ = D⁻¹x: D Q D − diag(groups) ⪰ 0 (pole shifting only
    adds positive semidefinite terms), and the groups sit on the right states."""
    from acmm.io.config import Q0Groups
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs

    g = Q0Groups(rates=1e-5, attitudes=2e-6, momentum=3e-6, momentum_integral=4e-5, drf=5e-7)
    np.testing.assert_array_equal(g.diagonal()[[0, 3, 6, 9, 12, 23]], [1e-5, 2e-6, 3e-6, 4e-5, 5e-7, 5e-7])
    cfg = load_config("ac")
    cfg = cfg.model_copy(update={"design": cfg.design.model_copy(update={"Q0_groups": g})})
    p = design_one(point_specs(cfg)[0], design_settings(cfg))
    d = p.model.scales
    q_scaled = p.lqr.Q * d[:, None] * d[None, :]
    q_scaled = 0.5 * (q_scaled + q_scaled.T)
    assert np.linalg.eigvalsh(q_scaled - np.diag(g.diagonal())).min() > -1e-9 * np.abs(q_scaled).max()


@pytest.mark.parametrize("spacing", ["tea", "blend"])
def test_a_blend_whose_end_is_on_another_branch_of_equilibria_is_flagged(tmp_runs, run_acmm, spacing):
    """TEA-spaced points follow the branch continued from the start (it reaches −35° at the end
    station); the end station asks for −55° (bias_from_tea), a root of another branch: the points
    jumped −36.25° → −55° and a polynomial was fitted across the jump without a word (a review's
    case).  The end keeps its asked TEA (test_tea: the schedule's end gets its asked attitude);
    the design says so, and --strict fails it."""
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
        f"disturbance: {{bias_from_tea: [0, -55.0, 0]}}}}\n  n_points: 5\n  spacing: {spacing}\n"
        "output: {figures: false}\n")
    r = run_acmm("design", "fold.yaml")
    assert r.exit_code == 0, r.output         # the end keeps the TEA it asks for (a result) ...
    assert "warning: the end station's TEA [+0.00, -55.00, +0.00] deg (as asked) is not on the branch" in r.stdout
    assert "fitted across the jump" in r.stdout
    branch = re.search(r"which reaches \[([^]]*)\] deg there", r.stdout).group(1)
    assert np.allclose([float(x) for x in branch.split(",")], np.degrees(t), atol=0.006)
    r = run_acmm("design", "fold.yaml", "--strict")
    assert r.exit_code == 1 and "another branch of equilibria" in r.output      # ... failed by --strict


def test_table_form_prints_the_check_that_strict_judges(tmp_runs, run_acmm):
    """schedule.form: table printed no check lines, yet --strict failed on the check's margin."""
    r = run_acmm("design", "staircase", "schedule.form=table", "schedule.fit=least_squares",
                 "schedule.n_points=4", "--no-figures")
    assert r.exit_code == 0, r.output
    assert "scheduled gain (table) on the local models" in r.stdout and "scheduled closed loops:" in r.stdout


@pytest.mark.parametrize("spacing", ["tea", "blend"])
def test_no_equilibrium_on_the_blend_names_the_blend(tmp_runs, run_acmm, spacing):
    """The message gave a blended bias the user never wrote and hinted at disturbance.bias only."""
    (tmp_runs / "s.yaml").write_text(
        "name: s\ninertia: {I11: 10.0e6, I22: 3.0e6, I33: 11.0e6}\norbit_rate: 0.0011\n"
        "disturbance: {bias_from_tea: [1.0, -30.0, 1.5]}\n"
        "schedule:\n  to: {name: endst, inertia: {I11: 30.0e6, I22: 9.0e6, I33: 36.0e6}, "
        f"disturbance: {{bias: [0, 500, 0]}}}}\n  n_points: 5\n  spacing: {spacing}\noutput: {{figures: false}}\n")
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

    cfg = load_config("staircase")
    n = cfg.orbit_rate
    specs = point_specs(cfg)
    teas = [compute_design(cfg).points[k].tea.theta for k in range(len(specs))]
    assert off_branch_point(specs, teas, n) is None
    blend = [p for p in specs if np.isfinite(p.s)]
    i0, i1 = blend[0].inertia[0, 0], blend[-1].inertia[0, 0]
    real = tea_mod.solve_tea_near

    def folds_at_0_6(inertia, n_, bias, guess, **kw):          # no equilibrium beyond s = 0.6
        if (inertia[0, 0] - i0) / (i1 - i0) > 0.6:
            from acmm_qpp.errors import NoEquilibriumError
            raise NoEquilibriumError("folds")
        return real(inertia, n_, bias, guess, **kw)

    monkeypatch.setattr(sp_mod, "_TRACKS", {})
    monkeypatch.setattr(sp_mod, "solve_tea_near", folds_at_0_6)
    jump = off_branch_point(specs, teas, n)
    first_beyond = next(p for p in blend if p.s > 0.6)
    assert jump is not None and jump.name == first_beyond.name and jump.branch is None
