"""Torque-equilibrium attitude (CR-185644 eqs 4.1-4.3, Table 1).

Residuals and the largest pitch bias are re-computed here from an independently built
direction-cosine matrix, never through the module's own residual or fold search.
"""
from __future__ import annotations

import functools
import re

import numpy as np
import pytest
from scipy.optimize import fsolve, minimize_scalar

from acmm.model import tea
from acmm.io.config import Disturbance
from acmm.io.config import load_config
from acmm.model.tea import NoEquilibriumError
from acmm.stages.runners import _compute_tea
from acmm.design.schedule_points import point_specs
from acmm.model.inertia import perturb_inertia, unphysical_reason
from acmm_qpp.errors import AcmmError

from tests.conftest import CONFIGS, LQR_ROUTE
from tests.acmm.model.conftest import tea_continuation_np

N = 0.0011
TABLE1 = {"mb3": (1.3, -44.7, 2.1), "ac": (0.19, -5.0, 0.56)}
MB3_INERTIA = np.array([[23.22e6, -0.023e6, 0.477e6],
                        [-0.023e6, 1.30e6, -0.011e6],
                        [0.477e6, -0.011e6, 23.23e6]])
AC_INERTIA = np.array([[50.28e6, -0.39e6, 0.16e6],
                       [-0.39e6, 10.80e6, 0.16e6],
                       [0.16e6, 0.16e6, 58.57e6]])


def _rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    m = np.eye(3)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = s, -s
    return m


def dcm(theta):
    """C_BL = C1(θ1) C3(θ3) C2(θ2), built here independently of acmm.model.dynamics."""
    return _rot(0, theta[0]) @ _rot(2, theta[2]) @ _rot(1, theta[1])


def residual_ref(theta, inertia, n, bias):
    """Eq 4.1 with ω* = C_BL(0, −n, 0) and c = C_BL e3 (independent of acmm)."""
    c = dcm(theta)
    om = c @ [0.0, -n, 0.0]
    nadir = c[:, 2]
    return -np.cross(om, inertia @ om) + 3 * n**2 * np.cross(nadir, inertia @ nadir) + bias


# ----------------------------------------------------------------- Table 1
def test_shipped_configs_carry_table1_inertia():
    for name, ref in (("mb3", MB3_INERTIA), ("ac", AC_INERTIA)):
        cfg = load_config(CONFIGS / f"{name}.yaml")
        np.testing.assert_array_equal(cfg.inertia.matrix(), ref)
        assert cfg.orbit_rate == N
        assert cfg.disturbance.A == [1.0, 2.0, 1.0]
        assert cfg.disturbance.B == [0.5, 0.5, 0.5]


@pytest.mark.parametrize("name", ["mb3", "ac"])
def test_tea_reproduces_table1(name):
    result = _compute_tea(CONFIGS / f"{name}.yaml")
    t = result.tea
    np.testing.assert_allclose(t.theta_deg, TABLE1[name], atol=0.01)
    assert t.residual < 1e-10
    inertia = result.config.inertia.matrix()
    # independent residual at the returned θ* with the returned bias
    assert np.abs(residual_ref(t.theta, inertia, N, t.bias)).max() < 1e-10
    np.testing.assert_allclose(t.omega, dcm(t.theta) @ [0, -N, 0], atol=1e-18)
    np.testing.assert_allclose(np.degrees(t.theta), t.theta_deg, rtol=1e-15)


@pytest.mark.parametrize("name", ["mb3", "ac"])
def test_bias_from_tea_balances_table1_attitude(name):
    cfg = load_config(CONFIGS / f"{name}.yaml")
    inertia = cfg.inertia.matrix()
    bias = tea.resolve_bias(cfg.disturbance, inertia, cfg.orbit_rate)
    th = np.radians(TABLE1[name])
    assert np.abs(residual_ref(th, inertia, N, bias)).max() < 1e-12
    assert np.abs(bias).max() > 1e-2  # a real, non-zero bias


