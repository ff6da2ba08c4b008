"""Balanced multiloop disk margin at the plant input of a state-feedback loop (ch. 5.3 checks).

The loop ẋ = A x + B u, u = −K x (eq 4.46 model, sector-LQR gain of ch. 5.2) is broken at the
plant input; with skew 0, α = 1 / max_ω μ_Δ(S(jω) − I/2), μ replaced by its D-scaled upper
bound (:func:`_mu_upper`) on the grid :data:`DISK_OMEGA_N` (units of n), found by branch and
bound over the frequencies (:func:`disk_margin_input`).  :func:`disk_gain_phase` turns α into
the gain and phase margins it guarantees.  Used by :mod:`acmm.design.path_check`.
"""
from __future__ import annotations

import numpy as np


#: Frequencies of the disk-margin evaluation, units of n (log-spaced).
DISK_OMEGA_N = np.logspace(-2.0, 3.0, 121)


def _mu_upper(M: np.ndarray, iters: int = 25, floor=None) -> np.ndarray:
    """min over diagonal D > 0 of σ̄(D M D⁻¹) for stacked square complex M (F, m, m).

    Osborne balancing start, then the fixed point |u_i| = |v_i| of the top singular vectors
    (the optimality condition of the D-scaling for a simple σ̄).  Every iterate is an upper
    bound on μ with respect to m independent complex scalars; for m ≤ 3 the infimum equals μ
    (Packard & Doyle 1993), the iteration approaches it from above.  With ``floor`` (F,), a
    row stops iterating once its bound is below its floor (the caller's lower bound on the
    largest μ that matters), returning that bound.
    """
    F, m, _ = M.shape
    d = np.ones((F, m))
    aM = np.abs(M)
    offdiag = 1.0 - np.eye(m)
    for _ in range(5):
        A = aM * offdiag * d[:, :, None] / d[:, None, :]
        r = np.sqrt((A ** 2).sum(axis=2)) + 1e-300
        c = np.sqrt((A ** 2).sum(axis=1)) + 1e-300
        d = d * np.sqrt(np.sqrt(c / r))
    best = np.full(F, np.inf)
    act = np.arange(F)                      # rows whose D-scaling is still moving
    for _ in range(iters):
        Ma = M[act] * d[act, :, None] / d[act, None, :]
        # σ̄ and the top singular vectors from the 3×3 Hermitian MᴴM (faster than a batched
        # SVD; u = M v/σ̄ — same values to rounding)
        w, X = np.linalg.eigh(np.conj(np.swapaxes(Ma, 1, 2)) @ Ma)
        sig = np.sqrt(np.maximum(w[:, -1], 0.0))
        vv = X[:, :, -1]
        best[act] = np.minimum(best[act], sig)
        u = np.abs(np.einsum("fab,fb->fa", Ma, vv)) / (sig[:, None] + 1e-300) + 1e-300
        v = np.abs(vv) + 1e-300
        step = np.sqrt(v / u)
        d[act] = d[act] * step
        # a row whose scaling no longer moves (relative 1e-12) has reached its fixed point:
        # further iterates repeat its σ̄ to rounding
        keep = np.max(np.abs(step - 1.0), axis=1) > 1e-12
        if floor is not None:
            keep &= best[act] >= floor[act]
        act = act[keep]
        if act.size == 0:
            break
    return best


