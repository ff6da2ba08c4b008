"""The report's quadratic gain schedule, converged (CR-185644 ch. 5.3; issue 41 item 4;
docs/results/design.md, "The gain schedule").

:func:`refit_shifted_lqr` (``schedule.fit: shifted_lqr``) chooses the coefficients of the
polynomial schedule K(θ2*) = Σ_k c_k θ2*^k as the minimizer of one smooth function, the
shifted LQR cost of the scheduled local loop summed over TEAs θ_j of the path, ::

    F(x) = log( (1/T) Σ_j [tr P_j + tr P_j^c] ) + (ε/2)·‖x‖²,
    A_j^α = A_j − B_j K(θ_j) + α n I,
    (A_j^α)ᵀ P_j + P_j A_j^α + Q + K(θ_j)ᵀ R K(θ_j) = 0,
    (e^{jψ} A_j^α)ᴴ P_j^c + P_j^c (e^{jψ} A_j^α) + Q = 0,      ψ = 90° − the cone's half-angle,

with x the coefficients' change from the least-squares fit of the design points (in the
normalized variable u = (θ2* − c)/h, each coefficient in units of the largest of its element's
least-squares coefficients), Q = I + the design's state weight on the scaled states, R = the
design's control weight, α the decay rate asked of the loop (units of n) and ε a weight that
makes the minimizer unique.  tr P_j is finite exactly when every pole of loop j has
Re λ < −α n, and tr P_j^c exactly when every pole lies inside the cone of half-angle 90° − ψ
about the negative real axis with its apex at −α n (e^{±jψ}(λ + α n) in the left half-plane;
the conjugate equation has the same trace); both grow without bound at the region's edge, so F
is a barrier and its minimizer keeps every loop at the chosen TEAs inside the region.  The
result is re-checked on every TEA of the path by :func:`acmm.design.path_check.check_path`.

The least-squares fit is usually far outside the region (on the packaged stair-case its loop is
unstable, +0.96n), so the minimization starts with a homotopy: from α₀ = −(w₀ + 0.1) and ψ₀ = 0,
w₀ the start's largest Re λ/n, each stage minimizes the barrier part of F (ε = 0: the weight
would hold the stage near the fit it must leave) at its (α, ψ) by BFGS (scipy), then moves α half
way to the new largest −Re λ/n and ψ half way to the largest rotation the loops now allow, never
past the targets.  The homotopy ends when the loops are inside the final region with
:data:`HOMOTOPY_GAP` to spare in decay, or when two stages at the targets change nothing; it
gives up (the least-squares fit is kept, ``accepted`` false, the reason in the message) after
:data:`MAX_STAGES` stages.  The last problem, F at the targets with its weight, is solved by BFGS
and then Newton's method (the exact Hessian, reused while the steps contract by half, a
backtracking line search that keeps F finite) until no coefficient moves by more than
:data:`STEP_TOL` of its scale: the answer is the stationary point itself,
not where an iteration count ran out, and it does not depend on the way there.

Gradients (Levine–Athans): ∂ tr P/∂K = 2(R K − Bᵀ P) L with A^α L + L (A^α)ᵀ + I = 0; for the
cone term ∂ tr P^c/∂K = −2 Re(e^{−jψ} Bᵀ P^c L^c) with (e^{jψ}A^α) L^c + L^c (e^{jψ}A^α)ᴴ + I = 0;
both chained through K = Σ_k u^k a_k.  The Hessian differentiates these once more along each
gain element E (dA^α = −B E): with S = R K − Bᵀ P, ∂(∂ tr P/∂K)[E] = 2(R E − Bᵀ dP) L + 2 S dL, where
(A^α)ᵀ dP + dP A^α + (dA^α)ᵀ P + P dA^α + Eᵀ R K + Kᵀ R E = 0 and
A^α dL + dL (A^α)ᵀ + dA^α L + L (dA^α)ᵀ = 0, and likewise for the cone term; F's Hessian adds the
log's rank-one term −∇T ∇Tᵀ/T² (T the summed traces) and the weight ε I.
"""
from __future__ import annotations