def test_mb3_zero_bias_pitch_is_inertia_alone():
    t = tea.solve_tea(MB3_INERTIA, N, np.zeros(3))
    assert t.theta_deg[1] == pytest.approx(-44.70, abs=0.005)
    assert np.abs(residual_ref(t.theta, MB3_INERTIA, N, np.zeros(3))).max() < 1e-10
    # with no bias the equilibrium aligns the principal axes with LVLH: C^T I C is diagonal
    lvlh_inertia = dcm(t.theta).T @ MB3_INERTIA @ dcm(t.theta)
    off = lvlh_inertia - np.diag(np.diag(lvlh_inertia))
    assert np.abs(off).max() < 1e-9 * np.abs(MB3_INERTIA).max()


def test_mb3_zero_bias_all_equilibria_has_both_principal_alignments():
    roots = tea.all_equilibria(MB3_INERTIA, N, np.zeros(3))
    pitches = [r.theta_deg[1] for r in roots]
    assert any(abs(p + 44.70) < 0.005 for p in pitches), pitches
    assert any(abs(p - 45.30) < 0.005 for p in pitches), pitches
    for r in roots:
        assert np.abs(residual_ref(r.theta, MB3_INERTIA, N, np.zeros(3))).max() < 1e-10
    norms = [np.linalg.norm(r.theta) for r in roots]
    assert norms == sorted(norms)
    # the +45.30° root is the other principal alignment, 90° away in pitch
    p_minus = min(pitches, key=lambda p: abs(p + 44.70))
    p_plus = min(pitches, key=lambda p: abs(p - 45.30))
    assert p_plus - p_minus == pytest.approx(90.0, abs=1e-6)


def test_diagonal_body_zero_bias_is_lvlh():
    t = tea.solve_tea(np.diag(np.diag(AC_INERTIA)), N, np.zeros(3))
    np.testing.assert_array_equal(t.theta, np.zeros(3))


def test_diagonal_body_pitch_bias_matches_closed_form():
    """Pure pitch: 3n²(I33 − I11) sin θ2 cos θ2 + b = 0 (roll, yaw stay zero)."""
    inertia = np.diag(np.diag(AC_INERTIA))
    b = 2.0
    t = tea.solve_tea(inertia, N, np.array([0.0, b, 0.0]))
    expected = 0.5 * np.arcsin(-b / (1.5 * N**2 * (inertia[2, 2] - inertia[0, 0])))
    assert t.theta[1] == pytest.approx(expected, abs=1e-12)
    np.testing.assert_allclose(t.theta[[0, 2]], 0.0, atol=1e-12)


def test_solve_tea_is_reproducible():
    bias = tea.resolve_bias(load_config(CONFIGS / "mb3.yaml").disturbance, MB3_INERTIA, N)
    a = tea.solve_tea(MB3_INERTIA, N, bias)
    b = tea.solve_tea(MB3_INERTIA, N, bias)
    np.testing.assert_array_equal(a.theta, b.theta)


# ----------------------------------------------------------------- no equilibrium
@functools.lru_cache(maxsize=None)
def _max_pitch_bias_scan() -> float:
    """Largest positive pitch bias MB3's gravity gradient balances, by brute force.

    Scans pitch over a full turn (0.1° grid) with roll = yaw = 0, taking −τ_pitch from the
    independent residual (a pure pitch attitude has no gyroscopic pitch torque), then
    refines the best grid point with a bounded scalar search.
    """
    def neg_tau2(g):
        return -residual_ref(np.array([0.0, g, 0.0]), MB3_INERTIA, N, np.zeros(3))[1]

    grid = np.radians(np.arange(-180.0, 180.0, 0.1))
    vals = np.array([neg_tau2(g) for g in grid])
    g0 = grid[np.argmax(vals)]
    opt = minimize_scalar(lambda g: -neg_tau2(g), bounds=(g0 - 0.01, g0 + 0.01), method="bounded",
                          options={"xatol": 1e-10})
    return float(max(vals.max(), -opt.fun))


def _max_pitch_bias_roll_yaw_solved(g_lo, g_hi) -> float:
    """As above, but roll and yaw solved at each pitch so their residuals vanish."""
    def neg_tau2(g):
        def ry(v):
            r = residual_ref(np.array([v[0], g, v[1]]), MB3_INERTIA, N, np.zeros(3))
            return [r[0], r[2]]
        y = fsolve(ry, np.zeros(2), xtol=1e-13)
        return -residual_ref(np.array([y[0], g, y[1]]), MB3_INERTIA, N, np.zeros(3))[1]

    opt = minimize_scalar(lambda g: -neg_tau2(g), bounds=(g_lo, g_hi), method="bounded",
                          options={"xatol": 1e-9})
    return float(-opt.fun)


