"""The dwell-time LMIs of a stair-case of frozen closed loops (report ch. 5.3 and ch. 6: the
scheduled loop between design points; Geromel & Colaneri 2006), and an interior-point KKT solver
for their chain structure.

For levels A_0 … A_{L−1} (switches only between neighbours, both ways), a dwell T and a decay
rate λ, the program looks for one matrix per level with ::

    P_k ⪰ I,                                   (normalization: the conditions are homogeneous)
    (A_k + λI)ᵀ P_k + P_k (A_k + λI) ⪯ 0,      (V_k = xᵀP_k x decays at rate λ while k holds)
    E_kᵀ P_j E_k ⪯ e^{−2λT} P_k,  E_k = e^{A_k T},  j = k ± 1,

minimizing Σ_k tr P_k.  When it holds, every switching sequence between neighbouring levels whose
levels are each held at least T is exponentially stable with rate λ: a level held τ ≥ T from
x takes V_k(x) to V_j(x(τ)) ≤ e^{−2λT} V_k(e^{A_k(τ−T)}x) ≤ e^{−2λτ} V_k(x).

Every block is a sum of terms Sym(P V Qᵀ) in one or two of the P_k (:class:`acmm.design.lmi_structure.Term`),
so the Schur complement of each Newton step is a sum of Kronecker products of 24 × 24 matrices, and
block tridiagonal: :class:`_ChainKKT` factors it by block Cholesky (12 blocks of 300 at the packaged
stair-case, instead of one dense matrix of 3 600).  An answer is a candidate only:
:mod:`acmm.design.dwell` accepts it on eigenvalue checks of its own.
"""
from __future__ import annotations

import itertools

import numpy as np
import scipy.linalg as sla

from acmm.design.lmi_structure import Layout, StructuredKKT, Term, run_conelp, symmetric_places


def _chain_layout(levels: int, N: int) -> Layout:
    """Layout of ``levels`` symmetric N × N matrices P0, P1, …, each one's upper triangle row by row."""
    place, mirror = symmetric_places(N)
    names = [f"P{k}" for k in range(levels)]
    return Layout({v: (N, N) for v in names}, {v: k * N * N for k, v in enumerate(names)},
                  np.concatenate([k * N * N + place for k in range(levels)]),
                  np.concatenate([np.where(mirror >= 0, k * N * N + mirror, -1) for k in range(levels)]))


def _dwell_terms(As: np.ndarray, T: float, decay: float, R: np.ndarray) -> tuple:
    """(blocks of Terms in the P̂_k, their constant parts F0) of the program, each ⪯ 0, in the
    coordinates P_k = R_kᵀ P̂_k R_k of each level (As 1/time unit, dwell T time units, λ = decay) ::

        I − P̂_k,   (Â_k + λI)ᵀ P̂_k + P̂_k (Â_k + λI),   Ê_kjᵀ P̂_j Ê_kj − e^{−2λT} P̂_k,

    Â_k = R_k A_k R_k⁻¹, Ê_kj = R_j e^{A_k T} R_k⁻¹ (P̂_k ⪰ I is as good as P_k ⪰ I: the rest is
    homogeneous)."""
    L, N = As.shape[:2]
    I, zero = np.eye(N), np.zeros((N, N))
    c = np.exp(-2.0 * decay * T)
    Rinv = [np.linalg.inv(r) for r in R]
    blocks, F0 = [], []
    for k in range(L):
        E = sla.expm(As[k] * T) @ Rinv[k]
        Ak = R[k] @ As[k] @ Rinv[k]
        blocks += [[Term(-0.5 * I, f"P{k}", I)], [Term((Ak + decay * I).T, f"P{k}", I)]]
        F0 += [I, zero]
        for j in (k - 1, k + 1):
            if 0 <= j < L:
                Ekj = R[j] @ E
                blocks.append([Term(0.5 * Ekj.T, f"P{j}", Ekj.T), Term(-0.5 * c * I, f"P{k}", I)])
                F0.append(zero)
    return blocks, F0