from dataclasses import replace
from math import comb

import numpy as np
from scipy.linalg import schur, solve_triangular
from scipy.linalg.lapack import ztrsyl
from scipy.optimize import minimize

from acmm.design.path_check import PathModels
from acmm.design.schedule import ScheduleFit

#: Decay rate α asked of every local loop, units of n (issue 41 item 4 asks Re λ ≤ −0.25n on the
#: path; 0.3n leaves room between the fit's TEAs).
DECAY = 0.3

#: Half-angle of the cone, apex −α n, about the negative real axis that every local loop's poles
#: are kept in, deg: the damping the shifted cost alone does not ask for (measured when it was
#: chosen: without the cone the packaged stair-case's loop at AC had lightly damped poles, a disk
#: margin near 0.1 and an AC level peaking near 10 600 ft·lbf·s; docs/results/design.md).
CONE_DEG = 70.0

#: Weight ε of the coefficients' distance from the points' least-squares fit (dimensionless):
#: it makes the minimizer unique (without it the Hessian of F on the packaged stair-case had
#: eigenvalues near zero and below it, and Newton's steps wandered without converging).
WEIGHT = 1e-2

#: TEAs of the path the cost sums over (evenly spaced, the ends included).
N_TEA = 51

#: The homotopy stops when every chosen loop has Re λ < −(α + HOMOTOPY_GAP) n.
HOMOTOPY_GAP = 0.02

#: Newton's method stops when no coefficient changes by more than STEP_TOL of its size.
STEP_TOL = 1e-10

#: Guards on the work (a result that reaches MAX_STAGES or MAX_NEWTON is reported as not done or
#: not converged); STAGE_ITER and FINAL_BFGS_ITER bound BFGS on the way, not the answer, which
#: Newton's step tolerance decides.
MAX_STAGES = 60
MAX_NEWTON = 60
STAGE_ITER = 40
FINAL_BFGS_ITER = 2000


def _power_basis(a: np.ndarray, c: float, h: float) -> np.ndarray:
    """Coefficients in powers of θ (units of ``a`` per rad^k) of Σ_k a[k]·((θ − c)/h)^k, c and h in rad."""
    order = a.shape[0] - 1
    b = np.zeros_like(a)
    for k in range(order + 1):
        for j in range(k + 1):       # ((θ − c)/h)^k = Σ_j C(k,j) θ^j (−c)^(k−j) / h^k
            b[j] = b[j] + a[k] * comb(k, j) * (-c) ** (k - j) / h ** k
    return b


def _refit_start(fit: ScheduleFit, path: PathModels, every: int) -> dict:
    """The TEAs, models and starting coefficients of a refit of ``fit`` on every ``every``-th TEA
    of ``path`` (ends included): ``idx``, ``c0``, ``h0`` (u = (θ2* − c0)/h0, rad), ``d`` (the
    state scaling), ``As``, ``Bs`` (scaled models), ``up`` (powers of u at each TEA), ``shape``,
    ``a0`` (starting coefficients in u, scaled gains) and ``sc`` (the largest |a0| per element)."""
    idx = sorted(set(range(0, path.theta2.size, max(1, every))) | {path.theta2.size - 1})
    th = path.theta2[idx]
    c0, h0 = 0.5 * (th.max() + th.min()), 0.5 * (th.max() - th.min())
    d = path.scales
    As, Bs = path.A[idx] / d[:, None] * d[None, :], path.B[idx] / d[:, None]
    order = fit.order
    u = (th - c0) / h0
    up = u[:, None] ** np.arange(order + 1)[None, :]                     # (T, order+1)
    # the starting coefficients (fit.coef, powers of θ) in u, scaled gains: sample and refit
    shape = (order + 1,) + fit.gains.shape[1:]
    us = np.linspace(-1.0, 1.0, order + 1)
    ks = np.array([fit.gain(c0 + h0 * x) * d[None, :] for x in us]).reshape(order + 1, -1)
    a0 = np.linalg.solve(us[:, None] ** np.arange(order + 1)[None, :], ks).reshape(shape)
    sc = np.broadcast_to(np.maximum(np.abs(a0).max(axis=0, keepdims=True), 1e-12), shape)
    return {"idx": idx, "c0": c0, "h0": h0, "d": d, "As": As, "Bs": Bs, "up": up, "shape": shape,
            "a0": a0, "sc": sc}