def test_mb3_gravity_gradient_pitch_capacity_is_about_1p73():
    scan = _max_pitch_bias_scan()
    # closed form for pure pitch: 3n² sqrt(((I33 − I11)/2)² + I13²)
    closed = 3 * N**2 * np.hypot((MB3_INERTIA[2, 2] - MB3_INERTIA[0, 0]) / 2, MB3_INERTIA[0, 2])
    assert scan == pytest.approx(closed, rel=1e-6)
    assert scan == pytest.approx(1.73, abs=0.005)
    refined = _max_pitch_bias_roll_yaw_solved(np.radians(-100.0), np.radians(-80.0))
    assert refined == pytest.approx(scan, rel=1e-3)


def test_mb3_4ftlbf_pitch_bias_has_no_equilibrium():
    scan = _max_pitch_bias_scan()
    with pytest.raises(NoEquilibriumError) as exc:
        tea.solve_tea(MB3_INERTIA, N, np.array([0.0, 4.0, 0.0]))
    msg = str(exc.value)
    assert "\n" not in msg
    m = re.search(r"folds\) at bias \[([^\]]+)\]", msg)
    assert "no other equilibrium lies within" in msg
    assert m, msg
    largest = np.array([float(x) for x in m.group(1).split(",")])
    np.testing.assert_allclose(largest[[0, 2]], 0.0, atol=1e-12)
    assert largest[1] == pytest.approx(scan, rel=2e-3), (msg, scan)


def test_bias_fold_is_the_fraction_the_error_names():
    """tea.bias_fold: the fold's fraction of the bias, as NoEquilibriumError prints it, and None
    where the whole bias has an equilibrium."""
    bias = np.array([0.0, 4.0, 0.0])
    lam = tea.bias_fold(MB3_INERTIA, N, bias)
    with pytest.raises(NoEquilibriumError) as exc:
        tea.solve_tea(MB3_INERTIA, N, bias)
    assert 0.0 < lam < 1.0 and str(exc.value).startswith(tea._fold_message(bias, lam))
    assert lam * 4.0 == pytest.approx(_max_pitch_bias_scan(), rel=2e-3)
    assert tea.bias_fold(MB3_INERTIA, N, 0.3 * bias) is None        # 1.2 ft·lbf, below the capacity


def test_mb3_pitch_bias_just_inside_capacity_has_equilibrium():
    scan = _max_pitch_bias_scan()
    bias = np.array([0.0, 0.97 * scan, 0.0])
    t = tea.solve_tea(MB3_INERTIA, N, bias)
    assert np.abs(residual_ref(t.theta, MB3_INERTIA, N, bias)).max() < 1e-10
    with pytest.raises(NoEquilibriumError):
        tea.solve_tea(MB3_INERTIA, N, np.array([0.0, 1.03 * scan, 0.0]))


# ----------------------------------------------------------------- resolve_bias, Jacobian
def test_resolve_bias_variants():
    np.testing.assert_array_equal(tea.resolve_bias(Disturbance(), MB3_INERTIA, N), np.zeros(3))
    np.testing.assert_array_equal(
        tea.resolve_bias(Disturbance(bias=[0.5, -1.0, 2.0]), MB3_INERTIA, N), [0.5, -1.0, 2.0])
    th = [3.0, -20.0, -4.0]
    b = tea.resolve_bias(Disturbance(bias_from_tea=th), MB3_INERTIA, N)
    assert np.abs(residual_ref(np.radians(th), MB3_INERTIA, N, b)).max() < 1e-12
    np.testing.assert_allclose(tea.bias_for_attitude(np.radians(th), MB3_INERTIA, N), b, rtol=0, atol=0)


