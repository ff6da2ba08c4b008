"""The regional LMI program's structure (report ch. 5.2, eqs 5.2–5.4), and an interior-point KKT
solver that uses it (issue 40).

Every block of the program of :mod:`acmm.design.regional_lmi` is affine in three matrix
variables, Z = [X; Y] ((N + m) × N: the region certificate X stacked on Y = K̃X), X₂ (N × N) and
W (m × m), and is a sum of terms ::

    F_k(v) = F0_k + Σ_t Sym(P_t V_t Q_tᵀ),      Sym(U) = U + Uᵀ,

with constant P_t (m_k × rows V_t) and Q_t (m_k × cols V_t) (:func:`program_terms`; M = [Ã, −B̃]Z).
A primal-dual interior-point method spends its time on the Schur complement of the Newton system,
H_ab = Σ_k tr(F_k(E_a) Σ_k F_k(E_b) Σ_k) (678 × 678 at N = 24, m = 3; Σ_k the scaling of block
k), which a general solver forms from the data of each of the 678 variables.  For terms it is a
sum of Kronecker products of small matrices: with E_a = e_i e_jᵀ in V and E_b = e_k e_lᵀ in V′, ::

    tr(Sym(P E_a Qᵀ) Σ Sym(P′ E_b Q′ᵀ) Σ) = 2 [(QᵀΣP′)_jk (Q′ᵀΣP)_li + (QᵀΣQ′)_jl (P′ᵀΣP)_ki],

so each pair of terms costs four products of m_k-sized matrices and the sums over pairs are single
matrix products (:meth:`StructuredKKT.schur`; ``make bench`` times the whole solve against DSDP
and Clarabel).  This is the customization the CVXOPT user's guide describes for cone programs with
structure ("Cone Programming", "Exploiting Structure": G given as an operator and a
``kktsolver`` of one's own); everything else — the Nesterov–Todd scaling, the steps, the
stopping rule — is cvxopt's.

:func:`run_conelp` hands a program to cvxopt's ``conelp`` with this KKT solver
(:meth:`StructuredKKT.factor`); an answer is accepted or refused by :mod:`acmm.design.regional_lmi`'s checks.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

try:                  # GPL-3 (README, Dependencies): without it the LMI route solves with Clarabel only
    import cvxopt
    from cvxopt import solvers
except ImportError:   # pragma: no cover - exercised by uninstalling cvxopt
    cvxopt = solvers = None

#: Whether :func:`run_conelp` can run here (cvxopt installed).
conelp_available = solvers is not None

#: The variables of the terms, in the order of the program's variable vector's parts.
VARIABLES = ("Z", "X2", "W")


@dataclass(frozen=True)
class Term:
    """One term Sym(P V Qᵀ) of a block.

    Attributes
    ----------
    P : (m_k, r) array
        Left factor, dimensionless.
    var : str
        The variable V (:data:`VARIABLES`), r × c.
    Q : (m_k, c) array
        Right factor, dimensionless.
    """

    P: np.ndarray
    var: str
    Q: np.ndarray


def program_terms(Az, Bz, pars) -> list:
    """The terms of each block of the regional LMI program, in the order of
    :func:`acmm.design.regional_lmi.LMIProgram.blocks` (the constant parts are not terms).

    Parameters
    ----------
    Az, Bz : arrays
        The model in the program's coordinates, (N, N) and (N, m), dimensionless.
    pars : tuple of float
        (a, c, φ, r, β) of :class:`acmm.design.regional_lmi.LMIProgram`: half-plane and cone-apex
        shifts (units of n), sector half-angle (rad), disk radius (units of n), dilation (units of 1/n).

    Returns
    -------
    list of list of Term
        One list per block: half-plane, cone, the disk if r > 0, the dilated H2 condition, the cost.
    """
    N, m = Bz.shape
    a, c, phi, r, beta = pars
    I, zero = np.eye(N), np.zeros((N, m))
    e1, e2 = np.array([[1.0], [0.0]]), np.array([[0.0], [1.0]])
    AB = np.hstack([Az, -Bz])                                   # M = AB Z
    Xonly = np.hstack([I, zero])                                # X = Xonly Z
    theta = np.array([[np.sin(phi), np.cos(phi)], [-np.cos(phi), np.sin(phi)]])
    blocks = [[Term(AB + a * Xonly, "Z", I)],                                  # He(M) + 2aX
              [Term(np.kron(theta @ e, AB + c * Xonly), "Z", np.kron(e, I))    # Sym(Θ ⊗ M_c)
               for e in (e1, e2)]]
    if r > 0:                                                   # [[−rX, M], [Mᵀ, −rX]]
        blocks.append([Term(np.kron(e1, -0.5 * r * Xonly), "Z", np.kron(e1, I)),
                       Term(np.kron(e2, -0.5 * r * Xonly) + np.kron(e1, AB), "Z", np.kron(e2, I))])
    # [[−2βX, X₂ − X + βMᵀ], [X₂ − X + βM, M + Mᵀ]]
    blocks.append([Term(np.kron(e1, -beta * Xonly) + np.kron(e2, beta * AB - Xonly), "Z", np.kron(e1, I)),
                   Term(np.kron(e2, I), "X2", np.kron(e1, I)),
                   Term(np.kron(e2, AB), "Z", np.kron(e2, I))])
    # −[[W, Y], [Yᵀ, 2X − X₂]]
    E1 = np.vstack([np.eye(m), np.zeros((N, m))])
    E2 = np.vstack([np.zeros((m, N)), I])
    blocks.append([Term(-0.5 * E1, "W", E1), Term(-np.hstack([E2, E1]), "Z", E2), Term(0.5 * E2, "X2", E2)])
    return blocks


@dataclass(frozen=True)
class Layout:
    """Where the variable vector's entries sit in the terms' variables.

    The vector v stacks the upper triangles of X and X₂ (row by row), Y (row by row) and the upper
    triangle of W (:class:`acmm.design.regional_lmi.LMIProgram`); the variables Z = [X; Y], X₂ and
    W are stored whole, row by row, one after another.

    Attributes
    ----------
    shapes : dict
        Each variable's shape.
    offsets : dict
        Each variable's first index in the stacked whole variables.
    first, second : (n_var,) int arrays
        Where each v_a sits in the variables stored whole: an off-diagonal entry of a symmetric
        variable at two places (``second`` ≥ 0), every other entry at one (``second`` = −1).  They
        are the duplication S, vec(whole variables) = S v, written as indices.
    """

    shapes: dict
    offsets: dict
    first: np.ndarray
    second: np.ndarray

    @property
    def n_full(self) -> int:
        """Number of entries of the variables stored whole."""
        return sum(r * c for r, c in self.shapes.values())

    def _expand(self, v) -> np.ndarray:
        """S v: the variables stored whole, (n_full,), from the variable vector (dimensionless)."""
        two = self.second >= 0
        whole = np.empty(self.n_full)
        whole[self.first] = v
        whole[self.second[two]] = v[two]
        return whole

    def _fold(self, A, axis: int = 0) -> np.ndarray:
        """Sᵀ A along ``axis`` (A S for axis 1; A over the whole variables, then one zero slice:
        n_full + 1), by two gathers (faster here than sparse products or indexed additions): an
        entry with no second place (``second`` = −1) gathers A's last slice, which must be zero."""
        out = np.take(A, self.first, axis=axis)
        out += np.take(A, self.second, axis=axis)
        return out


