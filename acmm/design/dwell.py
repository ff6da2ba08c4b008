"""A stability certificate of the stair-case as a switched linear system (report ch. 5.3, ch. 6).

The report says of the scheduled stair-case (ch. 5.3) that "there is no systematic procedure to
determine the performance and the stability characteristics … other than to exhaustively
simulate".  The stair-case is, however, a *switched* system: level k holds the inertia I_k for
τ_k seconds, its frozen closed loop (eq 4.46 linearized about the level's TEA, eqs 4.1–4.3, with
the scheduled gain, eq 5.1) is ẋ = A_k x with A_k = A(I_k, θ*_k) − B(I_k, θ*_k) K_k.  This module
certifies it with multiple Lyapunov functions and a dwell time (Hespanha & Morse 1999;
Geromel & Colaneri 2006 in spirit):

1. one decay rate λ > 0 and, per level, P_k ≻ 0 solving the Lyapunov equation
   (A_k + λI)ᵀ P_k + P_k (A_k + λI) = −I in the common scaled coordinates x = D x̃, so that
   V_k(x) = xᵀ P_k x decays at least as e^{−2λt} while level k holds;
2. the jump ratio μ between levels that follow each other, in both directions,
   μ_{j←i} = λ_max(P_i⁻¹ P_j) (V_j ≤ μ_{j←i} V_i): both directions, because a one-way chain can be
   rescaled to any μ and certifies nothing;
3. the certified minimum dwell time τ* = ln μ / (2λ), μ the worst ratio: every switching sequence
   between neighbouring levels (either way) whose levels are each held longer than τ* is
   exponentially stable; λ is the local minimizer of τ* a bounded Brent search finds (the
   certificate holds for any λ in the range; the search only makes τ* small);
4. the transient caused by each level's TEA step: at the switch into level j the state's deviation
   from the new equilibrium jumps by δ_j (the change of the TEA in the attitude states and of the
   LVLH rate ω* = C_BL(0, −n, 0) in the rate states), so s_j = √V_j after the switch obeys
   s_j ≤ √μ_{j←i} e^{−λ τ_i} s_i + √V_j(δ_j), s_0 = √V_0 of the initial state's deviation from
   the first equilibrium (``simulation.initial_offset``; 0 when the run starts there);
   while level j holds |u_a| ≤ s_j √(K_a P_j⁻¹ K_aᵀ) and |h_a| ≤ s_j √((P_j⁻¹)_aa), checked
   against the torque and momentum limits.

What it does not cover (stated with every certificate): the nonlinear plant (3.1–3.9) away from the
equilibria, the saturations, the cyclic aerodynamic disturbance (eq 3.9) that the DRFs reject in
steady state, and the equilibrium CMG momentum of each level.  The cores take arrays and return
arrays; the stage gathers the levels from a scenario.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import minimize_scalar

#: relative tolerance on the decay rate λ that minimizes τ* (bounded Brent search)
DECAY_XTOL = 1e-6

#: the search for λ keeps this fraction of the smallest level decay rate as its upper end, so
#: that every (A_k + λI) stays Hurwitz with room (P_k finite)
DECAY_UPPER_FRACTION = 0.999

#: what a dwell-time certificate never covers, printed and stored with it
NOT_COVERED = ("the nonlinear plant away from each level's equilibrium, the torque and momentum "
               "saturations, the cyclic disturbance torque (eq 3.9, rejected by the DRFs in steady "
               "state) and each level's equilibrium CMG momentum")


@dataclass(frozen=True)
class DwellCertificate:
    """A dwell-time certificate of a switched linear system (see the module docstring).

    Attributes
    ----------
    decay : float
        Common decay rate λ of every level's Lyapunov function, 1/s (V̇_k ≤ −2λ V_k).
    P : (L, N, N) array
        Lyapunov matrices of the levels, in the scaled coordinates x̃ = D⁻¹ x (dimensionless).
    scale : (N,) array
        The scaling D (units of each state).
    jump_up, jump_down : (L-1,) arrays
        μ_{k+1←k} and μ_{k←k+1}: the jump ratios into the next level and back, dimensionless.
    mu : float
        The worst jump ratio, dimensionless.
    tau_star : float
        Certified minimum dwell time ln μ / (2λ), s (0 with one level).
    dwell : (L-1,) array
        How long each level but the last is held, s.
    certified : bool
        Every level is held longer than τ*.
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
    """P_k ≻ 0 with (A_k + λI)ᵀ P_k + P_k (A_k + λI) = −I for every level (step 1).

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
    N = Acl.shape[1]
    out = np.empty_like(Acl, dtype=float)
    for k, A in enumerate(Acl):
        P = sla.solve_continuous_lyapunov((A + decay * np.eye(N)).T, -np.eye(N))
        out[k] = 0.5 * (P + P.T)
    return out


def jump_ratios(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """μ_{k+1←k} = λ_max(P_k⁻¹ P_{k+1}) and μ_{k←k+1} = λ_max(P_{k+1}⁻¹ P_k) (step 2).

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


