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
time in units of 1/n: Ã = D⁻¹AD/n, B̃ = D⁻¹Be/n, K̃ = K D/e.  The program is written in coordinates
x̃ = T z with T = chol(X₀), X₀ the Lyapunov matrix of a reference closed loop (the sector LQR's
gain, shifted by σ, driven by G̃G̃ᵀ + 10⁻³I) — the reference loop's coordinates.

Well-posed.  Without more, the program has no attained optimum: X and X₂ grow without bound along
the directions the gain does not use (K̃ v ≈ 0; a 2-D subspace at MB3) while
tr W keeps falling toward its infimum, so every interior-point solver ends "inaccurate", stalls or
meets a singular system, and the answer depends on where it stopped (the BLAS kernel, the solver).
The objective is therefore ::

    tr W + ε (tr X' + tr X₂'),     X̃ = T X' Tᵀ  (the reference loop's coordinates),

with ε = ``regularization`` = 1e-5: the level sets are bounded, the optimum is attained, and the
control energy of the answer stays within 0.1 % of the unregularized program's (a slow test at
MB3).  The same weight on tr X̃ in the scaled coordinates, whose eigenvalues span many decades,
left the program ill-posed or cost more energy; a bound X' ⪯ cI would add a cone.

Solvers (``solver``; :data:`ROUTES`): ``"conelp"`` (default: cvxopt's ``conelp`` with the KKT solver
of :mod:`acmm.design.lmi_structure`, :func:`_route_conelp`), ``"dsdp"`` (DSDP 5 through ``cvxopt.dsdp``,
GPL-3, README; :func:`_route_dsdp`) and ``"clarabel"`` (through cvxpy, Apache-2.0, the reference: it
factors the whole KKT system, a dense 1 176 × 1 176 block per 48 × 48 LMI; :func:`_route_clarabel`);
``make bench`` times the three, ``tests/test_determinism.py`` holds the gains under two BLAS kernels
and thread counts.  Each answer is accepted on the checks of :func:`_rejection`, never on a status
string; a refused answer falls back to the next solver with a warning, and when none passes the
error says what each solver returned — never "infeasible", which a solver's failure does not prove.
All three solve the same program; at the tolerance 1e-7 the optimum's flat directions let their
gains differ by more than each solver's own rounding does (a slow test at MB3 holds them to 3e-5).
"""
from __future__ import annotations

import threading
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla

from acmm.design.lmi_structure import (StructuredKKT, coefficient_arrays, conelp_available, layout, program_terms,
                                      run_conelp)
from acmm.design.sector_lqr import eigen_conditioning, sector_margin, sector_robustness
from acmm_qpp.errors import DesignError

try:                  # GPL-3 (README, Dependencies): without it the route solves with Clarabel only
    import cvxopt
    from cvxopt import dsdp
except ImportError:   # pragma: no cover - exercised by uninstalling cvxopt (or a build without DSDP)
    dsdp = None

#: Clarabel options of every solve besides the tolerances: one thread.  Its solver threads are not
#: fork-safe (a forked child of a process that has solved a program with them hung in its next
#: solve: the LMI stair-case's points on the process pool after an in-process LMI design), and one
#: thread makes the result independent of the machine's core count; on these programs (a dense
#: KKT factorization per iteration) more threads were not faster.
CLARABEL_OPTIONS = {"max_threads": 1}

_RELAX_HINT = ("relax design.min_margin, design.sector.sigma, design.sector.half_angle_deg or "
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
    regularization : float
        ε of the objective's ε (tr X̃ + tr X̃₂), which makes its optimum attained (module
        docstring, "Well-posed"), dimensionless.
    solver : str
        The SDP solver tried first (:data:`SOLVERS`): ``"conelp"``, ``"dsdp"`` or ``"clarabel"``;
        the others follow, in that order, as fallbacks when its answer fails the checks.
    tol : float
        The solvers' tolerance of the final pass (conelp's relative gap and feasibility; DSDP's
        relative gap; Clarabel's tol_gap_abs = tol_gap_rel = tol_feas), dimensionless.
    max_iter : int
        Iteration limit per pass of conelp and Clarabel (a guard: they stop on their tolerances).
    refinements : int
        Largest number of Clarabel's re-pre-conditioned passes after the first.
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
    regularization: float = 1e-5
    solver: str = "conelp"
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
        Sector margin proved by X and K, less a rounding allowance (:func:`certified_margin`), units of n.
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
        tr W, the cost LMIs' upper bound of ``energy`` (energy ≤ it is checked), in the units of
        ``energy``.
    status : str
        The accepting solver's own status of its last pass (information only: the answer is
        accepted on the checks of :func:`regional_lmi`).
    tol : float
        The solvers' gap tolerance, dimensionless.
    iterations : tuple of int
        Iterations of each pass (0 where the solver does not report them: DSDP).
    solve_time : float
        Wall time of every solve tried, s.
    solver : str
        The solver whose answer was accepted.
    lmi_residual : float
        Largest eigenvalue of the cost LMIs at the answer relative to their norm (≤
        :data:`COST_TOL`), dimensionless.
    rejected : tuple of str
        The solvers tried before it and why their answers were refused.
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
    solver: str = "dsdp"
    lmi_residual: float = 0.0
    rejected: tuple = ()

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
def _blocks(Az, Bz, GG, X, X2, Y, W, a, c, phi, r, beta, bmat):
    """Every LMI of the program as a matrix that must be ⪯ 0 (numpy arrays or cvxpy expressions):
    the half-plane, the shifted cone, the optional disk, the dilated H2 condition and the cost."""
    M = Az @ X - Bz @ Y
    Mc = M + c * X
    out = [M + M.T + 2 * a * X,
           bmat([[np.sin(phi) * (Mc + Mc.T), np.cos(phi) * (Mc - Mc.T)],
                 [np.cos(phi) * (Mc.T - Mc), np.sin(phi) * (Mc + Mc.T)]])]
    if r > 0:
        out.append(bmat([[-r * X, M], [M.T, -r * X]]))
    out += [bmat([[-2 * beta * X, X2 - X + beta * M.T], [X2 - X + beta * M, M + M.T + GG]]),
            -bmat([[W, Y], [Y.T, 2 * X - X2]])]
    return out


@dataclass(frozen=True)
class LMIProgram:
    """The program in the coordinates x̃ = T z, as data: minimize cᵀv subject to
    F0_k + Σ_i v_i F_ik ⪯ 0 for every block k.

    v stacks the upper triangles of X and X₂ (row by row), Y (m × N, row by row) and the upper
    triangle of W.  The objective is tr(S W S) + ε (tr X' + tr X₂') with S = diag(s_u) and X'
    the matrix in the regularization's coordinates (module docstring, "Well-posed").

    Attributes
    ----------
    Az, Bz : arrays
        T⁻¹ÃT and T⁻¹B̃ diag(s_u), dimensionless (time in 1/n).
    GG : (N, N) array
        T⁻¹G̃G̃ᵀT⁻ᵀ, dimensionless.
    T : (N, N) array
        The coordinates x̃ = T z, dimensionless.
    s_u : (m,) array
        Input column scaling, dimensionless.
    pars : tuple of float
        (a, c, φ, r, β): half-plane shift σ + μ and cone-apex shift μ/sin φ (units of n), φ (rad),
        disk radius (units of n, 0 = none), dilation β (units of 1/n).
    c : (n_var,) array
        Objective coefficients, dimensionless.
    F0 : list of arrays
        Constant term of each block, dimensionless.
    terms : list of list of Term
        Each block's linear part, F_k(v) − F0_k = Σ_t Sym(P_t V_t Q_tᵀ)
        (:func:`acmm.design.lmi_structure.program_terms`; :meth:`coefficients` gives the F_ik).
    reg : (N, N) array
        ε R with ε (tr X' + tr X₂') = tr(reg X) + tr(reg X₂) in these coordinates, dimensionless.
    """

    Az: np.ndarray
    Bz: np.ndarray
    GG: np.ndarray
    T: np.ndarray
    s_u: np.ndarray
    pars: tuple
    c: np.ndarray
    F0: list
    terms: list
    reg: np.ndarray

    @property
    def sizes(self):
        """(N, m): states and inputs."""
        return self.Bz.shape

    def coefficients(self) -> list:
        """The coefficient F_ik of every variable in every block, the data of a general SDP
        solver (:func:`acmm.design.lmi_structure.coefficient_arrays`).

        Returns
        -------
        list of (n_var, m_k, m_k) arrays
            Dimensionless.
        """
        return coefficient_arrays(self.terms, layout(*self.sizes))

    def unpack(self, v):
        """The matrices of a variable vector.

        Parameters
        ----------
        v : (n_var,) array
            Variable vector, dimensionless.

        Returns
        -------
        tuple of arrays
            (X, X₂, Y, W) in the coordinates z, dimensionless.
        """
        N, m = self.sizes
        iu, ium = np.triu_indices(N), np.triu_indices(m)
        nS, nY = iu[0].size, N * m
        return (_sym(v[:nS], N, iu), _sym(v[nS:2 * nS], N, iu), v[2 * nS:2 * nS + nY].reshape(m, N),
                _sym(v[2 * nS + nY:], m, ium))

    def pack(self, X, X2, Y, W):
        """The variable vector of matrices (the inverse of :meth:`unpack`).

        Parameters
        ----------
        X, X2, Y, W : arrays
            (N, N), (N, N), (m, N), (m, m) in the coordinates z, dimensionless.

        Returns
        -------
        (n_var,) array
            Variable vector, dimensionless.
        """
        N, m = self.sizes
        iu, ium = np.triu_indices(N), np.triu_indices(m)
        return np.concatenate([X[iu], X2[iu], np.asarray(Y).ravel(), W[ium]])

    def blocks(self, v):
        """Every LMI block at a variable vector.

        Parameters
        ----------
        v : (n_var,) array
            Variable vector, dimensionless.

        Returns
        -------
        list of arrays
            The blocks (each ⪯ 0 where ``v`` is feasible), dimensionless.
        """
        X, X2, Y, W = self.unpack(v)
        return _blocks(self.Az, self.Bz, self.GG, X, X2, Y, W, *self.pars, np.block)

    def result(self, v):
        """The gain and the certificates of a variable vector in the scaled coordinates.

        Parameters
        ----------
        v : (n_var,) array
            Variable vector, dimensionless.

        Returns
        -------
        tuple of arrays
            (K̃, X̃, X̃₂), scaled coordinates (time in 1/n), dimensionless.
        """
        X, X2, Y, _ = self.unpack(v)               # (symmetric to the bit)
        Kz = self.s_u[:, None] * np.linalg.solve(X, Y.T).T
        Xs, X2s = self.T @ X @ self.T.T, self.T @ X2 @ self.T.T
        return Kz @ np.linalg.inv(self.T), 0.5 * (Xs + Xs.T), 0.5 * (X2s + X2s.T)


def _sym(v, N, iu):
    M = np.zeros((N, N))
    M[iu] = v
    return M + M.T - np.diag(np.diag(M))


def lmi_program(As, Bs, Gs, T, s_u, st: "RegionalLMISettings", T_reg=None) -> LMIProgram:
    """The regional LMI program of the scaled model in the coordinates x̃ = T z, input columns
    scaled by ``s_u``, as :class:`LMIProgram` data (F0 the blocks at v = 0 and the terms of
    :func:`acmm.design.lmi_structure.program_terms`).

    Parameters
    ----------
    As, Bs, Gs : arrays
        Scaled model and disturbance input (time in 1/n), dimensionless.
    T : (N, N) array
        Coordinates x̃ = T z, dimensionless.
    s_u : (m,) array
        Input column scaling, dimensionless.
    st : RegionalLMISettings
        Regions, dilation and regularization.
    T_reg : (N, N) array or None
        The coordinates x̃ = T_reg z' in which the regularization is ε (tr X' + tr X₂'): the
        reference loop's (module docstring, "Well-posed"), dimensionless; None = ``T``.

    Returns
    -------
    LMIProgram
        The program data.
    """
    N, m = Bs.shape
    Ti = np.linalg.inv(T)
    Az, Bz, Gz = Ti @ As @ T, Ti @ Bs * s_u[None, :], Ti @ Gs
    phi = np.deg2rad(st.half_angle_deg)
    mu = st.min_margin + st.backoff
    pars = (st.sigma + mu, mu / np.sin(phi), phi, st.disk_radius, st.dilation)
    iu, ium = np.triu_indices(N), np.triu_indices(m)
    P = np.eye(N) if T_reg is None else np.linalg.solve(T_reg, T)
    TT = P.T @ P
    reg = st.regularization * TT[iu] * np.where(iu[0] == iu[1], 1.0, 2.0)        # tr(reg X) over X's upper triangle
    c = np.concatenate([reg, reg, np.zeros(m * N), (s_u[ium[0]] * s_u[ium[1]]) * np.where(ium[0] == ium[1], 1.0, 0.0)])
    prog = LMIProgram(Az, Bz, Gz @ Gz.T, T, s_u, pars, c, [], program_terms(Az, Bz, pars), st.regularization * TT)
    return replace(prog, F0=prog.blocks(np.zeros(c.size)))            # the blocks at v = 0


# ---------------------------------------------------------------------------------------------
# the solvers: each returns (status, variable vector or None, iterations)
# ---------------------------------------------------------------------------------------------
#: Serializes cvxopt's module-level DSDP options and the call that reads them (threads of one process).
_DSDP_OPTIONS_LOCK = threading.Lock()

#: Gap tolerance of DSDP's first (pre-conditioning) pass, dimensionless.
DSDP_FIRST_TOL = 1e-4

#: DSDP's box |v_i| ≤ bound on the variables in the reference loop's coordinates (where X, X₂ are
#: O(1)–O(10³) at the optimum): an answer with any |v_i| above half of it is refused, so the box
#: never changes the optimum.  With DSDP's default 1e7 its iterates stalled well above the optimum
#: (MB3).
DSDP_BOUND = 1e5


def _solve_dsdp(prog: LMIProgram, tol: float):
    """DSDP 5 (dual scaling, Schur complement with low-rank data) through ``cvxopt.dsdp.sdp``:
    the blocks as sparse lower triangles, gap tolerance ``tol``."""
    Gs = []
    for F in prog.coefficients():
        n_var, mk, _ = F.shape
        G = F.reshape(n_var, mk * mk).T.copy()          # column i = vec(F_i) (symmetric: any order)
        G[~np.tril(np.ones((mk, mk), bool)).ravel(order="F")] = 0.0
        Gs.append(cvxopt.sparse(cvxopt.matrix(G)))                      # its nonzero entries
    hs = [cvxopt.matrix(-F0) for F0 in prog.F0]
    options = {"DSDP_GapTolerance": tol, "DSDP_MaxIts": 500, "DSDP_Monitor": 0}
    with _DSDP_OPTIONS_LOCK:            # cvxopt reads its options from module state: one call at a time
        saved = dict(dsdp.options)
        dsdp.options.clear()
        dsdp.options.update(options)
        try:
            status, x, r, _, _ = dsdp.sdp(cvxopt.matrix(prog.c), Gs=Gs, hs=hs, gamma=1e8, beta=DSDP_BOUND)
        finally:
            dsdp.options.clear()
            dsdp.options.update(saved)
    if x is None:
        return "no answer", None, 0
    v = np.array(x).ravel()
    if float(r) > 0 or np.max(np.abs(v)) > 0.5 * DSDP_BOUND:
        return (f"no answer: the LMIs needed relaxing by r = {float(r):.1e}" if float(r) > 0 else
                f"no answer: at the box |v| ≤ {DSDP_BOUND:.0e} (max |v| = {np.max(np.abs(v)):.3g})"), None, 0
    return status, v, 0


def _solve_conelp(prog: LMIProgram, tol: float, feastol: float, max_iter: int = 100, start=None,
                  refinement: int = 2):
    """cvxopt's ``conelp`` on ``prog`` with its :class:`acmm.design.lmi_structure.StructuredKKT`:
    :func:`acmm.design.lmi_structure.run_conelp` (tolerances dimensionless, returns as it does)."""
    return run_conelp(StructuredKKT(prog.terms, layout(*prog.sizes)), prog.c, prog.F0, tol, feastol, max_iter,
                      start, refinement)


def _solve_clarabel_pass(prog: LMIProgram, obj_scale: float, st: "RegionalLMISettings", tol: float):
    """One Clarabel solve of ``prog`` through cvxpy; the objective divided by ``obj_scale``."""
    import cvxpy as cp  # deferred: cvxpy start-up (~1 s), only on the reference route

    N, m = prog.sizes
    X = cp.Variable((N, N), symmetric=True)
    X2 = cp.Variable((N, N), symmetric=True)
    Y = cp.Variable((m, N))
    W = cp.Variable((m, m), symmetric=True)
    cons = [L << 0 for L in _blocks(prog.Az, prog.Bz, prog.GG, X, X2, Y, W, *prog.pars, cp.bmat)]
    S = np.diag(prog.s_u)
    objective = cp.trace(S @ W @ S) + cp.trace(prog.reg @ X) + cp.trace(prog.reg @ X2)
    problem = cp.Problem(cp.Minimize(objective / obj_scale), cons)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            problem.solve(solver=cp.CLARABEL, tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol,
                          max_iter=st.max_iter, **CLARABEL_OPTIONS)
        except cp.error.SolverError as exc:
            return f"solver error: {exc}", None, 0
    iters = int(problem.solver_stats.num_iters or 0)
    if X.value is None:
        return "no answer", None, iters
    return problem.status, prog.pack(X.value, X2.value, Y.value, W.value), iters


def _precondition(Ks, Xs):
    """The next pass's coordinates and input scaling: T ← chol(X̃), s_u = row norms of K̃ T."""
    T = np.linalg.cholesky(Xs)
    return T, np.maximum(np.linalg.norm(Ks @ T, axis=1), 1e-12)


