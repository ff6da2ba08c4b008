"""A stability certificate of the stair-case as a switched linear system (report ch. 5.3, ch. 6).

The report says of the scheduled stair-case (ch. 5.3) that "there is no systematic procedure to
determine the performance and the stability characteristics … other than to exhaustively
simulate".  The stair-case is, however, a *switched* system: level k holds the inertia I_k for
τ_k seconds, its frozen closed loop (eq 4.46 linearized about the level's TEA, eqs 4.1–4.3, with
the scheduled gain, eq 5.1) is ẋ = A_k x with A_k = A(I_k, θ*_k) − B(I_k, θ*_k) K_k.  This module
certifies it with one Lyapunov function per level and a minimum dwell time (Geromel & Colaneri
2006), in the common scaled coordinates x = D x̃:

1. a decay rate λ = α/64, α = −max_k max Re λ(A_k) the slowest level's (:data:`DECAY_FRACTION`:
   any λ > 0 gives a certificate, and the smallest certified dwell grows with λ);
2. for a dwell T, matrices P_k found by the LMIs of :mod:`acmm.design.dwell_program` (solved for
   the rate 2λ) and *accepted only on checks computed here* (:func:`dwell_margins`): P_k ≻ 0,
   (A_k + λI)ᵀP_k + P_k(A_k + λI) ≺ 0 and e^{A_kᵀT} P_j e^{A_k T} ≺ e^{−2λT} P_k for the levels
   j = k ± 1 that can follow k (switches both ways), by symmetric eigenvalues less a first-order
   rounding allowance.  Then every switching sequence between neighbouring levels whose levels
   are each held at least T is exponentially stable with rate λ (V = xᵀP_σ x falls by e^{−2λτ}
   over every level held τ ≥ T);
3. the certified minimum dwell τ*: the smallest T so certified, found by bisection
   (:func:`smallest_dwell`, feasibility grows with T) to :data:`DWELL_RESOLUTION`; ``tau_lower``
   is the largest dwell tried that the program did not certify (not a proof that none exists);
4. the transient caused by each level's TEA step: at the switch into level j the state's deviation
   from the new equilibrium jumps by δ_j (the change of the TEA in the attitude states and of the
   LVLH rate ω* = C_BL(0, −n, 0) in the rate states), so s_j = √V_j after the switch obeys
   s_j ≤ q_i e^{−λ τ_i} s_i + √V_j(δ_j), q_i = 1 when τ_i ≥ τ* and √μ_{j←i} otherwise
   (μ_{j←i} = λ_max(P_i⁻¹ P_j), V_j ≤ μ_{j←i} V_i), s_0 = √V_0 of the initial state's
   deviation from the first equilibrium (``simulation.initial_offset``; 0 when the run starts
   there); while level j holds |u_a| ≤ s_j √(K_a P_j⁻¹ K_aᵀ) and |h_a| ≤ s_j √((P_j⁻¹)_aa),
   checked against the torque and momentum limits.

An earlier certificate (Hespanha & Morse 1999: one common decay rate λ′, P_k from Lyapunov
equations, τ* = ln μ / (2λ′)) is never sharper: its P_k satisfy the LMIs of step 2 at the rate
λ < λ′ from T = ln μ / (2(λ′ − λ)) on.

What it does not cover is stated with every certificate (:data:`NOT_COVERED`: the nonlinear plant,
eqs 3.1–3.9, away from the equilibria among others).  The cores take arrays and return arrays; the
stage gathers the levels from a scenario.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from acmm.design.dwell_program import solve_dwell_program

#: the decay rate the certificate proves, as a fraction of the slowest level's decay rate α
#: (a power of two: the program's coordinates are scaled by it exactly)
DECAY_FRACTION = 1.0 / 64.0

#: the program is solved for this multiple of the proved decay rate, so that an answer on the
#: edge of its LMIs still proves the rate λ with room for rounding
SOLVE_FACTOR = 2.0

#: bisection resolution of τ* and its first upper end, in units of 1/α (α the slowest level's
#: decay rate); the upper end doubles until a dwell is certified
DWELL_RESOLUTION = 1.0 / 8.0
FIRST_UPPER = 1.0

#: the bisection gives up (no certificate, τ* infinite) once the upper end passes this many
#: units of 1/α
UPPER_LIMIT = 1024.0

#: what a dwell-time certificate never covers, printed and stored with it
NOT_COVERED = ("the nonlinear plant away from each level's equilibrium, the torque and momentum "
               "saturations, the cyclic disturbance torque (eq 3.9, rejected by the DRFs in steady "
               "state) and each level's equilibrium CMG momentum")


@dataclass(frozen=True)
class DwellProof:
    """The stability part of a dwell-time certificate (steps 1–3), which depends on the levels'
    closed loops only (not on the scenario's dwell times, jumps or limits).

    Attributes
    ----------
    decay : float
        Decay rate λ proved, 1/s.
    tau : float
        Certified minimum dwell τ*, s (0 with one level, infinite when none was found).
    lower : float
        The largest dwell tried and not certified, s.
    P : (L, N, N) array
        Lyapunov matrices in the scaled coordinates, dimensionless (with ``tau`` infinite: the
        Lyapunov equations' at rate λ, which prove only the decay while a level holds).
    """

    decay: float
    tau: float
    lower: float
    P: np.ndarray


@dataclass(frozen=True)
class DwellCertificate:
    """A dwell-time certificate of a switched linear system (see the module docstring).

    Attributes
    ----------
    decay : float
        Decay rate λ the certificate proves, 1/s (V̇_k ≤ −2λ V_k while a level holds).
    P : (L, N, N) array
        Lyapunov matrices of the levels, in the scaled coordinates x̃ = D⁻¹ x (dimensionless).
    scale : (N,) array
        The scaling D (units of each state).
    jump_up, jump_down : (L-1,) arrays
        μ_{k+1←k} = λ_max(P_k⁻¹ P_{k+1}) and μ_{k←k+1}: the jump ratios into the next level and
        back, dimensionless.
    mu : float
        The worst jump ratio, dimensionless.
    tau_star : float
        Certified minimum dwell time, s (0 with one level; infinite without a certificate).
    tau_lower : float
        The largest dwell the bisection tried and did not certify, s (0 with one level).
    dwell : (L-1,) array
        How long each level but the last is held, s.
    certified : bool
        Every level but the last is held at least τ*.
    transient : (L,) array
        Bound on √V_k of the deviation from the level's equilibrium while level k holds,
        dimensionless (V_k of the scaled state).
    u_bound, h_bound : (L, 3) arrays
        Bounds on |u| (ft·lbf) and on the deviation of |h| (ft·lbf·s) while each level holds.
    torque_limit, momentum_limit : float
        The limits they are checked against (ft·lbf, ft·lbf·s).
    within_limits : bool
        Every bound is below its limit.
    unstable_levels : tuple of int
        Levels whose frozen closed loop is not asymptotically stable (then no certificate exists:
        ``decay`` is NaN, ``tau_star`` infinite, ``certified`` False).
    """

    decay: float
    P: np.ndarray
    scale: np.ndarray
    jump_up: np.ndarray
    jump_down: np.ndarray
    mu: float
    tau_star: float
    tau_lower: float
    dwell: np.ndarray
    certified: bool
    transient: np.ndarray
    u_bound: np.ndarray
    h_bound: np.ndarray
    torque_limit: float
    momentum_limit: float
    within_limits: bool
    unstable_levels: tuple = ()


def lyapunov_matrices(Acl: np.ndarray, decay: float) -> np.ndarray:
    """P_k ≻ 0 with (A_k + λI)ᵀ P_k + P_k (A_k + λI) = −I for every level (the certificate of a
    stair-case with one level).

    Parameters
    ----------
    Acl : (L, N, N) array
        Closed-loop state matrices in scaled coordinates, 1/s.
    decay : float
        λ, 1/s; every A_k + λI must be Hurwitz.

    Returns
    -------
    (L, N, N) array
        The symmetric P_k, dimensionless.
    """
    I = np.eye(Acl.shape[1])
    P = np.array([sla.solve_continuous_lyapunov((A + decay * I).T, -I) for A in Acl], dtype=float)
    return 0.5 * (P + P.transpose(0, 2, 1))


def jump_ratios(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """μ_{k+1←k} = λ_max(P_k⁻¹ P_{k+1}) and μ_{k←k+1} = λ_max(P_{k+1}⁻¹ P_k).

    Parameters
    ----------
    P : (L, N, N) array
        Lyapunov matrices (symmetric positive definite), dimensionless.

    Returns
    -------
    up, down : (L-1,) arrays
        The ratios, dimensionless (≥ 1 unless the two levels' P are ordered).
    """
    up = np.array([sla.eigh(P[k + 1], P[k], eigvals_only=True)[-1] for k in range(len(P) - 1)])
    down = np.array([sla.eigh(P[k], P[k + 1], eigvals_only=True)[-1] for k in range(len(P) - 1)])
    return up, down


def dwell_margins(As: np.ndarray, P: np.ndarray, T: float, decay: float) -> np.ndarray:
    """How far P_0 … P_{L−1} satisfy the dwell-time conditions at T (step 2), relative to the
    matrices' norms and less a first-order allowance for rounding: positive means proved.

    The matrices are scaled together by a power of two (the conditions are homogeneous).  A
    symmetric matrix formed from the data is allowed 8Nu times the norms of its products (u the unit
    roundoff).  The switch condition of level k is decided after the congruence by S_k, the inverse
    Cholesky factor of level k's Lyapunov matrix at the rate λ (congruences keep the signs of
    eigenvalues): there Â_k = S_k⁻¹A_kS_k has a logarithmic norm μ̂_k ≤ −λ, so ‖e^{Â_k s}‖ ≤
    G = e^{max(μ̂_k, 0)T} ≤ 1 for s ∈ [0, T], and the error of scipy's e^{Â_kT} is bounded by G²
    times its backward error (4u‖Â_kT‖, the Padé design of Al-Mohy and Higham, plus the error of
    forming Â_k) and the rounding of its squarings.  Non-finite or asymmetric candidates fail.

    Parameters
    ----------
    As : (L, N, N) array
        The levels' closed loops, 1/s.
    P : (L, N, N) array
        Candidate Lyapunov matrices, dimensionless.
    T : float
        Dwell, s.
    decay : float
        λ, 1/s.

    Returns
    -------
    (3,) array
        The worst margin of P_k ≻ 0, of the decay LMIs and of the switch LMIs (both ways),
        dimensionless (−inf where a candidate cannot be checked).
    """
    L, N = As.shape[:2]
    u = 0.5 * np.finfo(float).eps
    g = 8 * N * u
    fail = np.full(3, -np.inf)
    P = np.asarray(P, float)
    if (P.shape != As.shape or not (np.all(np.isfinite(P)) and np.all(np.isfinite(As)) and np.isfinite(T)
                                    and T >= 0 and decay > 0) or np.any(P != P.transpose(0, 2, 1))):
        return fail
    top = max(np.linalg.norm(p, 2) for p in P)
    if not 0 < top < np.inf:
        return fail
    P = P * 2.0 ** -np.ceil(np.log2(top))                               # exact: every ‖P_k‖ ≤ 1
    try:
        S = [np.linalg.inv(np.linalg.cholesky(Q / np.linalg.norm(Q, 2)).T) for Q in lyapunov_matrices(As, decay)]
    except np.linalg.LinAlgError:
        return fail
    c = np.exp(-2.0 * decay * T)
    I = np.eye(N)
    pos, lyap, jump = [], [], []
    for k in range(L):
        nk = np.linalg.norm(P[k], 2)
        pos.append(np.linalg.eigvalsh(P[k])[0] / nk - g)
        At = As[k] + decay * I
        nA = np.linalg.norm(At, 2)
        M = At.T @ P[k] + P[k] @ At
        lyap.append(-np.linalg.eigvalsh(0.5 * (M + M.T))[-1] / (nA * nk) - 2 * g)
        # the switch condition after the congruence by S_k, where the exponential is a contraction
        Sk, Rk = S[k], np.linalg.inv(S[k])
        Ah = Rk @ As[k] @ Sk
        dA = g * np.linalg.cond(Sk) * np.linalg.norm(Rk, 2) * np.linalg.norm(As[k], 2) * np.linalg.norm(Sk, 2)
        nAh = np.linalg.norm(Ah, 2)
        mu = np.linalg.eigvalsh(0.5 * (Ah + Ah.T))[-1] + dA + g * nAh
        G = np.exp(max(mu, 0.0) * T)
        squarings = max(0, int(np.ceil(np.log2(max(np.linalg.norm(Ah, 1) * T, 1.0))))) + 1
        gamma = G * G * (T * (dA + 4 * u * nAh) + 2 * g * squarings)
        Eh = sla.expm(Ah * T)
        nE = np.linalg.norm(Eh, 2)
        Pk = Sk.T @ P[k] @ Sk
        nSk = np.linalg.norm(Sk, 2) ** 2
        for j in (k - 1, k + 1):
            if 0 <= j < L:
                Pj = Sk.T @ P[j] @ Sk
                nj, nkh = np.linalg.norm(Pj, 2), np.linalg.norm(Pk, 2)
                M = Eh.T @ Pj @ Eh - c * Pk
                allow = (2 * nE * gamma + gamma * gamma) * nj + g * (nE * nE * nj + nkh) + 2 * g * nSk
                jump.append(-(np.linalg.eigvalsh(0.5 * (M + M.T))[-1] + allow) / nkh)
    m = np.array([np.min(pos), np.min(lyap), np.min(jump) if jump else np.inf])
    return m if not np.any(np.isnan(m)) else fail


def smallest_dwell(As: np.ndarray, decay: float) -> tuple:
    """The smallest dwell certified (steps 2–3): T = :data:`FIRST_UPPER`/α, doubled until the
    program's answer passes :func:`dwell_margins`, then bisection to :data:`DWELL_RESOLUTION`/α.

    Parameters
    ----------
    As : (L, N, N) array
        The levels' closed loops (scaled coordinates), 1/s, L ≥ 2, each Hurwitz.
    decay : float
        λ to prove, 1/s.

    Returns
    -------
    tau : float
        The certified dwell, s (infinite when none was found).
    lower : float
        The largest dwell tried and not certified, s.
    P : (L, N, N) array or None
        The matrices that certify ``tau``, dimensionless.
    """
    alpha = min(-np.max(np.linalg.eigvals(A).real) for A in As)
    Au = As / alpha                                     # the program's time unit: 1/α
    rate = SOLVE_FACTOR * decay / alpha
    # each level's coordinates: its Lyapunov matrix at the program's rate, R_kᵀR_k = P_k/‖P_k‖
    R = np.array([np.linalg.cholesky(P / np.linalg.norm(P, 2)).T for P in lyapunov_matrices(Au, rate)])

    def certify(k):
        """The matrices that certify the dwell k·(resolution)/α, or None."""
        P = solve_dwell_program(Au, k * DWELL_RESOLUTION, rate, R)
        return P if P is not None and np.all(dwell_margins(As, P, k * DWELL_RESOLUTION / alpha, decay) > 0) else None

    # the bracket in whole steps of the resolution, so that the steps taken never depend on rounding
    lo, hi = 0, int(round(FIRST_UPPER / DWELL_RESOLUTION))
    P = certify(hi)
    while P is None:
        lo, hi = hi, 2 * hi
        if hi * DWELL_RESOLUTION > UPPER_LIMIT:
            return np.inf, lo * DWELL_RESOLUTION / alpha, None
        P = certify(hi)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        got = certify(mid)
        if got is None:
            lo = mid
        else:
            hi, P = mid, got
    return hi * DWELL_RESOLUTION / alpha, lo * DWELL_RESOLUTION / alpha, P


def dwell_proof(As: np.ndarray) -> DwellProof:
    """Steps 1–3 for the levels' closed loops in scaled coordinates.

    Parameters
    ----------
    As : (L, N, N) array
        D⁻¹ A_k D of every level, 1/s, each Hurwitz.

    Returns
    -------
    DwellProof
        λ = α/64, τ* and its matrices.
    """
    lam = DECAY_FRACTION * min(-np.max(np.linalg.eigvals(A).real) for A in As)
    if len(As) < 2:
        return DwellProof(lam, 0.0, 0.0, lyapunov_matrices(As, lam))
    tau, lower, P = smallest_dwell(As, lam)
    return DwellProof(lam, tau, lower, lyapunov_matrices(As, lam) if P is None else P)


def _reused(As: np.ndarray, proof: DwellProof) -> DwellProof | None:
    """A proof found before, as this module would find it for these levels, or None where it does
    not hold for them: its decay rate must be theirs (to rounding: a design read back from SI units
    differs in the last digits), its dwell and the one below neighbouring steps of this bisection's
    grid, and its matrices must pass :func:`dwell_margins` here.  The rate and the dwells returned
    are computed here (the grid's steps over α), those stored only located."""
    alpha = min(-np.max(np.linalg.eigvals(A).real) for A in As)
    lam = DECAY_FRACTION * alpha
    steps = np.array([proof.tau, proof.lower]) * alpha / DWELL_RESOLUTION
    if not (abs(proof.decay - lam) <= 1e-9 * lam and np.all(np.isfinite(steps))
            and np.all(np.abs(steps - np.round(steps)) <= 1e-6) and round(steps[0]) - round(steps[1]) == 1):
        return None
    tau, lower = (round(k) * DWELL_RESOLUTION / alpha for k in steps)
    return DwellProof(lam, tau, lower, proof.P) if np.all(dwell_margins(As, proof.P, tau, lam) > 0) else None


def dwell_certificate(Acl: np.ndarray, K: np.ndarray, scale: np.ndarray, dwell: np.ndarray, jumps: np.ndarray,
                      h_index, torque_limit: float, momentum_limit: float, start=None,
                      proof: DwellProof | None = None) -> DwellCertificate:
    """The dwell-time certificate of a stair-case of frozen closed loops (steps 1–4).

    Parameters
    ----------
    Acl : (L, N, N) array
        Closed-loop state matrices A_k − B_k K_k of the levels, physical units (1/s).
    K : (L, 3, N) array
        The gain of each level (u = −K x), ft·lbf per state unit.
    scale : (N,) array
        State scaling D (units of each state) of the common coordinates x = D x̃.
    dwell : (L-1,) array
        How long each level but the last is held, s.
    jumps : (L-1, N) array
        δ_{k+1}: the change of the equilibrium state at the switch into level k+1, state units.
    h_index : sequence of 3 int
        Indices of the CMG momentum states h1, h2, h3 in x.
    torque_limit, momentum_limit : float
        |u| limit (ft·lbf) and |h| limit (ft·lbf·s).
    start : (N,) array, optional
        The initial state's deviation from the first level's equilibrium, state units (default:
        the run starts at that equilibrium).
    proof : DwellProof, optional
        Steps 1–3 found before for these closed loops (e.g. stored in ``design.h5``): used when its
        decay rate and grid are these loops' and its matrices pass :func:`dwell_margins` here
        again, else found anew.

    Returns
    -------
    DwellCertificate
        The certificate (``certified`` False when a level is held shorter than τ*).
    """
    d = np.asarray(scale, float)
    Dinv = 1.0 / d
    As = np.array([A * Dinv[:, None] * d[None, :] for A in Acl])          # D⁻¹ A D
    dwell = np.asarray(dwell, float)
    L = len(As)
    unstable = tuple(k for k, A in enumerate(As)
                     if not np.all(np.isfinite(A)) or np.max(np.linalg.eigvals(A).real) >= 0)
    if unstable:
        nan3 = np.full((L, 3), np.nan)
        return DwellCertificate(np.nan, np.full_like(As, np.nan), d, np.full(L - 1, np.nan), np.full(L - 1, np.nan),
                                np.inf, np.inf, 0.0, dwell, False, np.full(L, np.nan), nan3, nan3.copy(),
                                float(torque_limit), float(momentum_limit), False, unstable)
    proof = (_reused(As, proof) if proof is not None and L > 1 else None) or dwell_proof(As)
    lam, tau, P = proof.decay, proof.tau, proof.P
    up, down = jump_ratios(P)                                           # empty with one level
    mu = float(max(np.max(up, initial=1.0), np.max(down, initial=1.0)))
    s = np.zeros(L)
    if start is not None:
        z0 = np.asarray(start, float) * Dinv
        s[0] = np.sqrt(z0 @ P[0] @ z0)
    for k in range(1, L):
        dj = np.asarray(jumps[k - 1], float) * Dinv
        q = 1.0 if dwell[k - 1] >= tau else np.sqrt(up[k - 1])
        s[k] = q * np.exp(-lam * dwell[k - 1]) * s[k - 1] + np.sqrt(dj @ P[k] @ dj)
    Pinv = np.linalg.inv(P)
    Ks = np.asarray(K, float) * d                                         # u = −K D x̃
    h = list(h_index)
    u_bound = s[:, None] * np.sqrt(np.einsum("kai,kij,kaj->ka", Ks, Pinv, Ks))
    h_bound = s[:, None] * d[h] * np.sqrt(np.diagonal(Pinv, axis1=1, axis2=2)[:, h])
    within = bool(np.all(u_bound <= torque_limit) and np.all(h_bound <= momentum_limit))
    return DwellCertificate(lam, P, d, up, down, mu, tau, proof.lower, dwell, bool(L < 2 or np.all(dwell >= tau)), s,
                            u_bound, h_bound, float(torque_limit), float(momentum_limit), within)