def _dwell_bound(P: np.ndarray, decay: float) -> tuple:
    """(μ_{k+1←k}, μ_{k←k+1}, worst μ, τ* = ln μ/(2λ) in s) of Lyapunov matrices ``P`` (step 3);
    one level: no switch, μ = 1, τ* = 0."""
    up, down = jump_ratios(P) if len(P) > 1 else (np.zeros(0), np.zeros(0))
    mu = float(max(np.max(up, initial=1.0), np.max(down, initial=1.0)))
    return up, down, mu, float(np.log(mu) / (2.0 * decay))


def _tau_star(Acl: np.ndarray, decay: float) -> float:
    return _dwell_bound(lyapunov_matrices(Acl, decay), decay)[3]


def best_decay(Acl: np.ndarray) -> float:
    """The λ in (0, min_k α_k) minimizing τ* = ln μ(λ) / (2λ), α_k = −max Re λ(A_k) (step 3):
    a bounded Brent search converged to :data:`DECAY_XTOL` relative.

    Parameters
    ----------
    Acl : (L, N, N) array
        Closed-loop state matrices (scaled coordinates), 1/s; each Hurwitz.

    Returns
    -------
    float
        λ, 1/s.

    Raises
    ------
    ValueError
        A level's closed loop is not asymptotically stable (no certificate exists).
    """
    alpha = min(-np.max(np.linalg.eigvals(A).real) for A in Acl)
    if not alpha > 0:
        raise ValueError(f"a level's frozen closed loop is not stable (largest Re λ = {-alpha:+.3g} 1/s)")
    hi = DECAY_UPPER_FRACTION * alpha
    if len(Acl) < 2:
        return hi
    got = minimize_scalar(lambda x: _tau_star(Acl, x * alpha), bounds=(1e-3, DECAY_UPPER_FRACTION),
                          method="bounded", options={"xatol": DECAY_XTOL})
    return float(got.x * alpha)


def dwell_certificate(Acl: np.ndarray, K: np.ndarray, scale: np.ndarray, dwell: np.ndarray, jumps: np.ndarray,
                      h_index, torque_limit: float, momentum_limit: float, decay: float | None = None,
                      start=None) -> DwellCertificate:
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
    decay : float, optional
        λ (1/s); default :func:`best_decay`.
    start : (N,) array, optional
        The initial state's deviation from the first level's equilibrium, state units (default:
        the run starts at that equilibrium).

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
    unstable = tuple(k for k, A in enumerate(As) if np.max(np.linalg.eigvals(A).real) >= 0)
    if unstable:
        nan3 = np.full((L, 3), np.nan)
        return DwellCertificate(np.nan, np.full_like(As, np.nan), d, np.full(L - 1, np.nan), np.full(L - 1, np.nan),
                                np.inf, np.inf, dwell, False, np.full(L, np.nan), nan3, nan3.copy(),
                                float(torque_limit), float(momentum_limit), False, unstable)
    lam = best_decay(As) if decay is None else float(decay)
    P = lyapunov_matrices(As, lam)
    up, down, mu, tau = _dwell_bound(P, lam)
    s = np.zeros(L)
    if start is not None:
        z0 = np.asarray(start, float) * Dinv
        s[0] = np.sqrt(z0 @ P[0] @ z0)
    for k in range(1, L):
        dj = np.asarray(jumps[k - 1], float) * Dinv
        s[k] = np.sqrt(up[k - 1]) * np.exp(-lam * dwell[k - 1]) * s[k - 1] + np.sqrt(dj @ P[k] @ dj)
    u_bound, h_bound = np.empty((L, 3)), np.empty((L, 3))
    for k in range(L):
        Pinv = np.linalg.inv(P[k])
        Ks = K[k] * d[None, :]                                            # u = −K D x̃
        u_bound[k] = s[k] * np.sqrt(np.einsum("ai,ij,aj->a", Ks, Pinv, Ks))
        h_bound[k] = s[k] * d[list(h_index)] * np.sqrt(np.diag(Pinv)[list(h_index)])
    within = bool(np.all(u_bound <= torque_limit) and np.all(h_bound <= momentum_limit))
    return DwellCertificate(lam, P, d, up, down, mu, tau, dwell, bool(L < 2 or np.all(dwell > tau)), s,
                            u_bound, h_bound, float(torque_limit), float(momentum_limit), within)