def certified_margin(As, Bs, Ks, X, sigma: float, half_angle_deg: float) -> float:
    """Sector margin proved by the region certificate X for Ã − B̃K̃, less a rounding allowance
    (units of n).

    With X = LLᵀ (Cholesky) and Z = L⁻¹(Ã − B̃K̃)L, the half-plane LMI He(Ã_cl X) + 2aX ⪯ 0 holds
    for every a ≤ a* = −λ_max(Z + Zᵀ)/2 and the cone LMI of M_c = Ã_cl X + cX for every
    c ≤ c* = λ_min(−L₀(Z))/(2 sin φ), L₀(Z) = [[sin φ He Z, cos φ (Z − Zᵀ)], [cos φ (Zᵀ − Z),
    sin φ He Z]] (the generalized eigenvalues of the pencils with X, computed from symmetric
    matrices of the whitened loop Z, whatever the condition of X); the margin is
    min(a* − σ, c* sin φ) − δ, δ the rounding allowance of :func:`whitened_loop`.  −inf if X is not
    ≻ 0 (its Cholesky factorization fails).

    Parameters
    ----------
    As, Bs, Ks : arrays
        Scaled model and gain (time in 1/n), dimensionless.
    X : (N, N) array
        The certificate in the same coordinates, dimensionless.
    sigma, half_angle_deg : float
        The sector (units of n, deg).

    Returns
    -------
    float
        The certified margin, units of n.
    """
    whitened = whitened_loop(As, Bs, Ks, X)
    if whitened is None:
        return float("-inf")
    Z, delta = whitened
    phi = np.deg2rad(half_angle_deg)
    H, S = Z + Z.T, Z - Z.T
    a_star = -0.5 * float(np.max(np.linalg.eigvalsh(H)))
    L0 = np.block([[np.sin(phi) * H, np.cos(phi) * S], [-np.cos(phi) * S, np.sin(phi) * H]])
    c_star = float(np.min(np.linalg.eigvalsh(-L0))) / (2 * np.sin(phi))
    return min(a_star - sigma, c_star * np.sin(phi)) - delta


