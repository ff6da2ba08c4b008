"""The minimax refit of a polynomial schedule (acmm.design.schedule_refit, ``schedule.fit: minimax``)
on a constructed path whose optimum is known: every local model has an input-free mode at
−0.3n, so no gain puts the largest Re λ below −0.3n, and a quadratic gain that does reach it exists.
The refit must get there from a weak start, never rise on the way, and say why it stopped; the
worst pole is recomputed here from the stored coefficients with numpy's polyval and eigvals."""
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design import schedule as sch
from acmm.design.path_check import PathModels
from acmm.design.schedule_refit import MINIMAX_DEFAULTS, refit_closed_loop

N_RATE = 1.0            # orbital rate of the constructed path (the refit works in units of n)
FLOOR = -0.3            # the input-free mode, units of n


def _path(count: int = 41) -> PathModels:
    """A 5-state, 3-input path over θ ∈ [−0.6, −0.2] rad: a controllable 4-state block that
    drifts with θ (open-loop unstable) and an input-free mode at FLOOR."""
    theta = np.linspace(-0.6, -0.2, count)
    A = np.zeros((count, 5, 5))
    B = np.zeros((count, 5, 3))
    for k, t in enumerate(theta):
        A[k, :4, :4] = np.array([[0.0, 1.0, 0.0, 0.0], [0.4 + t, 0.1, 0.3 * t, 0.0],
                                 [0.0, 0.0, 0.0, 1.0], [0.2, 0.0, -0.5 - t, 0.05]])
        A[k, 4, 4] = FLOOR
        B[k, :4] = np.array([[0.0, 0.0, 0.1], [1.0, 0.2 * t, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.3]])
    return PathModels(theta, np.linspace(0, 1, count), A, B, np.ones(5))


def _weak_start(path: PathModels) -> sch.ScheduleFit:
    """Least-squares quadratic of cheap-control-averse LQR gains (R = 400 I) at 5 points: stable,
    but its slowest controllable pole lies right of the floor."""
    idx = np.linspace(0, path.theta2.size - 1, 5).round().astype(int)
    gains = [sla.solve(400 * np.eye(3), path.B[j].T @ sla.solve_continuous_are(path.A[j], path.B[j], np.eye(5),
                                                                               400 * np.eye(3)))
             for j in idx]
    return sch.fit_schedule(path.theta2[idx], np.array(gains), 2, "polynomial")


def _worst(path: PathModels, coef: np.ndarray, block=slice(None)) -> float:
    worst = -np.inf
    for A, B, t in zip(path.A, path.B, path.theta2):
        K = np.array([[np.polyval(coef[::-1, i, j], t) for j in range(5)] for i in range(3)])
        worst = max(worst, np.linalg.eigvals((A - B @ K)[block, block]).real.max())
    return worst / N_RATE


def test_minimax_refit_reaches_the_floor_no_gain_can_pass():
    path = _path()
    start = _weak_start(path)
    before = _worst(path, start.coef)
    assert FLOOR < before < 0            # a stable start that leaves room to the floor
    fit = refit_closed_loop(start, path, N_RATE, **MINIMAX_DEFAULTS)
    info = fit.refit_info
    assert fit.method == "minimax" and info["accepted"] and info["converged"]
    assert info["max_real_before"] == pytest.approx(before, abs=1e-9)
    # the controllable block moved left of the floor at every TEA: the worst pole is the floor itself
    assert _worst(path, fit.coef, slice(0, 4)) <= FLOOR + 1e-6
    assert _worst(path, fit.coef) == pytest.approx(FLOOR, abs=1e-9)
    assert info["max_real_after"] == pytest.approx(_worst(path, fit.coef), abs=1e-9)


def test_minimax_refit_keeps_a_start_it_cannot_improve():
    """A start already at the floor is returned as it is (least squares), the refit recorded as
    not accepted."""
    path = _path()
    start = refit_closed_loop(_weak_start(path), path, N_RATE, **MINIMAX_DEFAULTS)
    again = refit_closed_loop(sch.ScheduleFit(start.coef, start.variable, start.gains, start.rms_residual,
                                              start.rel_residual, "polynomial"), path, N_RATE, **MINIMAX_DEFAULTS)
    assert not again.refit_info["accepted"] and again.method == "least_squares"
    np.testing.assert_array_equal(again.coef, start.coef)


def test_minimax_refit_models_the_largest_real_part_only():
    path = _path(9)
    with pytest.raises(ValueError, match="largest Re λ alone"):
        refit_closed_loop(_weak_start(path), path, N_RATE, **{**MINIMAX_DEFAULTS, "angle_weight": 0.7})
