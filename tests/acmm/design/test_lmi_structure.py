"""The regional LMI program's terms and the structured KKT solver (acmm.design.lmi_structure),
checked against the program's blocks as :mod:`acmm.design.regional_lmi` writes them (np.block),
a dense Schur complement, the KKT equations themselves, and DSDP and Clarabel on a small plant."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import solve_continuous_are

from acmm.design import lmi_structure as ls
from acmm.design import regional_lmi as rl
from acmm.design.regional_lmi import RegionalLMISettings, lmi_program, regional_lmi

cvxopt = pytest.importorskip("cvxopt")


def _plant(N=5, m=2, seed=3):
    """A small random plant in scaled units: (A, B, G = −B)."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((N, m))
    return rng.standard_normal((N, N)), B, -B


def _program(disk=0.0):
    A, B, G = _plant()
    N, m = B.shape
    return lmi_program(A, B, G, np.eye(N), np.linspace(0.5, 2.0, m), RegionalLMISettings(disk_radius=disk))


def _spd(d, rng):
    M = rng.standard_normal((d, d))
    return M @ M.T / d + 0.1 * np.eye(d)


@pytest.mark.parametrize("disk", [0.0, 30.0])
def test_the_terms_are_the_blocks(disk):
    """F0 + Σ v_i F_i from the terms equals the blocks written with np.block, at random v."""
    prog = _program(disk)
    F = prog.coefficients()
    assert len(F) == len(prog.F0) == (5 if disk else 4)
    rng = np.random.default_rng(0)
    for _ in range(3):
        v = rng.standard_normal(prog.c.size)
        for F0, Fk, blk in zip(prog.F0, F, prog.blocks(v)):
            assert np.allclose(F0 + np.einsum("i,iab->ab", v, Fk), blk, rtol=0, atol=1e-12 * np.abs(blk).max())


def test_the_operator_and_its_adjoint():
    """G v is the blocks' linear part; ⟨G v, Z⟩ = ⟨v, Gᵀ Z⟩ for symmetric Z."""
    prog = _program(30.0)
    kkt = ls.StructuredKKT(prog.terms, ls.layout(*prog.sizes))
    rng = np.random.default_rng(1)
    v = rng.standard_normal(prog.c.size)
    Gv = kkt._apply(v)
    lin = np.concatenate([(b - f0).ravel() for b, f0 in zip(prog.blocks(v), prog.F0)])
    assert np.allclose(Gv, lin, atol=1e-12 * np.abs(lin).max())
    Zs = [_spd(d, rng) - 0.5 * np.eye(d) for d in kkt.dims]
    lhs = sum(np.sum(g * Z.ravel()) for g, Z in zip(np.split(Gv, kkt.offs[1:-1]), Zs))
    assert kkt._adjoint(Zs) @ v == pytest.approx(lhs, rel=1e-12)


def test_the_schur_complement_equals_the_dense_formula():
    """H_ab = Σ_k tr(F_k(E_a) Σ_k F_k(E_b) Σ_k), formed from the coefficient arrays by einsum."""
    prog = _program(30.0)
    kkt = ls.StructuredKKT(prog.terms, ls.layout(*prog.sizes))
    rng = np.random.default_rng(2)
    sigma = [_spd(d, rng) for d in kkt.dims]
    H = kkt.schur(sigma)
    dense = sum(np.einsum("iab,bc,jcd,da->ij", F, S, F, S) for F, S in zip(prog.coefficients(), sigma))
    assert np.abs(H - dense).max() <= 1e-12 * np.abs(dense).max()
    assert np.allclose(H, H.T, rtol=0, atol=1e-13 * np.abs(H).max())