@pytest.mark.parametrize("seed", range(6))
def test_equilibrium_jacobian_against_central_differences(seed):
    rng = np.random.default_rng(seed)
    j = rng.uniform(0.3, 1.0, 3) * 3e7
    j[2] = min(j[2], 0.99 * (j[0] + j[1]))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    inertia = q @ np.diag(j) @ q.T
    th = np.radians(rng.uniform(-70, 70, 3))
    bias = rng.normal(size=3)
    h = 1e-3
    cols = []
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        f = lambda x: residual_ref(x, inertia, N, bias)  # noqa: E731
        cols.append((-f(th + 2 * e) + 8 * f(th + e) - 8 * f(th - e) + f(th - 2 * e)) / (12 * h))
    ref = np.array(cols).T
    scale = 3 * N**2 * np.abs(inertia).max()
    np.testing.assert_allclose(tea.equilibrium_jacobian(th, inertia, N), ref, atol=1e-10 * scale)
    np.testing.assert_allclose(tea.equilibrium_residual(th, inertia, N, bias),
                               residual_ref(th, inertia, N, bias), atol=1e-12 * scale)


# ----------------------------------------------------------------- stations the continuation cannot follow
def test_symmetric_station_i11_equal_i33_finds_the_nearest_equilibrium():
    # I11 = I33: every pitch balances the diagonal body, so the continuation has no start; the
    # products then put the principal axes at ±45° in pitch.  The TEA is the equilibrium of
    # smallest |θ|: an exact root (independent residual) at ±45° pitch, the nearer one.
    inertia = MB3_INERTIA.copy()
    inertia[2, 2] = inertia[0, 0]
    t = tea.solve_tea(inertia, N, np.zeros(3))
    scale = 3 * N**2 * np.abs(inertia).max()
    assert np.max(np.abs(residual_ref(t.theta, inertia, N, np.zeros(3)))) < 1e-12 * scale
    assert abs(abs(np.degrees(t.theta[1])) - 45.0) < 0.01
    roots = [fsolve(residual_ref, np.radians([0, p, 0]), args=(inertia, N, np.zeros(3)), xtol=1e-13)
             for p in (-45.0, 45.0)]
    assert np.linalg.norm(t.theta) <= min(np.linalg.norm(r) for r in roots) + 1e-9


def test_station_whose_branch_leaves_the_range_finds_the_lvlh_near_root():
    # principal axes ~3° off the body axes with I11 ≈ I33: the continuation in the products
    # turns past ±89.5° before reaching the full products, while an exact equilibrium lies
    # within 3° of LVLH (found independently by fsolve from LVLH)
    inertia = np.array([[14764757., 377503., 17488.], [377503., 26536835., 545632.],
                        [17488., 545632., 14775172.]])
    ref = fsolve(residual_ref, np.zeros(3), args=(inertia, N, np.zeros(3)), xtol=1e-13)
    t = tea.solve_tea(inertia, N, np.zeros(3))
    np.testing.assert_allclose(t.theta, ref, atol=1e-9)
    assert np.max(np.abs(np.degrees(t.theta))) < 3.0


@pytest.mark.parametrize("asked", [(0.0, 20.0, 0.0), (0.62, 3.39, 4.14), (-5.0, -60.0, 10.0)])
def test_bias_from_tea_gives_the_asked_attitude(asked):
    # the bias of bias_from_tea makes the asked attitude an exact equilibrium; the continuation
    # from LVLH may end on another root (MB3 with pitch +20°: −19.4°), so the stage's TEA is the
    # asked one, and the design's first point is designed about it
    cfg = load_config(CONFIGS / "mb3.yaml", [f"disturbance.bias_from_tea=[{asked[0]},{asked[1]},{asked[2]}]"])
    t = _compute_tea(cfg).tea
    np.testing.assert_allclose(np.degrees(t.theta), asked, atol=1e-9)
    assert np.max(np.abs(residual_ref(t.theta, cfg.inertia.matrix(), N, t.bias))) < 1e-9
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs
    from acmm.design.settings import design_settings

    spec = point_specs(cfg)[0]
    np.testing.assert_allclose(np.degrees(design_one(spec, design_settings(cfg)).tea.theta), asked, atol=1e-9)
    # the Python API's linear model too (it used to continue from LVLH to the other root)
    import acmm.api

    np.testing.assert_allclose(np.degrees(acmm.api.linearize(cfg).theta_star), asked, atol=1e-9)