def disk_margin_input(A, B, K, n: float, scale=None, omega_n=None, *, refine: int = 6):
    """Balanced multiloop disk margin at the plant input of ẋ = Ax + Bu, u = −Kx.

    Loop broken at u: L(s) = K(sI − A)⁻¹B, S = (I + L)⁻¹ = I − K(sI − A + BK)⁻¹B.  With
    skew 0 (Seiler, Packard & Gahinet 2020; python-control ``disk_margins``) ::

        α = 1 / max_ω μ_Δ(S(jω) − I/2),   Δ = diag(δ1, δ2, δ3) complex,

    evaluated here with μ_Δ replaced by its D-scaled upper bound (:func:`_mu_upper`, equal to μ
    for three scalar loops), found by branch and bound over the frequency grid: the bound is
    computed at the frequencies whose cheap upper bound √(‖M‖₁‖M‖∞) or σ̄ still exceeds the
    largest μ found, so α is a guaranteed *lower* bound of the disk margin on the grid and equals
    the D-scaled value there.  python-control's ``disk_margins`` (SLICOT AB13MD
    per frequency, ~2 ms each) computes the same quantity; the tests compare the two on the
    same loops (agreement to 1e-4 relative), this vectorized form keeps the 201-TEA check of
    the design stage at ~0.3 s.

    Parameters
    ----------
    A, B, K : arrays
        Model (physical units) and gain.  Must give a stable closed loop (else α = 0).
    n : float
        Orbital rate, rad/s (frequency unit of ``omega_n``).
    scale : (N,) array or None
        State scaling for the computation (the transfer function is unchanged), in the units of
        each state.
    omega_n : array or None
        Frequencies in units of n; default :data:`DISK_OMEGA_N` (0.01n … 1000n, 121 points).
    refine : int
        Refinement steps of the branch and bound (:func:`disk_alpha_batch`).

    Returns
    -------
    (α, gain margin dB, phase margin deg) : tuple of float
        The disk (α dimensionless), and the gain (dB) / phase (deg) variations it guarantees
        simultaneously in all loops.
    """
    A, B, K = (np.asarray(x, dtype=float) for x in (A, B, K))
    if scale is not None:
        d = np.asarray(scale, dtype=float)
        A, B, K = A / d[:, None] * d[None, :], B / d[:, None], K * d[None, :]
    alpha = float(disk_alpha_batch(disk_parts(A[None], B[None], K[None], n, omega_n), refine)[0])
    return (alpha,) + disk_gain_phase(alpha)


def disk_parts(A, B, K, n, omega_n=None, eig=None) -> list:
    """S(jω) − I/2 on the frequency grid (stacked) and the cheap upper bound √(‖M‖₁‖M‖∞) of
    σ̄ ≥ μ at each frequency, for a stack of loops; None for an unstable closed loop.  Scaled inputs.

    Parameters
    ----------
    A, B : ndarray
        Plant matrices (P×n×n, P×n×m), scaled states (units of the scaled model).
    K : ndarray
        Gains (P×m×n), in the units of the scaled model.
    n : float
        Orbit rate, rad/s (the grid is in units of it).
    omega_n : array_like, optional
        Frequency grid in units of ``n`` (default :data:`DISK_OMEGA_N`).
    eig : tuple, optional
        The eigendecompositions (λ, V) of every A − BK when already computed.

    Returns
    -------
    list
        Per loop (M, bound): M(jω) stacked over the grid (dimensionless) and the upper bound per
        frequency (dimensionless); None when the closed loop is unstable.
    """
    Acl = A - B @ K
    lam, V = np.linalg.eig(Acl) if eig is None else eig
    condV = np.linalg.cond(V)
    try:
        W = np.linalg.inv(V)
    except np.linalg.LinAlgError:
        W = None
    w = n * (DISK_OMEGA_N if omega_n is None else np.asarray(omega_n, dtype=float))
    m = B.shape[-1]
    stable = np.max(lam.real, axis=-1) < 0
    parts = [None] * len(A)
    # every stable, well-conditioned loop in one modal evaluation, the others by a solve per frequency
    fast = stable & (condV < 1e8) & (W is not None)
    if np.any(fast):
        idx = np.flatnonzero(fast)
        KV = K[idx] @ V[idx]                                        # (Q, M, N)
        WB = W[idx] @ B[idx]                                        # (Q, N, M)
        res = 1.0 / (1j * w[None, :, None] - lam[idx][:, None, :])  # (Q, F, N)
        M_all = (0.5 * np.eye(m))[None, None] - np.einsum("qak,qfk,qkb->qfab", KV, res, WB, optimize=True)
        aM = np.abs(M_all)
        cheap = np.sqrt(aM.sum(axis=2).max(axis=2) * aM.sum(axis=3).max(axis=2))
        for r, j in enumerate(idx):
            parts[j] = (M_all[r], cheap[r])
    eye = np.eye(A.shape[-1])
    for j in np.flatnonzero(stable & ~fast):
        S = np.array([np.eye(m) - K[j] @ np.linalg.solve(1j * wk * eye - Acl[j], B[j]) for wk in w])
        M = S - 0.5 * np.eye(m)[None]
        aM = np.abs(M)
        parts[j] = (M, np.sqrt(aM.sum(axis=1).max(axis=1) * aM.sum(axis=2).max(axis=1)))
    return parts