def test_the_kkt_solver_solves_the_kkt_equations():
    """With a random scaling W (r_k), the returned ux and W uz satisfy Gᵀuz = bx and
    G ux − WᵀW uz = bz, checked with the coefficient arrays (cvxopt's 's' storage: lower triangles)."""
    prog = _program()
    kkt = ls.StructuredKKT(prog.terms, ls.layout(*prog.sizes))
    rng = np.random.default_rng(4)
    r = [np.linalg.cholesky(_spd(d, rng)) + 0.1 * rng.standard_normal((d, d)) for d in kkt.dims]
    W = {"r": [cvxopt.matrix(x) for x in r], "rti": [cvxopt.matrix(np.linalg.inv(x).T) for x in r]}
    bx = rng.standard_normal(prog.c.size)
    Bz = [_spd(d, rng) - np.eye(d) for d in kkt.dims]
    x, z = cvxopt.matrix(bx), cvxopt.matrix(np.concatenate([np.tril(B).T.ravel() for B in Bz]))
    kkt._kktsolver(W)(x, cvxopt.matrix(0.0, (0, 1)), z)
    ux = np.array(x).ravel()
    Wuz = [np.array(z).ravel()[a:b].reshape(d, d).T for a, b, d in zip(kkt.offs[:-1], kkt.offs[1:], kkt.dims)]
    uz = [rk.T @ M @ rk for rk, M in zip([np.linalg.inv(x) for x in r], Wuz)]     # W⁻¹(W uz) = r⁻ᵀ(·)r⁻¹
    F = prog.coefficients()
    assert np.allclose(sum(np.einsum("iab,ab->i", Fk, U) for Fk, U in zip(F, uz)), bx, atol=1e-8)
    for Fk, U, rk, B in zip(F, uz, r, Bz):
        WtW = rk @ rk.T @ U @ rk @ rk.T                                          # WᵀW(u) = r rᵀ u r rᵀ
        assert np.allclose(np.einsum("i,iab->ab", ux, Fk) - WtW, B, atol=1e-8 * np.abs(B).max())


def test_the_three_solvers_agree_on_a_small_plant():
    """The regional LMI design of a random 5-state plant by conelp (structured KKT), DSDP and
    Clarabel (cvxpy's own data, np.block): every answer passes the design's checks, the cost bounds
    agree to 3e-6 and the gains to 5e-5 relative (the optimum is flat along directions the gain
    barely uses); conelp's answer holds its cost LMIs to 1e-9 of their norm (its regions are proved
    by the certified margin, ≥ 0.1n)."""
    A, B, _ = _plant()
    K_ref = B.T @ solve_continuous_are(A + 3 * np.eye(5), B, np.eye(5), np.eye(2))
    out = {s: regional_lmi(A, B, 1.0, K_ref, RegionalLMISettings(solver=s, n_random=0))
           for s in ("conelp", "dsdp", "clarabel")}
    assert all(r.solver == s and r.rejected == () for s, r in out.items())
    a = out["conelp"]
    for s in ("dsdp", "clarabel"):
        assert out[s].cost_bound == pytest.approx(a.cost_bound, rel=3e-6), s
        assert np.linalg.norm(out[s].K - a.K) / np.linalg.norm(a.K) <= 5e-5, s
    assert a.certified_margin >= 0.1 and a.lmi_residual <= 1e-9


def test_an_infeasible_program_is_no_answer_not_the_solvers_word():
    """Regions no gain reaches (margin 50n here): cvxopt's own "primal infeasible" is not passed on."""
    A, B, G = _plant()
    st = replace(RegionalLMISettings(), min_margin=50.0, disk_radius=1.0)
    prog = lmi_program(A, B, G, np.eye(5), np.ones(2), st)
    status, v, _, _ = rl._solve_conelp(prog, 1e-7, 1e-7)
    assert v is None and status == "no answer"


def test_an_iterate_carried_into_other_coordinates_is_the_same_point():
    """_carry_iterate: the objective, every block up to its congruence (R F Rᵀ: positive
    definiteness kept) and sᵀz are those of the original iterate, the disk block included."""
    A, B, G = _plant()
    st = RegionalLMISettings(disk_radius=30.0)
    rng = np.random.default_rng(5)
    T1 = np.linalg.cholesky(_spd(5, rng))
    T2 = T1 @ np.linalg.cholesky(_spd(5, rng))
    prog = lmi_program(A, B, G, T1, np.array([0.7, 1.3]), st)
    prog2 = lmi_program(A, B, G, T2, np.array([1.1, 0.4]), st, T_reg=T1)
    v = rng.standard_normal(prog.c.size)
    slack = [-b for b in prog.blocks(v)]
    dual = [_spd(b.shape[0], rng) for b in slack]
    v2, slack2, dual2 = rl._carry_iterate(prog, prog2, v, (slack, dual))
    assert prog2.c @ v2 == pytest.approx(prog.c @ v, rel=1e-10)
    for b2, s2, s, z2, z in zip(prog2.blocks(v2), slack2, slack, dual2, dual):
        assert np.allclose(-b2, s2, atol=1e-9 * np.abs(s2).max())
        assert np.sum(s2 * z2) == pytest.approx(np.sum(s * z), rel=1e-9)