def symmetric_places(n: int) -> tuple:
    """Where the upper triangle of a symmetric n × n matrix, row by row, sits in the matrix stored
    whole (row by row): each entry's first place, and its mirror (−1 on the diagonal).

    Parameters
    ----------
    n : int
        Size.

    Returns
    -------
    first, second : (n(n+1)/2,) int arrays
        Flat indices into the n × n matrix.
    """
    i, j = np.triu_indices(n)
    return i * n + j, np.where(i == j, -1, j * n + i)


def layout(N: int, m: int) -> Layout:
    """The :class:`Layout` of a program with N states and m inputs.

    Parameters
    ----------
    N, m : int
        States and inputs.

    Returns
    -------
    Layout
        Shapes, offsets and the duplication.
    """
    shapes = {"Z": (N + m, N), "X2": (N, N), "W": (m, m)}
    offsets = dict(zip(VARIABLES, np.cumsum([0] + [r * c for r, c in shapes.values()])[:-1].tolist()))

    fx, sx = symmetric_places(N)
    fw, sw = symmetric_places(m)
    # v = [X's upper triangle, X₂'s, Y, W's]; X and Y are the rows of Z
    first = np.concatenate([offsets["Z"] + fx, offsets["X2"] + fx, offsets["Z"] + N * N + np.arange(m * N),
                            offsets["W"] + fw])
    second = np.concatenate([np.where(sx >= 0, offsets["Z"] + sx, -1), np.where(sx >= 0, offsets["X2"] + sx, -1),
                             np.full(m * N, -1), np.where(sw >= 0, offsets["W"] + sw, -1)])
    return Layout(shapes, offsets, first, second)