def _lyapunov(T: np.ndarray, U: np.ndarray, W: np.ndarray, adjoint: bool) -> np.ndarray:
    """X with Mᴴ X + X M + W = 0 (``adjoint``) or M X + X Mᴴ + W = 0, M = U T Uᴴ, T upper
    triangular (complex Schur form), U unitary (Bartels–Stewart).  One right-hand side W is
    solved by LAPACK's triangular Sylvester solver (ztrsyl); a stack of them (W's last two axes)
    together, a column of the triangular system at a time, each column one triangular solve with
    the whole stack as its right-hand sides."""
    C = -(U.conj().T @ W @ U)
    if C.ndim == 2:
        Y, scale, info = ztrsyl(T, T, C, trana="C" if adjoint else "N", tranb="N" if adjoint else "C")
        if info < 0:
            raise ValueError(f"ztrsyl: argument {-info} is invalid")
        return U @ (Y / scale) @ U.conj().T
    N = T.shape[0]
    stack = C.reshape(-1, N, N)
    Y = np.zeros(stack.shape, complex)
    eye = np.eye(N)
    if adjoint:     # Tᴴ y_k + Σ_{i ≤ k} y_i T_ik = c_k, k = 0, 1, …: (Tᴴ + T_kk I) lower triangular
        for k in range(N):
            rhs = stack[..., k] - Y[..., :k] @ T[:k, k]
            Y[..., k] = solve_triangular(T.conj().T + T[k, k] * eye, rhs.T, lower=True).T
    else:           # T y_k + Σ_{i ≥ k} y_i conj(T_ki) = c_k, k = N − 1, …, 0: (T + conj(T_kk) I) upper
        for k in range(N - 1, -1, -1):
            rhs = stack[..., k] - Y[..., k + 1:] @ T[k, k + 1:].conj()
            Y[..., k] = solve_triangular(T + np.conj(T[k, k]) * eye, rhs.T, lower=False).T
    Y = Y.reshape(C.shape)
    return U @ Y @ U.conj().T