def test_schedule_end_point_gets_its_asked_attitude():
    # the `to` station of a TEA-spaced schedule is designed about the TEA its bias_from_tea asks
    # for, even though its starting guess comes from the blend's track (which ends elsewhere)
    from acmm.design.schedule import design_one
    from acmm.design.schedule_points import point_specs
    from acmm.design.settings import design_settings

    cfg = load_config(CONFIGS / "staircase.yaml", [*LQR_ROUTE, "schedule.to.disturbance.bias_from_tea=[0,-60,0]"])
    end = point_specs(cfg)[-1]
    assert end.theta_guess is not None and abs(np.degrees(end.theta_guess[1]) + 60) > 5
    t = design_one(end, design_settings(cfg)).tea
    np.testing.assert_allclose(np.degrees(t.theta), [0.0, -60.0, 0.0], atol=1e-9)
    assert np.max(np.abs(residual_ref(t.theta, end.inertia, N, end.bias))) < 1e-9


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1e3])
def test_tea_is_scale_invariant(scale):
    """Eq 4.1 is homogeneous in (I, bias): a station scaled by any factor has the same TEA (a
    residual tolerance absolute in ft·lbf accepted a 3 % residual at 1e-12 and a TEA 9° off)."""
    inertia = np.array([[5e6, 0.3e6, -0.5e6], [0.3e6, 2e6, 0.2e6], [-0.5e6, 0.2e6, 6e6]])
    bias, n = np.array([0.3, -0.5, 0.2]), 0.00113
    ref = fsolve(residual_ref, np.zeros(3), args=(inertia, n, bias), xtol=1e-14)
    for solver in (tea.solve_tea, tea.solve_tea_fast):
        t = solver(inertia * scale, n, bias * scale)
        np.testing.assert_allclose(t.theta, ref, atol=1e-10)
        assert np.max(np.abs(residual_ref(t.theta, inertia, n, bias))) < 1e-9


def test_a_fold_names_the_equilibria_of_other_branches():
    """The branch continued from LVLH folds at 5.6 % of this bias, but equilibria exist at the full
    bias on other branches: the refusal says so and names them (it used to say none exists)."""
    inertia = np.array([[2989922.6, -196292.5, 1371916.1], [-196292.5, 6311364.4, 81755.5],
                        [1371916.1, 81755.5, 5983482.4]])
    bias = np.array([-0.309042, 0.026471, 0.028073])
    root = fsolve(residual_ref, np.radians([18.0, -19.0, -11.0]), args=(inertia, 0.0011, bias), xtol=1e-14)
    assert np.max(np.abs(residual_ref(root, inertia, 0.0011, bias))) < 1e-9      # one exists
    with pytest.raises(NoEquilibriumError) as exc:
        tea.solve_tea(inertia, 0.0011, bias)
    msg = str(exc.value)
    assert "folds" in msg and "do exist" in msg and "\n" not in msg
    listed = [np.array([float(v) for v in m.split(",")]) for m in re.findall(r"\[([-\d., ]+)\]", msg.split("exist")[1])]
    assert any(np.max(np.abs(r - np.degrees(root))) < 1e-3 for r in listed), msg
    # naming it with bias_from_tea gives that attitude
    t = tea.solve_tea(inertia, 0.0011, tea.bias_for_attitude(root, inertia, 0.0011), expected=root)
    np.testing.assert_allclose(t.theta, root, atol=1e-9)