def whitened_loop(As, Bs, Ks, X):
    """The loop Ã − B̃K̃ whitened by a certificate X = LLᵀ, Z = L⁻¹(Ã − B̃K̃)L, and the first-order
    rounding allowance δ = 8Nε κ(L)(‖Ã‖ + ‖B̃‖‖K̃‖) of forming it: region LMIs in X are decided
    on symmetric matrices of Z, whatever the condition of X (:func:`certified_margin`,
    ``acmm.design.robust._region_certificate``).

    Parameters
    ----------
    As, Bs, Ks : arrays
        Scaled model and gain (time in 1/n), dimensionless.
    X : (N, N) array
        The certificate in the same coordinates, dimensionless.

    Returns
    -------
    tuple or None
        (Z (N, N) array, δ float), dimensionless; None when X is not ≻ 0 (its Cholesky
        factorization fails) or Z is not finite.
    """
    X = 0.5 * (X + X.T)
    try:
        L = np.linalg.cholesky(X)
    except np.linalg.LinAlgError:
        return None
    Z = sla.solve_triangular(L, (As - Bs @ Ks) @ L, lower=True)
    if not np.all(np.isfinite(Z)):
        return None
    delta = 8 * X.shape[0] * np.finfo(float).eps * np.linalg.cond(L) * (
        np.linalg.norm(As, 2) + np.linalg.norm(Bs, 2) * np.linalg.norm(Ks, 2))
    return Z, delta


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
        No solver returned a gain that passes the checks (X̃ ≻ 0, certified and actual sector
        margin ≥ μ, the disk, the cost LMIs): one line naming each solver's outcome and the
        settings to relax.  It never claims the regions infeasible: a solver's failure is no
        proof of that.
    """
    st = settings
    if not (n > 0 and st.sigma > 0 and 0 < st.half_angle_deg < 90 and st.min_margin >= 0
            and st.dilation > 0 and st.backoff >= 0 and st.disk_radius >= 0 and st.tol > 0
            and st.regularization >= 0 and st.solver in KNOWN_SOLVERS):
        raise ValueError("need n > 0, sigma > 0, 0 < half_angle_deg < 90, min_margin ≥ 0, dilation > 0, "
                         f"disk_radius ≥ 0, tol > 0, regularization ≥ 0, solver in {KNOWN_SOLVERS}")
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    N = B.shape[0]
    d = np.ones(N) if scale is None else np.asarray(scale, dtype=float)
    As, Bs = scaled_model(A, B, n, d, input_scale)
    Gs = -Bs if G is None else np.asarray(G, dtype=float) / d[:, None] * input_scale / n
    K0 = np.asarray(K_ref, dtype=float) * d[None, :] / input_scale
    Acl0 = As - Bs @ K0
    if np.max(np.linalg.eigvals(Acl0).real) > -st.sigma:
        raise DesignError("regional LMI: the reference gain does not give Re λ ≤ −σn; "
                          "pass the sector LQR's gain as K_ref")
    X0 = sla.solve_continuous_lyapunov(Acl0 + st.sigma * np.eye(N), -(Gs @ Gs.T + 1e-3 * np.eye(N)))
    T0 = np.linalg.cholesky(0.5 * (X0 + X0.T))
    # the configured solver first (where installed), then the others in SOLVERS order
    order = tuple(dict.fromkeys(x for x in (st.solver,) + SOLVERS if x in ROUTES))
    if st.solver not in ROUTES:
        warnings.warn(f"regional LMI: design.lmi.solver {st.solver!r} is not installed (cvxopt); "
                      f"solving with {order[0]}", RuntimeWarning, stacklevel=2)
    rejected = []
    ts = time.perf_counter()
    for k, solver in enumerate(order):
        try:
            status, iters, sol = ROUTES[solver](As, Bs, Gs, K0, T0, st)
            reason = status if sol is None else _rejection(As, Bs, Gs, sol, st, n)
        except (KeyboardInterrupt, SystemExit):
            raise
        except BaseException as exc:        # a crash (a Rust panic is a BaseException) is the solver's failure
            status, iters, sol = "error", (0,), None
            reason = f"{type(exc).__name__}: {exc}"
        if reason is None:
            break
        # the solver's own words stay out of the message: its "infeasible" is no checked certificate
        rejected.append(f"{solver}: {reason}")
        if k + 1 < len(order):
            warnings.warn(f"regional LMI: {solver} returned no gain that passes the checks ({reason}); "
                          f"trying {order[k + 1]}", RuntimeWarning, stacklevel=2)
    else:
        raise DesignError("regional LMI: no solver returned a gain that passes the checks ("
                          + "; ".join(rejected) + ")", hint=_RELAX_HINT)
    solve_time = time.perf_counter() - ts
    Ks, Xs, X2s, cost, lmi_residual = sol
    lam, _, _, kappa = eigen_conditioning(As - Bs @ Ks)
    order = np.lexsort((lam.imag, lam.real))
    poles, kappa = lam[order] * n, kappa[order]
    K = Ks / d[None, :] * input_scale
    e_norm, e_elem = sector_robustness(A, B, K, n, st.sigma, st.half_angle_deg, scale=d)
    return RegionalLMI(K=K, X=Xs, X2=X2s, poles=poles,
                       margin=float(np.min(sector_margin(poles, n, st.sigma, st.half_angle_deg))),
                       certified_margin=certified_margin(As, Bs, Ks, Xs, st.sigma, st.half_angle_deg),
                       eig_condition=kappa, robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                       random_radius=random_gain_radius(A, B, K, n, st.sigma, st.half_angle_deg, st.n_random, st.seed),
                       energy=control_energy(A, B, K, n, d, input_scale, G), cost_bound=cost, status=status,
                       tol=st.tol, iterations=tuple(iters), solve_time=solve_time, solver=solver,
                       lmi_residual=lmi_residual, rejected=tuple(rejected))


def _two_passes(As, Bs, Gs, K0, T, st, first, second):
    """DSDP's and conelp's passes: ``first(prog)`` in the reference loop's coordinates (T, input columns
    scaled to the reference gain's rows) to a loose gap, then ``second(prog, prog2, answer)`` in the
    first answer's (T ← chol X̃, unit gain rows; the optimum is X ≈ I) to ``st.tol``, which makes the
    answer independent of rounding (one pass stalls at a point that moves with the BLAS kernel).  A
    refused second pass is not replaced by the first: the fallback solver answers instead.  Both
    solves return (status, v or None, iterations, ...); returns (status, iterations, solution or None)."""
    prog = lmi_program(As, Bs, Gs, T, np.maximum(np.linalg.norm(K0 @ T, axis=1), 1e-12), st)
    answer = first(prog)
    status, v, it = answer[:3]
    if v is None:
        return status, (it,), None
    sol = _solution(prog, v)
    prog2 = lmi_program(As, Bs, Gs, *_precondition(sol[0], sol[1]), st, T_reg=T)
    status, v, it2 = second(prog, prog2, answer)[:3]
    return status, (it, it2), None if v is None else _solution(prog2, v)


def _route_dsdp(As, Bs, Gs, K0, T, st):
    """DSDP in :func:`_two_passes`, the first to the gap :data:`DSDP_FIRST_TOL` (cvxopt's interface
    reports no iteration count: 0)."""
    return _two_passes(As, Bs, Gs, K0, T, st, lambda prog: _solve_dsdp(prog, max(st.tol, DSDP_FIRST_TOL)),
                       lambda prog, prog2, answer: _solve_dsdp(prog2, st.tol))


#: Relative gap and feasibility tolerances of conelp's first (pre-conditioning) pass, dimensionless
#: (a feasibility tolerance of 1e-2 let cvxopt declare MB3 "primal infeasible" on a spurious
#: certificate: its answer would then be no answer, and the fallback solver's).
CONELP_FIRST_TOL = (1e-1, 1e-3)

#: Largest feasibility tolerance of conelp's second pass, dimensionless: the answer must hold the
#: cost LMIs to :data:`COST_TOL` of their norm, which a looser ``tol`` (1e-3) alone did not.
CONELP_FEASTOL = 1e-7


def _route_conelp(As, Bs, Gs, K0, T, st):
    """cvxopt's conelp with the program's structured KKT solver (:mod:`acmm.design.lmi_structure`)
    in :func:`_two_passes`: the first to :data:`CONELP_FIRST_TOL`, the second to the relative gap
    ``st.tol`` and the feasibility min(``st.tol``, :data:`CONELP_FEASTOL`), started from the first
    pass's last iterate carried into its coordinates (:func:`_carry_iterate`: the same program, so
    the same point, residuals and gap)."""
    feastol = min(st.tol, CONELP_FEASTOL)

    def second(prog, prog2, answer):
        try:
            start = _carry_iterate(prog, prog2, answer[1], answer[3])
            return _solve_conelp(prog2, st.tol, feastol, st.max_iter, start=start)
        except ValueError:          # cvxopt refused the carried iterate (not interior after rounding)
            return _solve_conelp(prog2, st.tol, feastol, st.max_iter)

    return _two_passes(As, Bs, Gs, K0, T, st,
                       lambda prog: _solve_conelp(prog, *CONELP_FIRST_TOL, st.max_iter, refinement=1), second)


def _carry_iterate(prog: LMIProgram, prog2: LMIProgram, v, iterate):
    """An interior-point iterate (v, slacks s_k, duals z_k) of ``prog`` as one of ``prog2``, the same
    program in other coordinates: with P = T₂⁻¹T₁ and D = diag(s_u₁/s_u₂) the variables map as
    X ↦ PXPᵀ, X₂ ↦ PX₂Pᵀ, Y ↦ DYPᵀ, W ↦ DWD, every block as F ↦ R F Rᵀ (R = I ⊗ P, the cost
    block's diag(D, P)), so s ↦ R s Rᵀ and z ↦ R⁻ᵀ z R⁻¹: the same objective, blocks up to the
    congruence, and sᵀz (cvxopt's normalized residuals differ, and it restarts its homogeneous
    embedding with τ = κ = 1).  ``iterate`` = (slacks, duals), lists of symmetric arrays; all
    dimensionless.  Returns (v₂, slacks₂, duals₂) in ``prog2``'s coordinates."""
    N = prog.sizes[0]
    P = np.linalg.solve(prog2.T, prog.T)
    D = np.diag(prog.s_u / prog2.s_u)
    X, X2, Y, W = prog.unpack(v)
    v2 = prog2.pack(P @ X @ P.T, P @ X2 @ P.T, D @ Y @ P.T, D @ W @ D)
    slack, dual = iterate
    s2, z2 = [], []
    for k, (Sk, Zk) in enumerate(zip(slack, dual)):
        R = sla.block_diag(D, P) if k == len(slack) - 1 else np.kron(np.eye(Sk.shape[0] // N), P)
        Ri = np.linalg.inv(R)
        s2.append(R @ Sk @ R.T)
        z2.append(Ri.T @ Zk @ Ri)
    return v2, s2, z2


def _route_clarabel(As, Bs, Gs, K0, T, st):
    """Clarabel through cvxpy: a first pass as pre-conditioner, then up to ``st.refinements``
    passes with T ← chol(X̃) and unit gain rows, the objective divided by the last optimum,
    until Clarabel reports "optimal" (its status only selects the pass; acceptance is by the
    checks): (status, iterations, solution or None)."""
    prog = lmi_program(As, Bs, Gs, T, np.ones(Bs.shape[1]), st)
    status, v, it = _solve_clarabel_pass(prog, 1.0, st, max(st.tol, 1e-6))
    iters = [it]
    if v is None:
        return status, iters, None
    sol = _solution(prog, v)
    for _ in range(st.refinements):
        if status == "optimal" and len(iters) > 1:
            break
        prog = lmi_program(As, Bs, Gs, *_precondition(sol[0], sol[1]), st, T_reg=T)
        status_new, v, it = _solve_clarabel_pass(prog, max(sol[3], 1e-12), st, st.tol)
        iters.append(it)
        if v is None:
            break
        status, sol = status_new, _solution(prog, v)
    return status, iters, sol


#: Every ``design.lmi.solver``, in fallback order.
KNOWN_SOLVERS = ("conelp", "dsdp", "clarabel")

#: The solver routes that can run here (conelp and DSDP only where cvxopt and its DSDP are installed).
ROUTES = {name: route for name, route, here in (("conelp", _route_conelp, conelp_available),
                                                ("dsdp", _route_dsdp, dsdp is not None),
                                                ("clarabel", _route_clarabel, True)) if here}
SOLVERS = tuple(ROUTES)


def _solution(prog: LMIProgram, v):
    """(K̃, X̃, X̃₂, the cost tr(S W S), the largest relative eigenvalue of the cost blocks) of a
    variable vector."""
    W = prog.unpack(v)[3]
    S = np.diag(prog.s_u)
    residual = max(float(np.max(np.linalg.eigvalsh(0.5 * (F + F.T)))) / max(np.linalg.norm(F, 2), 1e-300)
                   for F in prog.blocks(v)[-2:])
    return *prog.result(v), float(np.trace(S @ W @ S)), residual


#: Largest eigenvalue of the cost blocks accepted, relative to their norm (the cost bound holds
#: to this); the regions are checked by the certified margin itself.
COST_TOL = 1e-6


def _rejection(As, Bs, Gs, sol, st, n):
    """Why a solution fails the checks (None: accepted): finite, X̃ ≻ 0, the margin X̃ certifies
    (:func:`certified_margin`, rounding allowance included) and every pole's margin ≥ μ, the
    disk, the cost LMIs to :data:`COST_TOL`, and the control energy ≤ the cost bound tr W."""
    Ks, Xs, X2s, cost, residual = sol
    if not (np.all(np.isfinite(Ks)) and np.all(np.isfinite(Xs)) and np.isfinite(cost)):
        return "answer not finite"
    if np.min(np.linalg.eigvalsh(Xs)) <= 0:
        return "X is not positive definite"
    cert = certified_margin(As, Bs, Ks, Xs, st.sigma, st.half_angle_deg)
    lam = np.linalg.eigvals(As - Bs @ Ks)
    margin = float(np.min(sector_margin(lam * n, n, st.sigma, st.half_angle_deg)))
    if margin < st.min_margin or cert < st.min_margin:
        return f"worst sector margin {margin:.4g}n (certified {cert:.4g}n) below {st.min_margin}n"
    fastest = float(np.max(np.abs(lam)))
    if st.disk_radius > 0 and fastest > st.disk_radius * (1 + 1e-6):
        return f"fastest pole |λ| = {fastest:.4g}n outside the disk of radius {st.disk_radius}n"
    if residual > COST_TOL:
        return f"cost LMIs violated by {residual:.1e} (relative)"
    W = sla.solve_continuous_lyapunov(As - Bs @ Ks, -(Gs @ Gs.T))
    energy = float(np.trace(Ks @ W @ Ks.T))
    if not energy <= cost * (1 + 1e-6):
        return f"control energy {energy:.6g} above the cost bound {cost:.6g}"
    return None