class _ShiftedCost:
    """F(x) of the module docstring, its gradient and its Hessian at the refit's TEAs ``st``
    (:func:`_refit_start`); n rad/s, Q on the scaled states (identity included), R 1/(ft·lbf)²,
    ``weight`` ε of the distance from the start.  Every ``x`` is the change of the coefficients
    from ``st["a0"]`` in units of ``st["sc"]``; α in units of n, ψ the cone term's rotation, rad."""

    def __init__(self, st: dict, n: float, Q: np.ndarray, R: np.ndarray, weight: float):
        self.st, self.n, self.Q, self.R, self.weight = st, n, Q, R, weight
        self.As, self.Bs = st["As"], st["Bs"]
        self.eye = np.eye(self.As.shape[1])

    def gains(self, x: np.ndarray) -> np.ndarray:
        """(T, M, N) gains at the refit's TEAs, ft·lbf per unit of each scaled state."""
        a = self.st["a0"] + x.reshape(self.st["shape"]) * self.st["sc"]
        return np.einsum("tk,kab->tab", self.st["up"], a)

    def poles(self, x: np.ndarray) -> np.ndarray:
        """(T, N) closed-loop poles (eigenvalues of A − B K) at the refit's TEAs, units of n."""
        return np.linalg.eigvals(self.As - self.Bs @ self.gains(x)) / self.n

    def __call__(self, x: np.ndarray, alpha: float, psi: float = 0.0) -> tuple[float, np.ndarray]:
        """(F, ∇F) at ``x``, dimensionless; (inf, 0) outside the region (ψ = 0: no cone term)."""
        terms = self._terms(x, alpha, psi)
        if terms is None:
            return np.inf, np.zeros_like(x)
        total, g, _ = terms
        f = np.log(total / len(self.As)) + 0.5 * self.weight * float(x @ x)
        return f, g / total + self.weight * x

    def hessian(self, x: np.ndarray, alpha: float, psi: float = 0.0) -> np.ndarray:
        """∇²F at ``x`` (inside the region, else ValueError), exact and symmetrized (the module
        docstring): each TEA's gradient differentiated along every gain element, the Schur form of
        its loop serving every Lyapunov equation."""
        terms = self._terms(x, alpha, psi, second=True)
        if terms is None:
            raise ValueError("the Hessian of F is asked outside the region")
        total, g, D = terms
        up, sc = self.st["up"], self.st["sc"].ravel()
        H = np.einsum("tk,tl,tef->kelf", up, up, D).reshape(g.size, g.size) * np.outer(sc, sc)
        H = H / total - np.outer(g, g) / total ** 2 + self.weight * np.eye(g.size)
        return 0.5 * (H + H.T)

    def _terms(self, x: np.ndarray, alpha: float, psi: float, second: bool = False):
        """(T, ∇T, D) with T = Σ_j tr P_j + tr P_j^c the summed traces, ∇T its gradient in x and
        D_j = ∂(∂T_j/∂K_j)/∂K_j (with ``second``; else None); None outside the region."""
        K = self.gains(x)
        rot = np.exp(1j * psi)
        # one complex Schur form A^α = U T Uᴴ per TEA serves all its Lyapunov equations (the
        # rotated matrix is U (e^{jψ} T) Uᴴ), each then a triangular Sylvester solve
        forms = [schur(Ac, output="complex") for Ac in self.As - self.Bs @ K + alpha * self.n * self.eye]
        # the region, with 1e-8 n to spare (closer, the Lyapunov equations are numerically singular)
        ev = np.array([np.diag(T) for T, _ in forms]) / self.n
        if not (np.all(ev.real < -1e-8) and np.all((rot * ev).real < -1e-8)
                and np.all((np.conj(rot) * ev).real < -1e-8)):
            return None
        m, N = K.shape[1:]
        E = np.eye(m * N).reshape(m * N, m, N) if second else None      # every gain element, one at a time
        total, gK, D = 0.0, np.empty_like(K), np.empty((len(K), m * N, m * N)) if second else None
        for j, ((T, U), B, Kj) in enumerate(zip(forms, self.Bs, K)):
            P = _lyapunov(T, U, self.Q + Kj.T @ self.R @ Kj, adjoint=True).real
            L = _lyapunov(T, U, self.eye, adjoint=False).real
            S = self.R @ Kj - B.T @ P
            total += np.trace(P)
            gK[j] = 2.0 * S @ L
            if second:
                dM = -B @ E                                     # (m N, N, N)
                dP = _lyapunov(T, U, _swap(dM) @ P + P @ dM + _swap(E) @ (self.R @ Kj) + Kj.T @ self.R @ E,
                               adjoint=True).real
                dL = _lyapunov(T, U, dM @ L + L @ _swap(dM), adjoint=False).real
                dG = 2.0 * ((self.R @ E - B.T @ dP) @ L + S @ dL)
            if psi:
                Pc = _lyapunov(rot * T, U, self.Q, adjoint=True)
                Lc = _lyapunov(rot * T, U, self.eye, adjoint=False)
                total += np.trace(Pc).real
                gK[j] -= 2.0 * (np.conj(rot) * (B.T @ Pc @ Lc)).real
                if second:
                    dMr = rot * dM
                    dPc = _lyapunov(rot * T, U, _swap(dMr).conj() @ Pc + Pc @ dMr, adjoint=True)
                    dLc = _lyapunov(rot * T, U, dMr @ Lc + Lc @ _swap(dMr).conj(), adjoint=False)
                    dG -= 2.0 * (np.conj(rot) * (B.T @ (dPc @ Lc + Pc @ dLc))).real
            if second:
                D[j] = dG.reshape(m * N, m * N)
        if not total > 0:
            return None
        return total, (np.einsum("tk,tab->kab", self.st["up"], gK) * self.st["sc"]).ravel(), D