class _ChainKKT(StructuredKKT):
    """:class:`acmm.design.lmi_structure.StructuredKKT` for symmetric variables P0, P1, … (terms of
    variables ``"P<k>"``, layout :func:`_chain_layout`) of which a block holds at most two
    neighbours: the Schur complement is block tridiagonal."""

    def __init__(self, blocks, lay: Layout):
        super().__init__(blocks, lay)
        self.levels = len(lay.shapes)
        N = lay.shapes["P0"][0]
        # H_ab = Σ_pairs Σ_(placements of a and b) X[i, k] Y[j, l], a = (i, j), b = (k, l): each
        # pair of terms gives X ⊗ Y, stored as the matrix Σ vec X vec Yᵀ and read at the four
        # placements of an off-diagonal entry (weight 0 where a placement repeats a diagonal one)
        i, j = np.triu_indices(N)
        off = (i != j).astype(float)
        places = ((i, j, np.ones(i.size)), (j, i, off))
        self._gather = [((ri[:, None] * N + ck[None, :]) * N * N + rj[:, None] * N + cl[None, :],
                         wr[:, None] * wc[None, :]) for (ri, rj, wr), (ck, cl, wc) in itertools.product(places, places)]

    def schur_blocks(self, sigma) -> dict:
        """The blocks H_(k,k) and H_(k,k+1) of the Schur complement for the block scalings ``sigma``
        (s.p.d., dimensionless): (k, l) → array over the upper triangles of P_k and P_l, k ≤ l;
        ValueError when a block holds variables that are not neighbours."""
        acc = {}
        for terms, Sg in zip(self.blocks, sigma):
            SP = [Sg @ t.P for t in terms]
            SQ = [Sg @ t.Q for t in terms]
            for a, t in enumerate(terms):
                for b, u in enumerate(terms):
                    key = (int(t.var[1:]), int(u.var[1:]))
                    if key[0] > key[1]:
                        continue                                # the lower blocks are the transposes
                    xs, ys = acc.setdefault(key, ([], []))
                    # tr(Sym(P E_a Qᵀ) Σ Sym(P′ E_b Q′ᵀ) Σ) = 2[(PᵀΣP′)_ik (QᵀΣQ′)_jl + (PᵀΣQ′)_il (QᵀΣP′)_jk]
                    xs += [(t.P.T @ SP[b]).ravel(), (t.P.T @ SQ[b]).ravel()]
                    ys += [(t.Q.T @ SQ[b]).ravel(), (t.Q.T @ SP[b]).ravel()]
        if any(l - k > 1 for k, l in acc):
            raise ValueError("a block holds two variables that are not neighbours")
        out = {}
        for key, (xs, ys) in acc.items():
            M = (np.array(xs).T @ np.array(ys)).ravel()
            out[key] = 2.0 * sum(M[idx] * w for idx, w in self._gather)
        return out

    def factor(self, sigma):
        """Block Cholesky of the block tridiagonal Schur complement: H = LLᵀ with diagonal blocks
        C_k = chol(H_kk − B_{k−1} B_{k−1}ᵀ) and sub-diagonal blocks B_k = H_(k,k+1)ᵀ C_k⁻ᵀ; returns
        ``solve(b)`` = H⁻¹ b (dimensionless).  ArithmeticError when a pivot block is not numerically
        positive definite (cvxopt then stops with status "unknown" and its last iterate, or, at its
        starting point, raises ValueError)."""
        H = self.schur_blocks(sigma)
        L = self.levels
        diag, sub = [], []
        try:
            for k in range(L):
                D = H[(k, k)] - sub[k - 1] @ sub[k - 1].T if k else H[(k, k)]
                diag.append(np.linalg.cholesky(D))
                if k < L - 1:
                    sub.append(sla.solve_triangular(diag[k], H[(k, k + 1)], lower=True, check_finite=False).T)
        except np.linalg.LinAlgError:
            raise ArithmeticError("the Schur complement is not numerically positive definite") from None
        n = diag[0].shape[0]

        def solve(b):
            y = np.empty_like(b)
            for k in range(L):
                r = b[k * n:(k + 1) * n] - sub[k - 1] @ y[(k - 1) * n:k * n] if k else b[:n]
                y[k * n:(k + 1) * n] = sla.solve_triangular(diag[k], r, lower=True, check_finite=False)
            x = np.empty_like(b)
            for k in reversed(range(L)):
                r = y[k * n:(k + 1) * n] - sub[k].T @ x[(k + 1) * n:(k + 2) * n] if k < L - 1 else y[k * n:]
                x[k * n:(k + 1) * n] = sla.solve_triangular(diag[k], r, lower=True, trans="T", check_finite=False)
            return x
        return solve


#: conelp's relative gap and feasibility tolerances: the program is a feasibility question (any
#: point that passes :mod:`acmm.design.dwell`'s checks is a certificate), so the gap is loose
DWELL_TOL = (1e-2, 1e-6)


def solve_dwell_program(As: np.ndarray, T: float, decay: float, R: np.ndarray, max_iter: int = 100):
    """Solve the dwell-time program (module docstring) by cvxopt's ``conelp`` with :class:`_ChainKKT`.

    Parameters
    ----------
    As : (L, N, N) array
        The levels' closed loops, 1/time unit, L ≥ 2.
    T : float
        Dwell, time units.
    decay : float
        λ, 1/time unit.
    R : (L, N, N) array
        Each level's coordinates (:func:`_dwell_terms`): chosen so that the P̂_k are well
        conditioned (e.g. R_kᵀR_k a Lyapunov matrix of level k), dimensionless.
    max_iter : int
        Iteration limit (a guard: the stop is the tolerances :data:`DWELL_TOL`).

    Returns
    -------
    (L, N, N) array or None
        The candidate P_k = R_kᵀ P̂_k R_k (symmetric, dimensionless), or None when cvxopt gives no
        answer (e.g. the program is infeasible at this T).
    """
    L, N = As.shape[:2]
    blocks, F0 = _dwell_terms(As, T, decay, R)
    kkt = _ChainKKT(blocks, _chain_layout(L, N))
    i, j = np.triu_indices(N)
    c = np.tile((i == j).astype(float), L)                      # Σ_k tr P̂_k
    try:
        _, v, _, _ = run_conelp(kkt, c, F0, *DWELL_TOL, max_iter=max_iter, refinement=1)
    except (ArithmeticError, ValueError):
        # a singular Schur complement at cvxopt's start ends in ValueError ("Rank(A) < p ..."), later
        # in an ArithmeticError: no answer at this T
        return None
    if v is None or not np.all(np.isfinite(v)):
        return None
    Ph = np.empty((L, N, N))
    Ph[:, i, j] = Ph[:, j, i] = v.reshape(L, -1)
    P = np.array([r.T @ p @ r for r, p in zip(R, Ph)])
    return 0.5 * (P + P.transpose(0, 2, 1))
