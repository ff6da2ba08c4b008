"""The compiled TEA continuations of sweeps (issue 16): from LVLH, the root :func:`acmm.model.tea.solve_tea`
finds with the same errors; from the design TEA, the equilibrium connected to it (checked against
an independent fine-step continuation)."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.model import tea
from acmm.io.config import load_config
from acmm_qpp.errors import AcmmError
from acmm.design.schedule_points import point_specs
from acmm.model.inertia import perturb_inertia, unphysical_reason
from acmm.model.tea_compiled import solve_tea_fast


def _outcome(fn, inertia, n, bias):
    try:
        return fn(inertia, n, bias).theta
    except AcmmError as exc:
        return f"{type(exc).__name__}: {exc}"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mb3", "ac"])
def test_compiled_continuation_matches_solve_tea_on_perturbed_plants(name):
    cfg = load_config(name)
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    rng = np.random.default_rng(16)
    checked = far = 0
    while checked < 40:
        d = rng.uniform(-0.3, 0.3, 6)
        f = np.array([[d[0], d[3], d[4]], [d[3], d[1], d[5]], [d[4], d[5], d[2]]])
        inertia = spec.inertia * (1 + f)
        if unphysical_reason(inertia) is not None:
            continue
        checked += 1
        ref = _outcome(tea.solve_tea, inertia, n, spec.bias)
        got = _outcome(solve_tea_fast, inertia, n, spec.bias)
        if isinstance(ref, str):
            # same error, same fold (same bisection); solve_tea goes on to name the roots of other
            # branches (a grid search the sweep's per-case path does not pay for)
            assert isinstance(got, str) and ref.startswith(got), (ref, got)
            continue
        assert not isinstance(got, str)
        assert np.max(np.abs(got - ref)) <= 1e-12
        assert np.max(np.abs(tea.equilibrium_residual(got, inertia, n, spec.bias))) <= 1e-11
        # a root far from the nominal TEA: Newton warm-started there may find another root
        far += np.max(np.abs(ref - tea.solve_tea(spec.inertia, n, spec.bias).theta)) > np.radians(5)
    assert far > 0 if name == "mb3" else True


def test_compiled_no_equilibrium_message_matches():
    cfg = load_config("mb3")
    inertia = cfg.inertia.matrix()
    bias = np.array([0.0, 4.0, 0.0])
    with pytest.raises(AcmmError) as ref:
        tea.solve_tea(inertia, cfg.orbit_rate, bias)
    with pytest.raises(AcmmError) as got:
        solve_tea_fast(inertia, cfg.orbit_rate, bias)
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
    (:func:`acmm.model.tea_compiled.solve_tea_connected`): the same root as an independent fine-step
    numpy continuation, and None exactly where that one folds too."""
    from acmm.model.tea_compiled import solve_tea_connected

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
        got = solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias)
        ref = _fine_path(nominal, spec.inertia, spec.bias, inertia, spec.bias, n)
        if ref is None or got is None:
            assert ref is None and got is None, (d, ref, got)
            agreed_none += 1
            continue
        np.testing.assert_allclose(got.theta, ref, atol=1e-8)
        assert np.max(np.abs(tea.equilibrium_residual(got.theta, inertia, n, spec.bias))) <= 1e-11
        lvlh = _outcome(solve_tea_fast, inertia, n, spec.bias)
        differ_from_lvlh += isinstance(lvlh, str) or np.max(np.abs(lvlh - got.theta)) > np.radians(5)
    # MB3 (I11 ≈ I33): connected roots the LVLH continuation does not reach; AC: design branches
    # that fold (the pitch bias's equilibrium is lost as I33 − I11 shrinks)
    assert differ_from_lvlh > 0 if name == "mb3" else 0 < agreed_none < checked


def test_connected_root_moves_continuously_where_the_lvlh_root_flips():
    """MB3 with I33 0.5 % smaller: the root continued from LVLH flips ~86° to the other principal
    alignment (−44.7° → +41.8° pitch), the design-connected one moves 3.5° (−48.2°)."""
    from acmm.model.tea_compiled import solve_tea_connected

    cfg = load_config("mb3")
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    prev = nominal
    for d in np.linspace(0, -0.03, 31)[1:]:
        inertia = perturb_inertia(spec.inertia, {"dI33": d})
        got = solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias).theta
        assert np.max(np.abs(got - prev)) < np.radians(1.5)
        prev = got
    inertia = perturb_inertia(spec.inertia, {"dI33": -0.005})
    lvlh = solve_tea_fast(inertia, n, spec.bias).theta
    connected = solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, spec.bias).theta
    assert abs(np.degrees(lvlh[1] - nominal[1])) > 80
    np.testing.assert_allclose(connected, _fine_path(nominal, spec.inertia, spec.bias, inertia, spec.bias, n),
                               atol=1e-8)
    assert abs(np.degrees(connected[1] - nominal[1])) < 5
    # a guess that is no equilibrium of the nominal plant is refused, not continued
    assert solve_tea_connected(nominal + np.radians(20), spec.inertia, spec.bias, inertia, n, spec.bias) is None


def test_connected_root_passes_a_pitchfork_of_a_symmetric_station():
    """A station symmetric about the orbit plane (I12 = I23 = 0, pitch bias only) keeps its
    pitch-only equilibrium while det ∂r/∂θ changes sign (roll/yaw stiffness changes sign: a
    pitchfork, not a fold); the connected root follows it (−60° → −65.0°), as the independent
    path does, instead of falling back to the LVLH root (−25°).  Random symmetric stations agree
    with the independent path too."""
    from acmm.model.tea_compiled import solve_tea_connected

    n = 0.0011
    i0, i1 = np.diag([7.2e6, 3.8e6, 4.9e6]), np.diag([6.2e6, 4.8e6, 3.6e6])
    th = np.radians([0.0, -60.0, 0.0])
    b0 = tea.bias_for_attitude(th, i0, n)
    got = solve_tea_connected(th, i0, b0, i1, n, b0)
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
    assert solve_tea_connected(th, j0, bj, j1, n, bj) is None
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
        got, ref = solve_tea_connected(t0, m0, b, m1, n, b), _fine_path(t0, m0, b, m1, b, n)
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
    from acmm.model.tea_compiled import solve_tea_connected

    cfg = load_config("mb3")
    spec = point_specs(cfg)[0]
    n = cfg.orbit_rate
    nominal = tea.solve_tea(spec.inertia, n, spec.bias).theta
    inertia = perturb_inertia(spec.inertia, {"dI33": -0.03})
    bias = spec.bias + np.array([0.0, 1.8, 0.0])
    got = solve_tea_connected(nominal, spec.inertia, spec.bias, inertia, n, bias)
    np.testing.assert_allclose(got.theta, _fine_path(nominal, spec.inertia, spec.bias, inertia, bias, n),
                               atol=1e-8)
    assert -92.0 < np.degrees(got.theta[1]) < -91.0