def _swap(M: np.ndarray) -> np.ndarray:
    """The transpose of each matrix of a stack (its last two axes)."""
    return np.swapaxes(M, -1, -2)


def _newton(cost: _ShiftedCost, x: np.ndarray, alpha: float, psi: float = 0.0) -> tuple[np.ndarray, int, bool]:
    """Newton's method on F at (``alpha``, ``psi``) from ``x`` (inside the region); the Hessian is
    reused while the steps contract by half or better (a chord method) and recomputed otherwise.
    Returns the minimizer, the steps taken and whether the step tolerance was met."""
    f, g = cost(x, alpha, psi)
    H, last = None, np.inf
    for it in range(1, MAX_NEWTON + 1):
        if H is None:
            ev, V = np.linalg.eigh(cost.hessian(x, alpha, psi))
            # a modified Newton step where the Hessian is not positive definite far from the answer
            H = (V, np.maximum(np.abs(ev), 1e-8 * ev.max()))
        step = -H[0] @ ((H[0].T @ g) / H[1])
        t = 1.0
        while True:
            f1, g1 = cost(x + t * step, alpha, psi)
            if f1 <= f + 1e-4 * t * float(g @ step) or t < 1e-6:
                break
            t *= 0.5
        if not np.isfinite(f1):
            return x, it, False
        size = np.abs(t * step).max()
        x, f, g = x + t * step, f1, g1
        if size <= STEP_TOL:
            return x, it, True
        if t < 1.0 or size > 0.5 * last:
            H = None
        last = size
    return x, MAX_NEWTON, False


