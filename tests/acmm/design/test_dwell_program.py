"""The dwell-time program and its chain-structured KKT solver (:mod:`acmm.design.dwell_program`),
checked against the blocks written out from the matrices, a dense Schur complement formed from the
definition H_ab = Σ_k tr(F_k(E_a) Σ_k F_k(E_b) Σ_k), and numpy's dense solve."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design import dwell_program as dp
from acmm.design.lmi_structure import Term

pytest.importorskip("cvxopt")


def _levels(L=3, N=4, seed=0):
    rng = np.random.default_rng(seed)
    return np.array([rng.standard_normal((N, N)) - 3.0 * np.eye(N) for _ in range(L)]), rng


def _sym(v, N):
    i, j = np.triu_indices(N)
    S = np.zeros((N, N))
    S[i, j] = v
    S[j, i] = v
    return S


def _spd(N, rng):
    M = rng.standard_normal((N, N))
    return M @ M.T / N + 0.2 * np.eye(N)


def test_the_terms_are_the_blocks():
    """G v (the blocks' linear parts in the P̂_k) equals the conditions written out with
    P_k = R_kᵀ P̂_k R_k, each congruent by R_k⁻¹."""
    As, rng = _levels()
    L, N = As.shape[:2]
    R = np.array([np.linalg.cholesky(_spd(N, rng)).T for _ in range(L)])
    T, lam = 0.7, 0.1
    blocks, F0 = dp._dwell_terms(As, T, lam, R)
    kkt = dp._ChainKKT(blocks, dp._chain_layout(L, N))
    v = rng.standard_normal(L * N * (N + 1) // 2)
    Ph = [_sym(part, N) for part in np.split(v, L)]
    P = [R[k].T @ Ph[k] @ R[k] for k in range(L)]
    Ri = [np.linalg.inv(r) for r in R]
    want = []
    for k in range(L):
        E = sla.expm(As[k] * T)
        want += [-Ph[k], Ri[k].T @ ((As[k] + lam * np.eye(N)).T @ P[k] + P[k] @ (As[k] + lam * np.eye(N))) @ Ri[k]]
        for j in (k - 1, k + 1):
            if 0 <= j < L:
                want.append(Ri[k].T @ (E.T @ P[j] @ E - np.exp(-2 * lam * T) * P[k]) @ Ri[k])
    got = np.split(kkt._apply(v), kkt.offs[1:-1])
    assert len(got) == len(want) == len(F0)
    for g, w in zip(got, want):
        assert np.allclose(g.reshape(N, N), w, atol=1e-11 * np.abs(w).max())


def test_the_schur_complement_and_its_block_cholesky():
    """The block tridiagonal Schur complement equals the definition's dense sum, and the block
    Cholesky solves it as numpy's dense solve does."""
    As, rng = _levels()
    L, N = As.shape[:2]
    R = np.array([np.eye(N)] * L)
    blocks, _ = dp._dwell_terms(As, 0.5, 0.05, R)
    kkt = dp._ChainKKT(blocks, dp._chain_layout(L, N))
    sigma = [_spd(N, rng) for _ in blocks]
    n = L * N * (N + 1) // 2
    cols = [np.split(kkt._apply(e), kkt.offs[1:-1]) for e in np.eye(n)]
    dense = np.array([[sum(np.trace(Fa.reshape(N, N) @ S @ Fb.reshape(N, N) @ S)
                           for Fa, Fb, S in zip(cols[a], cols[b], sigma)) for b in range(n)] for a in range(n)])
    H = np.zeros((n, n))                                  # the blocks set in place, the lower ones transposed
    m = N * (N + 1) // 2
    for (k, l), B in kkt.schur_blocks(sigma).items():
        H[k * m:(k + 1) * m, l * m:(l + 1) * m] = B
        H[l * m:(l + 1) * m, k * m:(k + 1) * m] = B.T
    assert np.allclose(H, dense, atol=1e-10 * np.abs(dense).max())
    assert np.all(H[:m, 2 * m:] == 0)                     # P_0 and P_2 never meet
    b = rng.standard_normal(n)
    assert np.allclose(kkt.factor(sigma)(b), np.linalg.solve(dense, b), rtol=1e-9, atol=1e-12)


def test_a_block_with_levels_that_are_not_neighbours_is_refused():
    As, rng = _levels()
    I = np.eye(4)
    blocks = [[Term(I, "P0", I), Term(I, "P2", I)]]
    kkt = dp._ChainKKT(blocks, dp._chain_layout(3, 4))
    with pytest.raises(ValueError, match="not neighbours"):
        kkt.schur_blocks([I])


def test_the_program_certifies_a_long_dwell():
    """At a long dwell the answer satisfies every condition (eigenvalues of the matrices it
    returns, the exponentials by scipy)."""
    As, _ = _levels(L=3, N=3, seed=0)
    assert all(np.max(np.linalg.eigvals(A).real) < -1 for A in As)
    L, N = As.shape[:2]
    R = np.array([np.eye(N)] * L)
    lam = 0.05
    P = dp.solve_dwell_program(As, 5.0, 2 * lam, R)
    assert P is not None
    for k in range(L):
        assert np.min(np.linalg.eigvalsh(P[k])) > 0
        M = (As[k] + lam * np.eye(N)).T @ P[k] + P[k] @ (As[k] + lam * np.eye(N))
        assert np.max(np.linalg.eigvalsh(M)) < 0
        E = sla.expm(As[k] * 5.0)
        for j in (k - 1, k + 1):
            if 0 <= j < L:
                assert np.max(np.linalg.eigvalsh(E.T @ P[j] @ E - np.exp(-2 * lam * 5.0) * P[k])) < 0