def disk_alpha_batch(parts, refine: int = 6, rounds: int = 6) -> np.ndarray:
    """Disk margin α = 1/max_ω μ(M(ω)) for several loops at once (None → 0), exact to the
    D-scaling bound on the grid by branch and bound: μ is computed (batched over loops) at the
    frequencies whose upper bound (√(‖M‖₁‖M‖∞), then σ̄) still exceeds the largest μ found.

    Parameters
    ----------
    parts : list
        :func:`disk_parts` of each loop (None for an unstable one).
    refine : int, optional
        Refinements of the D-scaling iteration per round.
    rounds : int, optional
        Rounds of branch and bound.

    Returns
    -------
    ndarray
        α of each loop (dimensionless; 0 for an unstable one).
    """
    P = len(parts)
    ub = [None if p is None else p[1].copy() for p in parts]      # current upper bound per freq
    exact = [None if p is None else np.zeros(p[1].size, bool) for p in parts]
    best = np.zeros(P)
    # a lower bound of the largest μ per loop: max|M_ii| ≤ μ(M) and ρ(M) ≤ μ(M) at every
    # frequency, so a frequency whose D-scaled bound falls below the largest of these cannot
    # set α (its iteration may stop there; α is unchanged)
    low = np.array([0.0 if p is None else float(np.max(np.abs(np.diagonal(p[0], axis1=1, axis2=2))))
                    for p in parts])
    for rnd in range(rounds + 1):
        pick = []
        for j, p in enumerate(parts):
            if p is None:
                continue
            open_ = np.flatnonzero(~exact[j] & (ub[j] > best[j] * (1 + 1e-9)))
            if open_.size == 0:
                continue
            order = open_[np.argsort(-ub[j][open_])]
            pick.append((j, order if rnd == rounds else order[:refine]))
        if not pick:
            break
        Ms = np.concatenate([parts[j][0][f] for j, f in pick])
        rho = np.max(np.abs(np.linalg.eigvals(Ms)), axis=1)
        cuts = np.cumsum([f.size for _, f in pick])[:-1]          # each loop's rows of Ms
        for (j, f), r in zip(pick, np.split(rho, cuts)):
            low[j] = max(low[j], float(np.max(r)))
        floor = np.concatenate([np.full(f.size, max(low[j], best[j])) for j, f in pick])
        sig = np.linalg.norm(Ms, ord=2, axis=(1, 2))
        mu = np.minimum(sig, _mu_upper(Ms, floor=floor))
        for (j, f), m in zip(pick, np.split(mu, cuts)):
            ub[j][f] = m
            exact[j][f] = True
            best[j] = max(best[j], float(np.max(m)))
    return np.array([0.0 if p is None else 1.0 / max(np.max(ub[j]), best[j]) for j, p in enumerate(parts)])


def disk_gain_phase(alpha: float) -> tuple[float, float]:
    """Gain (dB) and phase (deg) margins guaranteed by a balanced disk of size α (skew 0).

    Parameters
    ----------
    alpha : float
        Disk size α, dimensionless.

    Returns
    -------
    (gain margin, phase margin) : tuple of float
        Gain margin, dB, and phase margin, deg.
    """
    if alpha >= 2.0:
        return float("inf"), 90.0
    gmin = (1 - 0.5 * alpha) / (1 + 0.5 * alpha)
    gmax = (1 + 0.5 * alpha) / (1 - 0.5 * alpha)
    dgm = 20.0 * np.log10(min(1.0 / gmin, gmax))
    c = (1 + gmin * gmax) / (gmin + gmax)
    dpm = float(np.degrees(np.arccos(c))) if abs(c) < 1 else float("inf")
    return float(dgm), dpm