def coefficient_arrays(blocks, lay: Layout) -> list:
    """The coefficient F_ik of every variable in every block (the data of a general SDP solver).

    Parameters
    ----------
    blocks : list of list of Term
        :func:`program_terms`.
    lay : Layout
        The variable layout.

    Returns
    -------
    list of (n_var, m_k, m_k) arrays
        F_ik = Σ_t Sym(P_t E_i Q_tᵀ), E_i the i-th variable's unit matrix, dimensionless.
    """
    out = []
    for terms in blocks:
        mk = terms[0].P.shape[0]
        full = np.zeros((lay.n_full + 1, mk, mk))                # the last slice stays zero (fold)
        for t in terms:
            r, c = lay.shapes[t.var]
            o = lay.offsets[t.var]
            U = np.einsum("ai,bj->ijab", t.P, t.Q).reshape(r * c, mk, mk)
            full[o:o + r * c] += U + U.transpose(0, 2, 1)
        out.append(lay._fold(full))
    return out


class StructuredKKT:
    """cvxopt ``conelp`` callbacks for the program: the operator G (v ↦ the blocks' linear part) and
    the KKT solver whose Schur complement is formed from the terms (module docstring).

    Parameters
    ----------
    blocks : list of list of Term
        :func:`program_terms`.
    lay : Layout
        The variable layout.

    Attributes
    ----------
    dims : list of int
        The blocks' sizes m_k.
    indefinite : int
        Factorizations where rounding left H numerically indefinite (solved by LU instead).
    """

    def __init__(self, blocks, lay: Layout):
        self.blocks, self.lay = blocks, lay
        self.dims = [terms[0].P.shape[0] for terms in blocks]
        self.offs = np.cumsum([0] + [d * d for d in self.dims])
        self.lower = [np.tril(np.ones((d, d), bool)) for d in self.dims]
        # H over the whole variables (12 MB at N = 24), made at the first Schur complement and
        # rewritten at every one after: a fresh one each iteration cost a noticeable part of the
        # solve in zeroing and page faults
        self._whole = None
        self.indefinite = 0

    def _apply(self, v) -> np.ndarray:
        """G v: the blocks' linear parts Σ_t Sym(P_t V_t Q_tᵀ), (Σ m_k²,), each block a symmetric
        matrix stacked as a vector (row or column order alike), dimensionless."""
        whole, lay = self.lay._expand(v), self.lay
        V = {var: whole[lay.offsets[var]:lay.offsets[var] + r * c].reshape(r, c) for var, (r, c) in lay.shapes.items()}
        out = []
        for terms in self.blocks:
            B = sum(t.P @ V[t.var] @ t.Q.T for t in terms)
            out.append((B + B.T).ravel())
        return np.concatenate(out)

    def _adjoint(self, Zs) -> np.ndarray:
        """Gᵀ z: the gradient of Σ_k tr(F_k(v) Z_k) (Zs: one symmetric matrix per block),
        Σ_t 2 P_tᵀ Z_k Q_t folded into the variable vector, dimensionless."""
        g = np.zeros(self.lay.n_full + 1)                    # the last entry stays zero (fold)
        for terms, Z in zip(self.blocks, Zs):
            for t in terms:
                o = self.lay.offsets[t.var]
                D = 2.0 * (t.P.T @ Z @ t.Q)
                g[o:o + D.size] += D.ravel()
        return self.lay._fold(g)

    def schur(self, sigma) -> np.ndarray:
        """H_ab = Σ_k tr(F_k(E_a) Σ_k F_k(E_b) Σ_k) over the variable vector.

        Parameters
        ----------
        sigma : list of (m_k, m_k) arrays
            The symmetric positive definite scaling of each block, dimensionless.

        Returns
        -------
        (n_var, n_var) array
            The Schur complement, dimensionless.
        """
        lay = self.lay
        order = {v: k for k, v in enumerate(VARIABLES)}
        pairs = {}
        for terms, Sg in zip(self.blocks, sigma):
            SP = [Sg @ t.P for t in terms]
            SQ = [Sg @ t.Q for t in terms]
            for i, t in enumerate(terms):
                for j, u in enumerate(terms):
                    if order[t.var] > order[u.var]:
                        continue                                # the lower blocks are the transposes
                    acc = pairs.setdefault((t.var, u.var), ([], [], [], []))
                    acc[0].append((t.P.T @ SP[j]).ravel())      # (P′ᵀΣP)ᵀ_ik = (PᵀΣP′)_ik
                    acc[1].append((t.Q.T @ SQ[j]).ravel())      # (QᵀΣQ′)_jl
                    acc[2].append((SP[i].T @ u.Q).ravel())      # (Q′ᵀΣP)ᵀ_il
                    acc[3].append((t.Q.T @ SP[j]).ravel())      # (QᵀΣP′)_jk
        if self._whole is None:                          # its last row and column stay zero (fold)
            self._whole = np.zeros((lay.n_full + 1,) * 2)
        H = self._whole                                  # every variable pair meets in the cost block
        for (v, w), (pp, qq, pq, qp) in pairs.items():
            ri, cj = lay.shapes[v]
            rk, cl = lay.shapes[w]
            t2 = (np.array(pp).T @ np.array(qq)).reshape(ri, rk, cj, cl).transpose(0, 2, 1, 3)
            t1 = (np.array(pq).T @ np.array(qp)).reshape(ri, cl, cj, rk).transpose(0, 2, 3, 1)
            blk = (t1 + t2).reshape(ri * cj, rk * cl)
            rows = slice(lay.offsets[v], lay.offsets[v] + ri * cj)
            cols = slice(lay.offsets[w], lay.offsets[w] + rk * cl)
            H[rows, cols] = blk
            if v != w:
                H[cols, rows] = blk.T
        return 2.0 * lay._fold(lay._fold(H), axis=1)

    def _blocks_of(self, z):
        """The symmetric blocks of a cvxopt 's' vector (lower triangles, column by column)."""
        Zs = [z[a:b].reshape(d, d).T for a, b, d in zip(self.offs[:-1], self.offs[1:], self.dims)]
        return [np.where(lower, Z, Z.T) for Z, lower in zip(Zs, self.lower)]

    def factor(self, sigma):
        """The Schur complement H of the scaling ``sigma`` factored: LAPACK's Cholesky, or LU where
        rounding leaves H numerically indefinite (counted in :attr:`indefinite`).

        Parameters
        ----------
        sigma : list of (m_k, m_k) arrays
            The symmetric positive definite scaling of each block, dimensionless.

        Returns
        -------
        callable
            ``solve(b)``: H⁻¹ b for a vector b over the variable vector, dimensionless.

        Raises
        ------
        ArithmeticError
            H is numerically singular (cvxopt then stops with status "unknown" and its last
            iterate).
        """
        H = self.schur(sigma)
        try:
            factor = sla.cho_factor(H, lower=True, check_finite=False)
            return lambda b: sla.cho_solve(factor, b, check_finite=False)
        except np.linalg.LinAlgError:
            self.indefinite += 1
            with warnings.catch_warnings():
                warnings.simplefilter("error", sla.LinAlgWarning)
                try:
                    lu = sla.lu_factor(H, check_finite=False)
                except sla.LinAlgWarning:
                    # cvxopt ends on an ArithmeticError with status "unknown" and its last iterate
                    raise ArithmeticError("singular Schur complement") from None
            return lambda b: sla.lu_solve(lu, b, check_finite=False)

    def _kktsolver(self, W):
        """cvxopt's ``kktsolver(W)`` for [[0, Gᵀ], [G, −WᵀW]] [ux; uz] = [bx; bz] (no equality
        constraints): H ux = bx + Gᵀ(WᵀW)⁻¹bz, then W uz = W⁻ᵀ(G ux − bz), W["rti"][k] = r_k⁻ᵀ the
        Nesterov–Todd scaling W_k(u) = r_kᵀ u r_k.  Returns ``f(x, y, z)``, which overwrites x with ux
        and z with W uz; ArithmeticError (H singular, or the solve not finite) ends cvxopt's solve."""
        rti = [np.array(r) for r in W["rti"]]
        sigma = [r @ r.T for r in rti]                  # (WᵀW)⁻¹ u = Σ u Σ,  Σ = r⁻ᵀ r⁻¹
        solve = self.factor(sigma)

        def f(x, y, z):
            bz = self._blocks_of(np.array(z).ravel())
            ux = solve(np.array(x).ravel() + self._adjoint([Sg @ B @ Sg for Sg, B in zip(sigma, bz)]))
            if not np.all(np.isfinite(ux)):
                raise ArithmeticError("the KKT solve is not finite")
            gz = self._apply(ux)
            out = [(r.T @ (gz[self.offs[k]:self.offs[k + 1]].reshape(d, d) - bz[k]) @ r).T.ravel()
                   for k, (d, r) in enumerate(zip(self.dims, rti))]        # W⁻ᵀ(G ux − bz) = rtiᵀ(·)rti
            x[:] = cvxopt.matrix(ux)
            z[:] = cvxopt.matrix(np.concatenate(out))
        return f

    def _operator(self, x, y, alpha=1.0, beta=0.0, trans="N"):
        """cvxopt's G(x, y, alpha, beta, trans): y := alpha G x + beta y, or Gᵀ with trans "T" (cvxopt
        matrices; 's' vectors as lower triangles, column by column)."""
        xv = np.array(x).ravel()
        r = self._apply(xv) if trans == "N" else self._adjoint(self._blocks_of(xv))
        y[:] = cvxopt.matrix(alpha * r + beta * np.array(y).ravel())