def refit_shifted_lqr(fit: ScheduleFit, path: PathModels, n: float, Q: np.ndarray, R: np.ndarray,
                      *, decay: float = DECAY, cone_deg: float = CONE_DEG, weight: float = WEIGHT,
                      n_tea: int = N_TEA) -> ScheduleFit:
    """The polynomial schedule that minimizes the path's summed α-shifted LQR cost.

    Parameters
    ----------
    fit : acmm.design.schedule.ScheduleFit
        The least-squares polynomial schedule of the design points (the weight's centre and the
        homotopy's start).
    path : acmm.design.path_check.PathModels
        Local models along the path.
    n : float
        Orbital rate, rad/s.
    Q : (N, N) array
        State weight on the scaled states, dimensionless (the identity is added).
    R : (M, M) array
        Control weight, 1/(ft·lbf)².
    decay : float
        Decay rate α asked of every loop at the chosen TEAs, units of n.
    cone_deg : float
        Half-angle of the cone, apex −α n, the loops' poles are kept in, deg (90: none).
    weight : float
        Weight ε of the distance from the least-squares fit, dimensionless.
    n_tea : int
        TEAs of the path the cost sums over (evenly spaced, the ends included).

    Returns
    -------
    acmm.design.schedule.ScheduleFit
        The schedule (``method="shifted_lqr"``); ``refit_info`` holds the largest Re λ/n before
        and after on the chosen TEAs, the homotopy's stages, Newton's steps, whether Newton met
        :data:`STEP_TOL` (``converged``) and a message.  When the homotopy cannot reach α (a
        guard is met, or a stage makes no progress) the least-squares fit is returned with
        ``accepted`` false.

    Raises
    ------
    ValueError
        ``fit`` is not a polynomial schedule.
    """
    if fit.form != "polynomial":
        raise ValueError("refit_shifted_lqr refines a polynomial schedule")
    every = max(1, (path.theta2.size - 1) // max(1, n_tea - 1))
    st = _refit_start(fit, path, every)
    Qi = np.eye(st["As"].shape[1]) + Q
    # the homotopy's stages minimize the barrier alone (the weight would hold them near the
    # least-squares fit, which is far outside the region); the last problem adds it
    cost, stage_cost = _ShiftedCost(st, n, Qi, R, weight), _ShiftedCost(st, n, Qi, R, 0.0)
    x = np.zeros(st["a0"].size)
    w0 = w = float(cost.poles(x).real.max())
    psi_target = np.radians(90.0 - cone_deg)
    alpha, psi, stages, still = min(-(w0 + 0.1), decay), 0.0, 0, 0
    while True:
        inside = psi == psi_target and np.isfinite(cost(x, decay, psi)[0])
        if inside and (w < -(decay + HOMOTOPY_GAP) or still >= 2):
            break
        if stages == MAX_STAGES:
            return _outcome(fit, st, x, w0, w, stages, 0, False, False,
                            f"{MAX_STAGES} homotopy stages (the guard) before every loop was inside the region "
                            f"(Re λ < −{decay:g}n, the {cone_deg:g}° cone)", decay, cone_deg)
        res = minimize(lambda z: stage_cost(z, alpha, psi), x, jac=True, method="BFGS",
                       options={"maxiter": STAGE_ITER, "gtol": 1e-4})
        if np.isfinite(res.fun):
            x = res.x
        lam = cost.poles(x)
        w_new = float(lam.real.max())
        still = still + 1 if alpha == decay and psi == psi_target and abs(w_new - w) < 1e-9 else 0
        w, stages = w_new, stages + 1
        alpha = min(0.5 * (alpha - w), decay)
        # the largest rotation ψ that keeps every pole's e^{±jψ}(λ + αn) in the left half-plane
        ev = lam + alpha
        psi_max = 0.5 * np.pi - np.max(np.arctan2(np.abs(ev.imag), -ev.real))
        psi = min(psi_target, 0.5 * (psi + psi_max) if psi_max > psi else 0.5 * psi_max)
    res = minimize(lambda z: cost(z, decay, psi), x, jac=True, method="BFGS",
                   options={"maxiter": FINAL_BFGS_ITER, "gtol": 1e-8})
    if np.isfinite(res.fun):
        x = res.x
    x, steps, converged = _newton(cost, x, decay, psi)
    w1 = float(cost.poles(x).real.max())
    message = (f"Newton's method converged: no coefficient moves by more than {STEP_TOL:g} of its size"
               if converged else f"Newton's method did not meet its step tolerance in {steps} steps")
    return _outcome(fit, st, x, w0, w1, stages, steps, converged, w1 < -decay, message, decay, cone_deg)


def _outcome(fit: ScheduleFit, st: dict, x: np.ndarray, w0: float, w1: float, stages: int, steps: int,
             converged: bool, accepted: bool, message: str, decay: float, cone_deg: float) -> ScheduleFit:
    """The refitted schedule (or ``fit`` when not ``accepted``) with its ``refit_info``."""
    info = {"iterations": int(steps), "homotopy_stages": int(stages), "converged": bool(converged),
            "decay": float(decay), "cone_deg": float(cone_deg),
            "message": message, "n_tea": len(st["idx"]), "max_real_before": float(w0),
            "max_real_after": float(w1), "accepted": bool(accepted)}
    if not accepted:
        return replace(fit, method="least_squares", refit_info=info)
    a = st["a0"] + x.reshape(st["shape"]) * st["sc"]
    coef = _power_basis(a, st["c0"], st["h0"]) / st["d"][None, None, :]    # powers of θ2*, units of K
    return ScheduleFit(coef, fit.variable, fit.gains, fit.form, "shifted_lqr", info)