def test_axisymmetric_station_has_a_family_of_equilibria_not_none():
    """I11 = I22: the gravity gradient has no yaw stiffness, every yaw of a curve balances the
    bias and the Jacobian of eq 4.1 is singular there; the continuation failed and the station
    was reported to have no equilibrium (a review's case).  The member nearest LVLH is returned;
    an independent least-squares solve (scipy) confirms it is an equilibrium."""
    from scipy.optimize import least_squares

    from acmm.model.tea import equilibrium_jacobian, equilibrium_residual, solve_tea

    inertia, n, bias = np.diag([20e6, 20e6, 5e6]), 0.0011, np.array([0.1, 0.2, 0.0])
    t = solve_tea(inertia, n, bias)
    assert np.max(np.abs(equilibrium_residual(t.theta, inertia, n, bias))) < 1e-9
    sv = np.linalg.svd(equilibrium_jacobian(t.theta, inertia, n), compute_uv=False)
    assert sv[-1] < 1e-9 * sv[0]                                   # not isolated
    ref = least_squares(lambda th: equilibrium_residual(th, inertia, n, bias), np.zeros(3),
                        xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.max(np.abs(ref.fun)) < 1e-9
    # the family is a curve (roll and pitch move with yaw): ours is the member nearest LVLH
    assert np.linalg.norm(t.theta) <= np.linalg.norm(ref.x) + 1e-9 and abs(t.theta[2]) < 1e-6
    # the symmetry axis need not be a body axis: rotated, the products-of-inertia continuation
    # fails first (ConvergenceError), and the family is found all the same (review)
    from scipy.spatial.transform import Rotation

    for seed in range(3):
        R = Rotation.from_euler("xyz", np.random.default_rng(seed).uniform(-0.3, 0.3, 3)).as_matrix()
        rotated = R @ inertia @ R.T
        b = np.cross(R[:, 2], [0.0, 1.0, 0.0])
        b = 0.2 * b / np.linalg.norm(b)
        tr = solve_tea(rotated, n, b)
        assert np.max(np.abs(equilibrium_residual(tr.theta, rotated, n, b))) < 1e-9
    # the same station 1e-9 from axisymmetric has an isolated root, next to ours
    near = solve_tea(np.diag([20e6, 20e6 * (1 + 1e-9), 5e6]), n, bias)
    assert np.max(np.abs(equilibrium_residual(near.theta, inertia, n, bias))) < 1e-6


# ----------------------------------------------------------------- the continuation against its numpy oracle,
# and the continuation connected to a design TEA (sweeps)


def _outcome(fn, inertia, n, bias):
    try:
        return fn(inertia, n, bias).theta
    except AcmmError as exc:
        return f"{type(exc).__name__}: {exc}"


def _against_oracle(inertia, n, bias):
    """solve_tea_fast's outcome (θ, or the error) against :func:`tea_continuation_np`'s: the same root
    to 1e-12 rad, or the same fold at the same fraction of the bias (printed to 0.1 %)."""
    got = _outcome(tea.solve_tea_fast, inertia, n, bias)
    theta, status, lam = tea_continuation_np(inertia, n, bias)
    if status == 2:
        assert got == f"NoEquilibriumError: {tea._fold_message(bias, lam)}", got
    elif status == 0:
        assert not isinstance(got, str), got
        assert np.max(np.abs(got - theta)) <= 1e-12
        assert np.max(np.abs(residual_ref(got, inertia, n, bias))) <= 1e-11
    return got, status


def _perturbed(spec, rng):
    while True:
        d = rng.uniform(-0.3, 0.3, 6)
        f = np.array([[d[0], d[3], d[4]], [d[3], d[1], d[5]], [d[4], d[5], d[2]]])
        if unphysical_reason(spec.inertia * (1 + f)) is None:
            return spec.inertia * (1 + f)


@pytest.mark.parametrize("name", ["mb3", "ac", "staircase"])
def test_continuation_matches_its_numpy_oracle(name):
    """The compiled continuation finds the root (or the fold) the plain-numpy one does
    (``tests/acmm/model/conftest.py``): every design point of the config, and perturbed plants."""
    cfg = load_config(name)
    specs = point_specs(cfg)
    for spec in specs:
        _against_oracle(spec.inertia, cfg.orbit_rate, spec.bias)
    rng = np.random.default_rng(16)
    for _ in range(6):
        _against_oracle(_perturbed(specs[0], rng), cfg.orbit_rate, specs[0].bias)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mb3", "ac"])
def test_continuation_matches_its_numpy_oracle_on_perturbed_plants(name):
    cfg = load_config(name)
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    rng = np.random.default_rng(16)
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    far = folds = 0
    for _ in range(40):
        inertia = _perturbed(spec, rng)
        got, status = _against_oracle(inertia, n, spec.bias)
        folds += status == 2
        # a root far from the nominal TEA: Newton warm-started there may find another root
        far += status == 0 and np.max(np.abs(got - nominal)) > np.radians(5)
    assert far > 0 if name == "mb3" else folds > 0


def test_compiled_no_equilibrium_message_matches():
    cfg = load_config("mb3")
    inertia = cfg.inertia.matrix()
    bias = np.array([0.0, 4.0, 0.0])
    with pytest.raises(AcmmError) as ref:
        tea.solve_tea(inertia, cfg.orbit_rate, bias)
    with pytest.raises(AcmmError) as got:
        tea.solve_tea_fast(inertia, cfg.orbit_rate, bias)
    assert type(got.value) is type(ref.value) and str(ref.value).startswith(str(got.value))
    assert "no other equilibrium lies within ±85°" in str(ref.value)


def _fine_path(theta, i0, b0, i1, b1, n, steps=200):
    """An independent connected root: scipy's fsolve (MINPACK hybrd) from the previous root in
    `steps` equal small steps, continuity its only rule (no Jacobian test, no angle box); None
    when a step finds no root within 2° (the branch has folded)."""
    from scipy.optimize import fsolve

    scale = 3 * n * n * np.abs(i1).max()
    for lam in np.linspace(0, 1, steps + 1):
        inertia, bias = i0 + lam * (i1 - i0), b0 + lam * (b1 - b0)
        def f(t):
            return tea.equilibrium_residual(t, inertia, n, bias) / scale

        new = fsolve(f, theta, xtol=1e-13, full_output=True)[0]   # converged: judged by the residual
        if np.max(np.abs(f(new))) > 1e-13 or np.max(np.abs(new - theta)) > np.radians(2):
            return None
        theta = new
    return theta


@pytest.mark.parametrize("name", ["mb3", "ac"])
def test_connected_root_is_the_fine_continuation_of_the_design_tea(name):
    """A case's plant follows the equilibrium connected to the design TEA
    (:func:`acmm.model.tea.solve_tea_connected`): the same root as an independent fine-step
    numpy continuation, and None exactly where that one folds too."""
    cfg = load_config(name)
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    rng = np.random.default_rng(7)
    checked = agreed_none = differ_from_lvlh = 0
    while checked < 20:
        d = rng.uniform(-0.3, 0.3, 6)
        inertia = perturb_inertia(spec.inertia, dict(zip(["dI11", "dI22", "dI33", "dI12", "dI13", "dI23"], d)))
        if unphysical_reason(inertia) is not None:
            continue
        checked += 1
        got = tea.solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias)
        ref = _fine_path(nominal, spec.inertia, spec.bias, inertia, spec.bias, n)
        if ref is None or got is None:
            assert ref is None and got is None, (d, ref, got)
            agreed_none += 1
            continue
        np.testing.assert_allclose(got.theta, ref, atol=1e-8)
        assert np.max(np.abs(tea.equilibrium_residual(got.theta, inertia, n, spec.bias))) <= 1e-11
        lvlh = _outcome(tea.solve_tea_fast, inertia, n, spec.bias)
        differ_from_lvlh += isinstance(lvlh, str) or np.max(np.abs(lvlh - got.theta)) > np.radians(5)
    # MB3 (I11 ≈ I33): connected roots the LVLH continuation does not reach; AC: design branches
    # that fold (the pitch bias's equilibrium is lost as I33 − I11 shrinks)
    assert differ_from_lvlh > 0 if name == "mb3" else 0 < agreed_none < checked


