"""The converged quadratic schedule (acmm.design.schedule_shifted_lqr, ``schedule.fit: shifted_lqr``)
on a constructed 5-state path whose least-squares start is unstable.

What is checked independently of the module: the region (every pole of every path TEA's loop,
recomputed from the stored coefficients with numpy's polyval and eigvals, has Re λ < −α n and
lies in the cone), and that the answer is the minimizer of the documented function F — its
directional derivatives, by central differences of F written here with Kronecker-product
Lyapunov solves (not scipy's Bartels–Stewart), vanish, and F rises in every probed direction."""
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design import schedule as sch
from acmm.design.path_check import PathModels
from acmm.design.schedule_shifted_lqr import _ShiftedCost, _power_basis, _refit_start, refit_shifted_lqr

N_RATE = 1.0            # orbital rate of the constructed path (the refit works in units of n)
DECAY, CONE, WEIGHT = 0.3, 70.0, 1e-2
Q = np.diag([0.5, 0.0, 0.2, 0.0, 0.1])
R = 0.5 * np.eye(3)


def _path(count: int = 21, floor: float | None = None) -> PathModels:
    """A 5-state, 3-input path over θ ∈ [−0.6, −0.2] rad, open-loop unstable and drifting with θ;
    with ``floor`` the fifth state is an input-free mode at ``floor``·n."""
    theta = np.linspace(-0.6, -0.2, count)
    A = np.zeros((count, 5, 5))
    B = np.zeros((count, 5, 3))
    for k, t in enumerate(theta):
        A[k] = np.array([[0.0, 1.0, 0.0, 0.0, 0.0], [0.4 + t, 0.1, 0.3 * t, 0.0, 0.1],
                         [0.0, 0.0, 0.0, 1.0, 0.0], [0.2, 0.0, -0.5 - t, 0.05, 0.0],
                         [0.0, 0.0, 0.1, 0.0, 0.2 + t]])
        B[k] = np.array([[0.0, 0.0, 0.1], [1.0, 0.2 * t, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.3],
                         [0.0, 0.5, 1.0]])
        if floor is not None:
            A[k, 4] = 0.0
            A[k, 4, 4] = floor
            B[k, 4] = 0.0
    return PathModels(theta, np.linspace(0, 1, count), A, B, np.ones(5))


def _start(path: PathModels) -> sch.ScheduleFit:
    """Least-squares quadratic of LQR gains (Q = I, R = I) at 5 points with their sign reversed:
    gains of the right size whose loop is unstable."""
    idx = np.linspace(0, path.theta2.size - 1, 5).round().astype(int)
    gains = [-path.B[j].T @ sla.solve_continuous_are(path.A[j], path.B[j], np.eye(5), np.eye(3)) for j in idx]
    return sch.fit_schedule(path.theta2[idx], np.array(gains), 2, "polynomial")


def _poles(path: PathModels, coef: np.ndarray) -> np.ndarray:
    out = []
    for A, B, t in zip(path.A, path.B, path.theta2):
        K = np.array([[np.polyval(coef[::-1, i, j], t) for j in range(5)] for i in range(3)])
        out.append(np.linalg.eigvals(A - B @ K))
    return np.array(out) / N_RATE


def _lyap_trace(M: np.ndarray, W: np.ndarray) -> float:
    """tr P with Mᴴ P + P M + W = 0, by the Kronecker form (vec P column-wise)."""
    n = M.shape[0]
    op = np.kron(np.eye(n), M.conj().T) + np.kron(M.T, np.eye(n))
    P = np.linalg.solve(op, -W.reshape(-1, order="F")).reshape(n, n, order="F")
    return float(np.trace(P).real)


def _F(path: PathModels, start: sch.ScheduleFit, coef: np.ndarray, cone: float = CONE) -> float:
    """F of the module docstring at θ-power coefficients ``coef``: log of the mean over the path's
    TEAs of tr P (shifted LQR) + tr P_c (the cone's rotated Lyapunov equation), plus (ε/2)‖x‖²
    with x the change of the coefficients in u = (θ − c)/h from the start's, each in units of the
    largest of the start's coefficients of its element."""
    th = path.theta2
    c, h = 0.5 * (th.max() + th.min()), 0.5 * (th.max() - th.min())
    # coefficients in u: sample each quadratic at u = −1, 0, 1 and solve the Vandermonde system
    us = np.array([-1.0, 0.0, 1.0])
    vu = us[:, None] ** np.arange(3)
    vt = (c + h * us)[:, None] ** np.arange(3)
    a = np.linalg.solve(vu, (vt @ coef.reshape(3, -1)))
    a0 = np.linalg.solve(vu, (vt @ start.coef.reshape(3, -1)))
    x = (a - a0) / np.maximum(np.abs(a0).max(axis=0), 1e-12)
    rot = np.exp(1j * np.radians(90.0 - cone))
    total = 0.0
    for A, B, t in zip(path.A, path.B, th):
        K = np.array([[np.polyval(coef[::-1, i, j], t) for j in range(5)] for i in range(3)])
        Ac = A - B @ K + DECAY * N_RATE * np.eye(5)
        total += _lyap_trace(Ac, np.eye(5) + Q + K.T @ R @ K)
        if cone < 90.0:
            total += _lyap_trace(rot * Ac, (np.eye(5) + Q).astype(complex))
    return np.log(total / th.size) + 0.5 * WEIGHT * float(np.sum(x ** 2))


