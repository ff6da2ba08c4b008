"""Regional pole placement by LMIs with an H2 cost bound (report ch. 5.2, eqs 5.2–5.4, Fig 5.2).

An alternative to :func:`acmm.design.sector_lqr.sector_lqr` (issue 32 item 1): the state feedback
u = −K x (eq 5.3) is found by one convex program whose Lyapunov certificate proves every pole of
A − BK in the sector of Fig 5.2 with margin μ (:func:`acmm.design.sector_lqr.sector_margin`)::

    S = {λ : Re λ ≤ −σn  and  |Im λ| ≤ tan φ |Re λ|}      (σ = 0.5, φ = 45° in the report)

Regions (Chilali & Gahinet 1996, "H∞ design with pole placement constraints: an LMI approach",
IEEE TAC 41(3)), with M = Ã X − B̃ Y, K̃ = Y X⁻¹, in the scaled coordinates below:

* half-plane Re λ ≤ −(σ + μ)n:  M + Mᵀ + 2(σ + μ) X ⪯ 0;
* the sector's cone with its apex shifted to −c, c = μ / sin φ (every point of it lies ≥ μn
  inside the cone of Fig 5.2), M_c = M + cX:
  [[sin φ (M_c + M_cᵀ), cos φ (M_c − M_cᵀ)], [cos φ (M_cᵀ − M_c), sin φ (M_c + M_cᵀ)]] ⪯ 0;
* optionally a disk |λ| ≤ r n bounding the fastest pole: [[−rX, M], [Mᵀ, −rX]] ⪯ 0.

The two regions together are exactly {λ : sector margin ≥ μ}, so X ≻ 0 satisfying them certifies
the margin μ.

Cost (H2, "control energy"): for the disturbance torque w entering at the input (G = −B), ::

    E(K) = tr(K̃ W K̃ᵀ),   Ã_cl W + W Ã_clᵀ + G̃ G̃ᵀ = 0,   Ã_cl = Ã − B̃ K̃,

the variance of the (scaled) control for unit white noise on every torque axis (the same number as
the H2 norm² from w to u) — :func:`control_energy`, used for this route and the LQR route alike.
It is bounded with the *dilated* H2 condition of Ebihara & Hagiwara (2004, "New dilated LMI
characterizations for continuous-time multiobjective controller synthesis", Automatica 40) with
the slack V = X, which lets the H2 matrix X₂ differ from the region certificate X: with β > 0 ::

    [[−2βX, X₂ − X + βMᵀ], [X₂ − X + βM, M + Mᵀ + G̃G̃ᵀ]] ⪯ 0     ⇒  Ã_cl X₂ + X₂ Ã_clᵀ + G̃G̃ᵀ ⪯ 0,
    [[W, Y], [Yᵀ, 2X − X₂]] ⪰ 0                                   ⇒  W ⪰ K̃ X₂ K̃ᵀ ⪰ K̃ W_c K̃ᵀ,

(Finsler's lemma on [A_cl I]; 2X − X₂ ⪯ X X₂⁻¹ X), and tr W is minimized.  β → 0 is the
common-Lyapunov (Chilali–Gahinet) H2 bound, whose shared X overbounds the energy by ~30 % and
gives gains with *more* energy than the LQR route; β ≈ 0.35–0.5 gives less.  tr W stays an upper
bound of E(K) (loose for larger β: its minimizer, not its value, is what is used).

Scaling.  Scaled states x = D x̃ (:mod:`acmm.model.state_scaling`), input u = e ũ (``input_scale``),
time in units of 1/n: Ã = D⁻¹AD/n, B̃ = D⁻¹Be/n, K̃ = K D/e.  The program is solved in
coordinates x̃ = T z: first T = chol(X₀) with X₀ the Lyapunov matrix of a reference closed loop
(the sector LQR's gain, shifted by σ, driven by G̃G̃ᵀ + 10⁻³I), then again with T ← T chol(X)
from the first solution and the input columns scaled to unit gain-row norms, the objective divided
by the first optimum — the same problem, but with its optimum near X = I, Y, W = O(1), where
Clarabel reaches status "optimal" at gap and feasibility tolerance 1e-7 (``tol``; at 1e-8 AC stops
"optimal_inaccurate"); the first pass usually stops at
"optimal_inaccurate", which is accepted only as a pre-conditioner).
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from acmm.design.sector_lqr import eigen_conditioning, sector_margin, sector_robustness
from acmm_qpp.errors import DesignError

#: Clarabel options of every solve besides the tolerances: one thread.  Its solver threads are not
#: fork-safe (a forked child of a process that has solved a program with them hung in its next
#: solve: the LMI stair-case's points on the process pool after an in-process LMI design), and one
#: thread makes the result independent of the machine's core count; on these programs (a dense
#: KKT factorization per iteration) more threads were not faster.
CLARABEL_OPTIONS = {"max_threads": 1}

_RELAX = ("relax design.min_margin, design.sector.sigma, design.sector.half_angle_deg or "
          "design.lmi.disk_radius (or the cost weights: design.lmi.dilation, design.R)")


@dataclass(frozen=True)
class RegionalLMISettings:
    """Settings of :func:`regional_lmi`.

    Attributes
    ----------
    sigma : float
        Minimum decay rate σ of the sector, units of n (eq 5.4, Fig 5.2).
    half_angle_deg : float
        Sector half-angle φ, deg.
    min_margin : float
        μ: certified :func:`~acmm.design.sector_lqr.sector_margin` of every pole, units of n.
    backoff : float
        The regions are imposed with margin μ + backoff so that the certificate, which holds
        to the solver's tolerance, proves μ; units of n.
    disk_radius : float
        r > 0 adds the region |λ| ≤ r n (fastest pole), units of n; 0 = none.
    dilation : float
        β of the dilated H2 bound (module docstring), units of 1/n (time); > 0.
    tol : float
        Clarabel's tol_gap_abs = tol_gap_rel = tol_feas of the final pass, dimensionless.
    max_iter : int
        Clarabel iteration limit per pass.
    refinements : int
        Largest number of re-pre-conditioned passes tried after the first.
    n_random : int
        Random gain perturbations of :func:`random_gain_radius`.
    seed : int
        Seed of those perturbations.
    """

    sigma: float = 0.5
    half_angle_deg: float = 45.0
    min_margin: float = 0.1
    backoff: float = 0.002
    disk_radius: float = 0.0
    dilation: float = 0.35
    tol: float = 1e-7
    max_iter: int = 200
    refinements: int = 2
    n_random: int = 100
    seed: int = 0


@dataclass(frozen=True)
class RegionalLMI:
    """A regional-pole-placement design (:func:`regional_lmi`).

    Attributes
    ----------
    K : (M, N) array
        Gain, u = −K x (eq 5.3), physical units (ft·lbf per state unit).
    X : (N, N) array
        Lyapunov certificate of the regions in the scaled coordinates x̃ (dimensionless, time in 1/n).
    X2 : (N, N) array
        The H2 matrix X₂ ⪰ W_c (scaled coordinates), dimensionless.
    poles : (N,) complex array
        Eigenvalues of A − BK, rad/s, sorted by real part.
    margin : float
        Worst sector margin of the poles, units of n.
    certified_margin : float
        Sector margin proved by X: min(a* − σ, c* sin φ), a* and c* the largest half-plane shift
        and cone-apex shift for which the region LMIs hold with this X and K (generalized
        eigenvalues), units of n.
    eig_condition : (N,) array
        Eigenvalue condition numbers of Ã − B̃K̃ (:func:`~acmm.design.sector_lqr.eigen_conditioning`),
        same order as ``poles``, dimensionless.
    robustness_radius, robustness_radius_elementwise : float
        First-order sector robustness radii (:func:`~acmm.design.sector_lqr.sector_robustness`),
        normwise in the scaled coordinates and elementwise, dimensionless.
    random_radius : float
        Re-check: smallest relative elementwise gain error found to move a pole out of the sector
        (:func:`random_gain_radius`), dimensionless.
    energy : float
        :func:`control_energy` of K, in (input_scale)² (time unit 1/n).
    cost_bound : float
        tr W, the certified upper bound of ``energy``, in the units of ``energy``.
    status : str
        cvxpy status of the accepted pass ("optimal").
    tol : float
        Clarabel tolerance it converged to (gap and feasibility), dimensionless.
    iterations : tuple of int
        Clarabel iterations of each pass.
    solve_time : float
        Wall time of all passes, s.
    """

    K: np.ndarray
    X: np.ndarray
    X2: np.ndarray
    poles: np.ndarray
    margin: float
    certified_margin: float
    eig_condition: np.ndarray
    robustness_radius: float
    robustness_radius_elementwise: float
    random_radius: float
    energy: float
    cost_bound: float
    status: str
    tol: float
    iterations: tuple
    solve_time: float

    @property
    def max_eig_condition(self) -> float:
        """Largest eigenvalue condition number κ."""
        return float(np.max(self.eig_condition))


# ---------------------------------------------------------------------------------------------
# scaled coordinates and the measures shared with the LQR route
# ---------------------------------------------------------------------------------------------
def scaled_model(A, B, n: float, scale=None, input_scale: float = 1.0):
    """(Ã, B̃) = (D⁻¹AD/n, D⁻¹Be/n): scaled states, input in units of e, time in 1/n.

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s.
    B : (N, M) array
        Input matrix, state units per input unit.
    n : float
        Orbital rate, rad/s.
    scale : (N,) array or None
        State scales D (units of each state).
    input_scale : float
        Input unit e (e.g. ft·lbf).

    Returns
    -------
    (Ã, B̃) : tuple of arrays
        Dimensionless.
    """
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    d = np.ones(A.shape[0]) if scale is None else np.asarray(scale, dtype=float)
    return A / d[:, None] * d[None, :] / n, B / d[:, None] * input_scale / n


def control_energy(A, B, K, n: float, scale=None, input_scale: float = 1.0, G=None) -> float:
    """H2 control energy E(K) = tr(K̃ W K̃ᵀ), Ã_cl W + W Ã_clᵀ + G̃G̃ᵀ = 0 (module docstring).

    Parameters
    ----------
    A, B, K : arrays
        Model and gain u = −Kx, physical units.
    n : float
        Orbital rate, rad/s (time unit 1/n).
    scale : (N,) array or None
        State scales D, units of each state.
    input_scale : float
        Input unit e.
    G : (N, p) array or None
        Disturbance input, state units per s per ft·lbf; None = −B (torque disturbance at the input).

    Returns
    -------
    float
        E in units of e² (inf if A − BK is not Hurwitz).
    """
    As, Bs = scaled_model(A, B, n, scale, input_scale)
    d = np.ones(As.shape[0]) if scale is None else np.asarray(scale, dtype=float)
    Ks = np.asarray(K, dtype=float) * d[None, :] / input_scale
    Gs = -Bs if G is None else np.asarray(G, dtype=float) / d[:, None] * input_scale / n
    Acl = As - Bs @ Ks
    if np.max(np.linalg.eigvals(Acl).real) >= 0:
        return float("inf")
    W = sla.solve_continuous_lyapunov(Acl, -(Gs @ Gs.T))
    return float(np.trace(Ks @ W @ Ks.T))


def random_gain_radius(A, B, K, n: float, sigma: float = 0.5, half_angle_deg: float = 45.0,
                       n_samples: int = 100, seed: int = 0) -> float:
    """Smallest relative elementwise gain error found to move a pole of A − BK out of the sector.

    For each of ``n_samples`` matrices R with entries uniform in [−1, 1], the largest ε ≤ 1 with
    every pole of A − B (K ∘ (1 + εR)) inside the sector is found by bisection (30 steps); the
    minimum over the samples is returned — an upper bound of the true elementwise radius, the
    random re-check of :func:`~acmm.design.sector_lqr.sector_robustness`.

    Parameters
    ----------
    A, B, K : arrays
        Model and gain, physical units (the result is scale-invariant).
    n : float
        Orbital rate, rad/s.
    sigma, half_angle_deg : float
        The sector (units of n, deg).
    n_samples, seed : int
        Number of random directions and their seed.

    Returns
    -------
    float
        The radius, dimensionless (0 if a pole is outside already, 1 if none found below 1).
    """
    A, B, K = (np.asarray(x, dtype=float) for x in (A, B, K))
    rng = np.random.default_rng(seed)

    def inside(e, R):
        lam = np.linalg.eigvals(A - B @ (K * (1.0 + e * R)))
        return np.min(sector_margin(lam, n, sigma, half_angle_deg)) > 0

    if not inside(0.0, np.zeros_like(K)):
        return 0.0
    best = 1.0
    for _ in range(n_samples):
        R = rng.uniform(-1.0, 1.0, K.shape)
        if inside(best, R):
            continue
        lo, hi = 0.0, best
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if inside(mid, R) else (lo, mid)
        best = hi
    return float(best)


# ---------------------------------------------------------------------------------------------
# the program
# ---------------------------------------------------------------------------------------------
def _region_blocks(M, X, a, c, phi, r):
    """The LMIs (⪯ 0) of the half-plane, the shifted cone and the optional disk (numpy or cvxpy)."""
    import cvxpy as cp

    Mc = M + c * X
    out = [M + M.T + 2 * a * X,
           cp.bmat([[np.sin(phi) * (Mc + Mc.T), np.cos(phi) * (Mc - Mc.T)],
                    [np.cos(phi) * (Mc.T - Mc), np.sin(phi) * (Mc + Mc.T)]])]
    if r > 0:
        out.append(cp.bmat([[-r * X, M], [M.T, -r * X]]))
    return out


def _solve_pass(As, Bs, Gs, T, s_u, obj_scale, st: RegionalLMISettings, tol):
    """One Clarabel solve in the coordinates x̃ = T z, input columns scaled by ``s_u``.

    Returns (status, tr W, iterations, K̃, X̃, X̃₂) with K̃, X̃, X̃₂ in the scaled coordinates."""
    import cvxpy as cp

    N, m = Bs.shape
    Ti = np.linalg.inv(T)
    Az, Bz, Gz = Ti @ As @ T, Ti @ Bs * s_u[None, :], Ti @ Gs
    X = cp.Variable((N, N), symmetric=True)
    X2 = cp.Variable((N, N), symmetric=True)
    Y = cp.Variable((m, N))
    W = cp.Variable((m, m), symmetric=True)
    M = Az @ X - Bz @ Y
    phi = np.deg2rad(st.half_angle_deg)
    mu = st.min_margin + st.backoff
    a = st.sigma + mu
    c = mu / np.sin(phi)
    b = st.dilation
    cons = [L << 0 for L in _region_blocks(M, X, a, c, phi, st.disk_radius)]
    cons += [cp.bmat([[-2 * b * X, X2 - X + b * M.T], [X2 - X + b * M, M + M.T + Gz @ Gz.T]]) << 0,
             cp.bmat([[W, Y], [Y.T, 2 * X - X2]]) >> 0]
    S = np.diag(s_u)
    prob = cp.Problem(cp.Minimize(cp.trace(S @ W @ S) / obj_scale), cons)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            prob.solve(solver=cp.CLARABEL, tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol,
                       max_iter=st.max_iter, **CLARABEL_OPTIONS)
        except cp.error.SolverError as exc:
            return f"solver_error ({exc})", np.nan, 0, None, None, None
    iters = int(prob.solver_stats.num_iters or 0)
    if prob.status not in ("optimal", "optimal_inaccurate") or X.value is None:
        return prob.status, np.nan, iters, None, None, None
    Xz = 0.5 * (X.value + X.value.T)
    Kz = s_u[:, None] * np.linalg.solve(Xz, Y.value.T).T
    Xs = T @ Xz @ T.T
    X2s = T @ (0.5 * (X2.value + X2.value.T)) @ T.T
    return prob.status, float(prob.value) * obj_scale, iters, Kz @ Ti, 0.5 * (Xs + Xs.T), 0.5 * (X2s + X2s.T)


def certified_margin(As, Bs, Ks, X, sigma: float, half_angle_deg: float, min_margin: float) -> float:
    """Sector margin proved by the region certificate X for Ã − B̃K̃ (units of n).

    a* = −λ_max(He(Ã_cl X), 2X) (largest a with He(Ã_cl X) + 2aX ⪯ 0) and c* the largest apex
    shift with the cone LMI of M_c = Ã_cl X + c X ⪯ 0 (a generalized eigenvalue of the pencil
    (L₀, 2 sin φ I₂ ⊗ X)); the margin is min(a* − σ, c* sin φ).  −inf if X is not ≻ 0.

    Parameters
    ----------
    As, Bs, Ks : arrays
        Scaled model and gain (time in 1/n), dimensionless.
    X : (N, N) array
        The certificate in the same coordinates, dimensionless.
    sigma, half_angle_deg : float
        The sector (units of n, deg).
    min_margin : float
        μ, units of n (unused in the value; kept for the signature of the settings).

    Returns
    -------
    float
        The certified margin, units of n.
    """
    X = 0.5 * (X + X.T)
    if np.min(np.linalg.eigvalsh(X)) <= 0:
        return float("-inf")
    phi = np.deg2rad(half_angle_deg)
    M = (As - Bs @ Ks) @ X
    H = M + M.T
    a_star = -float(np.max(sla.eigh(H, 2 * X, eigvals_only=True)))
    L0 = np.block([[np.sin(phi) * H, np.cos(phi) * (M - M.T)], [np.cos(phi) * (M.T - M), np.sin(phi) * H]])
    E = 2 * np.sin(phi) * np.kron(np.eye(2), X)
    c_star = float(np.min(sla.eigh(-0.5 * (L0 + L0.T), E, eigvals_only=True)))
    return min(a_star - sigma, c_star * np.sin(phi))


def regional_lmi(A, B, n: float, K_ref, settings: RegionalLMISettings = RegionalLMISettings(), *,
                 scale=None, input_scale: float = 1.0, G=None) -> RegionalLMI:
    """Gain with every pole certified in the sector with margin μ and a minimal H2 energy bound.

    Parameters
    ----------
    A : (N, N) array
        Open-loop state matrix (eq 4.46), 1/s.
    B : (N, M) array
        Control input matrix, state units per ft·lbf.
    n : float
        Orbital rate, rad/s (unit of the sector and of the scaled time).
    K_ref : (M, N) array
        A stabilizing reference gain (e.g. the sector LQR's), physical units; used only to
        pre-condition the coordinates (module docstring).
    settings : RegionalLMISettings
        Regions, dilation, solver tolerance, robustness re-check.
    scale : (N,) array or None
        State scales D (x = D x̃), units of each state.
    input_scale : float
        Input unit e, ft·lbf (:func:`acmm.model.state_scaling.torque_scale`).
    G : (N, p) array or None
        Disturbance input, state units per s per ft·lbf; None = −B.

    Returns
    -------
    RegionalLMI
        The verified design (K physical, X scaled).

    Raises
    ------
    ValueError
        Settings out of range.
    DesignError
        The regions are infeasible, the final pass does not reach status "optimal", or a pole
        of the result lies outside the sector with margin μ (each with one line naming the
        settings to relax).
    """
    st = settings
    if not (n > 0 and st.sigma > 0 and 0 < st.half_angle_deg < 90 and st.min_margin >= 0
            and st.dilation > 0 and st.backoff >= 0 and st.disk_radius >= 0 and st.tol > 0):
        raise ValueError("need n > 0, sigma > 0, 0 < half_angle_deg < 90, min_margin ≥ 0, "
                         "dilation > 0, disk_radius ≥ 0, tol > 0")
    t0 = time.perf_counter()
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    N, m = B.shape
    d = np.ones(N) if scale is None else np.asarray(scale, dtype=float)
    As, Bs = scaled_model(A, B, n, d, input_scale)
    Gs = -Bs if G is None else np.asarray(G, dtype=float) / d[:, None] * input_scale / n
    K0 = np.asarray(K_ref, dtype=float) * d[None, :] / input_scale
    Acl0 = As - Bs @ K0
    if np.max(np.linalg.eigvals(Acl0).real) > -st.sigma:
        raise DesignError("regional LMI: the reference gain does not give Re λ ≤ −σn; "
                          "pass the sector LQR's gain as K_ref")
    X0 = sla.solve_continuous_lyapunov(Acl0 + st.sigma * np.eye(N), -(Gs @ Gs.T + 1e-3 * np.eye(N)))
    T = np.linalg.cholesky(0.5 * (X0 + X0.T))
    s_u, obj = np.ones(m), 1.0
    iters = []
    # pass 1: a pre-conditioner (optimal_inaccurate accepted); then re-pre-conditioned passes
    status, val, it, Ks, Xs, X2s = _solve_pass(As, Bs, Gs, T, s_u, obj, st, max(st.tol, 1e-6))
    iters.append(it)
    if Ks is None:
        raise DesignError(f"regional LMI: the regions and cost bound are infeasible (Clarabel: {status}); "
                          + _RELAX)
    for _ in range(st.refinements):
        T = np.linalg.cholesky(Xs)
        s_u = np.maximum(np.linalg.norm(Ks @ T, axis=1), 1e-12)
        obj = val
        status, val_new, it, Kn, Xn, X2n = _solve_pass(As, Bs, Gs, T, s_u, obj, st, st.tol)
        iters.append(it)
        if Kn is None:
            break
        val, Ks, Xs, X2s = val_new, Kn, Xn, X2n
        if status == "optimal":
            break
    if status != "optimal":
        raise DesignError(f"regional LMI: Clarabel status {status!r} after {len(iters)} passes "
                          f"(tolerance {st.tol:.0e}); " + _RELAX)
    Acl = As - Bs @ Ks
    lam, _, _, kappa = eigen_conditioning(Acl)
    order = np.lexsort((lam.imag, lam.real))
    poles, kappa = lam[order] * n, kappa[order]
    margin = float(np.min(sector_margin(poles, n, st.sigma, st.half_angle_deg)))
    cert = certified_margin(As, Bs, Ks, Xs, st.sigma, st.half_angle_deg, st.min_margin)
    if margin < st.min_margin or cert < st.min_margin:
        raise DesignError(f"regional LMI: worst sector margin {margin:.4g}n (certified {cert:.4g}n) "
                          f"below {st.min_margin}n; " + _RELAX)
    fastest = float(np.max(np.abs(poles))) / n
    if st.disk_radius > 0 and fastest > st.disk_radius * (1 + 1e-6):
        raise DesignError(f"regional LMI: the fastest pole |λ| = {fastest:.4g}n is outside the disk of radius "
                          f"design.lmi.disk_radius = {st.disk_radius}n; " + _RELAX)
    K = Ks / d[None, :] * input_scale
    e_norm, e_elem = sector_robustness(A, B, K, n, st.sigma, st.half_angle_deg, scale=d)
    rr = random_gain_radius(A, B, K, n, st.sigma, st.half_angle_deg, st.n_random, st.seed)
    energy = control_energy(A, B, K, n, d, input_scale, G)
    return RegionalLMI(K=K, X=Xs, X2=X2s, poles=poles, margin=margin, certified_margin=cert,
                       eig_condition=kappa, robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                       random_radius=rr, energy=energy, cost_bound=val, status=status, tol=st.tol,
                       iterations=tuple(iters), solve_time=time.perf_counter() - t0)