def test_connected_root_moves_continuously_where_the_lvlh_root_flips():
    """MB3 with I33 0.5 % smaller: the root continued from LVLH flips ~86° to the other principal
    alignment (−44.7° → +41.8° pitch), the design-connected one moves 3.5° (−48.2°)."""
    cfg = load_config("mb3")
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    prev = nominal
    for d in np.linspace(0, -0.03, 31)[1:]:
        inertia = perturb_inertia(spec.inertia, {"dI33": d})
        got = tea.solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias).theta
        assert np.max(np.abs(got - prev)) < np.radians(1.5)
        prev = got
    inertia = perturb_inertia(spec.inertia, {"dI33": -0.005})
    lvlh = tea.solve_tea_fast(inertia, n, spec.bias).theta
    connected = tea.solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias).theta
    assert abs(np.degrees(lvlh[1] - nominal[1])) > 80
    np.testing.assert_allclose(connected, _fine_path(nominal, spec.inertia, spec.bias, inertia, spec.bias, n),
                               atol=1e-8)
    assert abs(np.degrees(connected[1] - nominal[1])) < 5
    # a guess that is no equilibrium of the nominal plant is refused, not continued
    assert tea.solve_tea_connected(nominal + np.radians(20), spec.inertia, spec.bias, inertia, n, spec.bias) is None