def test_converged_quadratic_enters_the_region_from_an_unstable_start_and_is_the_minimizer():
    path = _path()
    start = _start(path)
    assert _poles(path, start.coef).real.max() > 0                  # the open loop: unstable
    fit = refit_shifted_lqr(start, path, N_RATE, Q, R, decay=DECAY, cone_deg=CONE, weight=WEIGHT)
    info = fit.refit_info
    assert fit.method == "shifted_lqr" and info["accepted"] and info["converged"]
    assert info["n_tea"] == path.theta2.size and info["max_real_before"] > 0
    lam = _poles(path, fit.coef) + DECAY
    assert lam.real.max() < 0                                          # Re λ < −α n at every TEA
    assert np.max(np.abs(lam.imag) / -lam.real) < np.tan(np.radians(CONE))   # inside the cone
    assert info["max_real_after"] == pytest.approx(lam.real.max() - DECAY, abs=1e-9)
    # the minimizer of F: no descent direction (central differences of F written here), and F
    # does not fall along any probed direction
    f0 = _F(path, start, fit.coef)
    rng = np.random.default_rng(7)
    scale = np.abs(fit.coef).max(axis=0, keepdims=True)
    for _ in range(6):
        d = rng.standard_normal(fit.coef.shape) * scale
        h = 1e-5
        fp, fm = _F(path, start, fit.coef + h * d), _F(path, start, fit.coef - h * d)
        assert abs(fp - fm) / (2 * h) < 1e-5
        assert min(fp, fm) >= f0 - 1e-12
    # the start is not stationary: the test above can fail
    d = rng.standard_normal(fit.coef.shape) * scale
    far = fit.coef + 0.05 * d
    assert abs(_F(path, start, far + 1e-5 * d) - _F(path, start, far - 1e-5 * d)) / 2e-5 > 1e-3


def test_a_region_no_gain_can_reach_returns_the_least_squares_fit_and_says_why():
    path = _path(floor=-0.2)            # an input-free mode right of −α n
    start = _start(path)
    fit = refit_shifted_lqr(start, path, N_RATE, Q, R, decay=DECAY, cone_deg=CONE, weight=WEIGHT)
    info = fit.refit_info
    assert fit.method == "least_squares" and not info["accepted"] and not info["converged"]
    np.testing.assert_array_equal(fit.coef, start.coef)
    assert "homotopy" in info["message"] and "0.3n" in info["message"]


def test_only_a_polynomial_is_refit():
    path = _path()
    idx = [0, 10, 20]
    table = sch.fit_schedule(path.theta2[idx], np.zeros((3, 3, 5)), 2, "table")
    with pytest.raises(ValueError, match="polynomial"):
        refit_shifted_lqr(table, path, N_RATE, Q, R)


def test_the_exact_hessian_is_the_curvature_of_F():
    """Newton's Hessian (_ShiftedCost.hessian) at the answer against the second differences of F
    written here (Kronecker-product Lyapunov solves) along random directions, vᵀ∇²F v, and the
    cross term between two directions; the module's coordinates x (the coefficients in u, scaled)
    are mapped to θ-power coefficients with its _power_basis."""
    path = _path()
    start = _start(path)
    fit = refit_shifted_lqr(start, path, N_RATE, Q, R, decay=DECAY, cone_deg=CONE, weight=WEIGHT)
    st = _refit_start(start, path, 1)
    # the answer's x: its coefficients in u (sampled at u = −1, 0, 1), less the start's, scaled
    us = np.array([-1.0, 0.0, 1.0])
    vt = (st["c0"] + st["h0"] * us)[:, None] ** np.arange(3)
    a = np.linalg.solve(us[:, None] ** np.arange(3), vt @ fit.coef.reshape(3, -1)).reshape(st["shape"])
    x = ((a - st["a0"]) / st["sc"]).ravel()

    def coef(z):
        return _power_basis(st["a0"] + z.reshape(st["shape"]) * st["sc"], st["c0"], st["h0"])

    assert np.allclose(coef(x), fit.coef, rtol=1e-10, atol=1e-12)
    rng = np.random.default_rng(3)
    h = 1e-4
    for cone in (CONE, 90.0):                   # with the cone term, and without it (ψ = 0)
        H = _ShiftedCost(st, N_RATE, np.eye(5) + Q, R, WEIGHT).hessian(x, DECAY, np.radians(90.0 - cone))
        assert np.allclose(H, H.T)
        if cone == CONE:
            assert np.linalg.eigvalsh(H).min() > 0        # the answer: a minimum

        def F(z):
            return _F(path, start, coef(z), cone)

        f0 = F(x)
        for _ in range(3):
            v, w = rng.standard_normal((2, x.size))
            fd = (F(x + h * v) - 2 * f0 + F(x - h * v)) / h ** 2
            assert v @ H @ v == pytest.approx(fd, rel=1e-4)
            cross = (F(x + h * (v + w)) - F(x + h * (v - w)) - F(x - h * (v - w)) + F(x - h * (v + w))) / (4 * h * h)
            assert v @ H @ w == pytest.approx(cross, rel=1e-3, abs=1e-4 * abs(v @ H @ v))