def run_conelp(kkt: StructuredKKT, c, F0, tol: float, feastol: float, max_iter: int = 100, start=None,
               refinement: int = 2):
    """Minimize cᵀv subject to F0_k + G_k(v) ⪯ 0 for every block k by cvxopt's ``conelp`` with a
    structured KKT solver.

    Parameters
    ----------
    kkt : StructuredKKT
        The program's operator G and KKT solver (its blocks' terms).
    c : (n_var,) array
        Objective, dimensionless.
    F0 : list of (m_k, m_k) arrays
        The blocks' constant parts, dimensionless.
    tol : float
        Relative gap tolerance, dimensionless.
    feastol : float
        Primal and dual feasibility tolerance, dimensionless.
    max_iter : int
        Iteration limit (a guard: the stop is the tolerances).
    start : tuple or None
        (v, slacks, duals): an interior iterate to start from (slacks s_k = −F_k(v) up to the
        residual and duals z_k, each block ≻ 0); None: cvxopt's own starting point.
    refinement : int
        Steps of iterative refinement of each KKT solve.  Near the optimum the Schur complement's
        condition grows as 1/gap²: with one step (cvxopt's default for matrix cones) the tight
        pass stalled on some of the packaged stair-case's points, its dual residual growing
        instead of falling; a loose pass needs one.

    Returns
    -------
    tuple
        (status, variable vector or None, iterations, (slacks, duals) of the last iterate or None);
        status is cvxopt's, with the count of indefinite Schur complements when there were any, or
        "no answer" without a vector (cvxopt's own word, e.g. "primal infeasible", is not a
        checked certificate).
    """
    h = cvxopt.matrix(np.concatenate([-f0.ravel(order="F") for f0 in F0]))
    options = {"show_progress": False, "abstol": 1e-300, "reltol": tol, "feastol": feastol,
               "maxiters": max_iter, "refinement": refinement}
    warm = {}
    if start is not None:
        v0, slacks, duals = start
        warm = {"primalstart": {"x": cvxopt.matrix(v0),
                                "s": cvxopt.matrix(np.concatenate([x.ravel(order="F") for x in slacks]))},
                "dualstart": {"z": cvxopt.matrix(np.concatenate([x.ravel(order="F") for x in duals]))}}
    sol = solvers.conelp(cvxopt.matrix(np.asarray(c, float)), kkt._operator, h, {"l": 0, "q": [], "s": kkt.dims},
                         kktsolver=kkt._kktsolver, options=options, **warm)
    status = sol["status"] + (f" ({kkt.indefinite} indefinite Schur complements)" if kkt.indefinite else "")
    if sol["status"] not in ("optimal", "unknown") or sol["x"] is None or sol["z"] is None:
        # an infeasibility certificate's ray is no answer, and cvxopt's word for it no checked proof
        return "no answer", None, int(sol["iterations"]), None
    s, z = np.array(sol["s"]).ravel(), np.array(sol["z"]).ravel()
    blocks = [(s[a:b].reshape(d, d).T, z[a:b].reshape(d, d).T)
              for a, b, d in zip(kkt.offs[:-1], kkt.offs[1:], kkt.dims)]
    return status, np.array(sol["x"]).ravel(), int(sol["iterations"]), tuple(zip(*blocks))