def test_connected_root_passes_a_pitchfork_of_a_symmetric_station():
    """A station symmetric about the orbit plane (I12 = I23 = 0, pitch bias only) keeps its
    pitch-only equilibrium while det ∂r/∂θ changes sign (roll/yaw stiffness changes sign: a
    pitchfork, not a fold); the connected root follows it (−60° → −65.0°), as the independent
    path does, instead of falling back to the LVLH root (−25°).  Random symmetric stations agree
    with the independent path too."""
    n = 0.0011
    i0, i1 = np.diag([7.2e6, 3.8e6, 4.9e6]), np.diag([6.2e6, 4.8e6, 3.6e6])
    th = np.radians([0.0, -60.0, 0.0])
    b0 = tea.bias_for_attitude(th, i0, n)
    got = tea.solve_tea_connected(th, i0, b0, i1, n, b0)
    np.testing.assert_allclose(got.theta, _fine_path(th, i0, b0, i1, b0, n), atol=1e-8)
    assert abs(np.degrees(got.theta[1]) + 65.0) < 0.01
    dets = [np.linalg.det(tea.equilibrium_jacobian(t, i, n))
            for t, i in ((th, i0), (got.theta, i1))]
    assert dets[0] * dets[1] < 0                  # the sign did change on the way
    # the same station with I23 = 40 slug·ft² (1e-5 relative) is no longer symmetric: its
    # pitchfork breaks, and the branch from −60° turns back at λ ≈ 0.478 (a pseudo-arclength
    # continuation, in review), leaving the plane (roll −0.001° at λ = 0.4, −0.03° at 0.475 on
    # the independent path); it is a fold, not a branch to step across
    j0, j1 = i0.copy(), i1.copy()
    j0[1, 2] = j0[2, 1] = j1[1, 2] = j1[2, 1] = 40.0
    bj = tea.bias_for_attitude(th, j0, n)
    assert tea.solve_tea_connected(th, j0, bj, j1, n, bj) is None
    lam = 0.475
    near = _fine_path(th, j0, bj, j0 + lam * (j1 - j0), bj, n, steps=950)
    assert abs(np.degrees(near[0])) > 0.02
    rng = np.random.default_rng(3)
    crossed = 0
    for _ in range(25):
        m0 = np.diag(rng.uniform(2e6, 9e6, 3))
        if unphysical_reason(m0) is not None:
            continue
        m1 = m0 * np.diag(1 + rng.uniform(-0.3, 0.3, 3))
        if unphysical_reason(m1) is not None:
            continue
        t0 = np.radians([0.0, rng.uniform(-70, 70), 0.0])
        b = tea.bias_for_attitude(t0, m0, n)
        got, ref = tea.solve_tea_connected(t0, m0, b, m1, n, b), _fine_path(t0, m0, b, m1, b, n)
        assert (got is None) == (ref is None), (np.diag(m0), np.diag(m1), t0)
        if got is not None:
            np.testing.assert_allclose(got.theta, ref, atol=1e-8)
            crossed += np.linalg.det(tea.equilibrium_jacobian(t0, m0, n)) * \
                np.linalg.det(tea.equilibrium_jacobian(got.theta, m1, n)) < 0
    assert crossed > 0


def test_connected_root_may_pass_90_degrees_of_pitch():
    """Only yaw ±90° is singular in the 2-3-1 sequence: MB3 with +1.8 ft·lbf of pitch bias and
    I33 3 % smaller has its design TEA's equilibrium at −91.6° pitch (the independent path agrees);
    it used to be called a fold and the case started at +55.8°."""
    cfg = load_config("mb3")
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    inertia = perturb_inertia(spec.inertia, {"dI33": -0.03})
    bias = spec.bias + np.array([0.0, 1.8, 0.0])
    got = tea.solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, bias)
    np.testing.assert_allclose(got.theta, _fine_path(nominal, spec.inertia, spec.bias, inertia, bias, n),
                               atol=1e-8)
    assert -92.0 < np.degrees(got.theta[1]) < -91.0
