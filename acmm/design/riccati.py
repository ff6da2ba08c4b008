"""Continuous algebraic Riccati equation (eq 5.4) with a verified residual.

Solves ::

    A'P + P A − P B R⁻¹ B' P + Q = 0                                       (eq 5.4)

for the stabilizing solution P = P' (A − B K stable, K = R⁻¹ B' P, eq 5.3) by one of three
methods behind :func:`solve_care`:

``"scipy"``
    :func:`scipy.linalg.solve_continuous_are` (generalized Schur of the extended pencil, with
    balancing).
``"sign"``
    The matrix sign function of the Hamiltonian (eq 5.5) by the fifth-order iteration of eq 5.6
    with the *corrected* denominator (:func:`acmm.design.matrix_sign.matrix_sign`); [I; P] then
    spans the stable invariant subspace of H = [[A, −G], [−Q, −A']], G = BR⁻¹B', which is the range
    of the projector (I − sign H)/2: an orthonormal basis [U1; U2] of it from a column-pivoted QR
    factorization gives P = U2 U1⁻¹.  (Solving (sign H + I)[I; P] = 0 by least squares instead
    loses up to ten digits on the nearly uncontrollable claim-1 model: backward error 3e-6
    against 1e-16.)
``"slycot"``
    SLICOT SB02MD (Schur vectors of the Hamiltonian) via :func:`slycot.sb02md`.

State scaling: with nominal state magnitudes d (``scale``), x = D x̃, D = diag(d), the solver
works on Ã = D⁻¹AD, B̃ = D⁻¹B, Q̃ = DQD and maps back P = D⁻¹P̃D⁻¹, K = K̃D⁻¹.  In physical units
the 24 ACMM states span ~12 orders of magnitude; unscaled, every method loses most digits
(``docs/ERRATA.md`` § Scaling).

Refinement and acceptance: every solver's answer is refined by Newton–Kleinman steps with exact
line search (:func:`refine_care`; Kleinman 1968, Benner & Byers 1998) until a step no longer
halves the backward error ω (:func:`care_backward_error`), i.e. at working accuracy, not after a
fixed count, and accepted when ω ≤ ``tol``: ω judges a nearly uncontrollable model (large
cancelling terms in PGP) by what working precision can give, the same for every method.  The
relative residual of :func:`care_residual` is still computed and reported; the error of P is
about κ_CARE·ω.

Existence check (every method): before solving, the eigenvalues λ_i of the (scaled) Hamiltonian
H = [[A, −G], [−Q, −A']] are computed, after balancing (H_b = T⁻¹HT, LAPACK GEBAL with
permutation), with their condition numbers κ_i (left/right eigenvectors of H_b).  A stabilizing
solution exists only if no λ_i lies on the imaginary axis; a computed λ_i is indistinguishable
from the axis when |Re λ_i| ≤ δ_i, ::

    δ_i = min(IMAG_AXIS_RTOL · κ_i · ε,  √ε) · ‖H_b‖_F,

(ε = machine epsilon): IMAG_AXIS_RTOL·κ_i·ε‖H_b‖ bounds the rounding error of a simple
eigenvalue; the √ε‖H_b‖ cap is the O(√ε) split of a defective (Jordan) pair by rounding, and
keeps a cluster of benign repeated eigenvalues (whose individual κ_i are huge) from being
rejected.  Such a problem is refused (``ConvergenceError`` naming the eigenvalue) instead of
returning "stabilizing" closed-loop poles at −1e-8.

Condition estimate: every solution carries ::

    κ_CARE = ‖Ω⁻¹‖₂ (‖Q‖₂ + 2‖A‖₂‖P‖₂ + ‖G‖₂‖P‖₂²) / ‖P‖₂,        Ω(X) = A_c'X + XA_c,

(A_c = A − GP, scaled coordinates), the relative condition number of the Riccati equation
(Kenney & Hewer 1990; Byers 1985), with ‖Ω⁻¹‖₂ = ‖Y‖₂ for A_c'Y + YA_c = −I (Hewer & Kenney
1988: exact for stable A_c), i.e. one extra Lyapunov solve.  A solution with
κ_CARE > ``ILL_CONDITIONED`` (1/√ε ≈ 6.7e7: fewer than half the digits of P can be trusted) is
flagged (``CareResult.ill_conditioned``) and the flag is written to the design output.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import NoReturn

import numpy as np
import scipy.linalg as sla

from acmm.design.matrix_sign import matrix_sign
from acmm_qpp.errors import ConvergenceError

#: Relative factor of the rounding band about the imaginary axis (module docstring).
IMAG_AXIS_RTOL = 100.0
#: κ_CARE above which a solution is flagged ill-conditioned (1/√ε).
ILL_CONDITIONED = 1.0 / np.sqrt(np.finfo(float).eps)


def _as_square(M, k: int, name: str) -> np.ndarray:
    """A scalar (times I) or a k×k matrix, symmetrized."""
    M = np.asarray(M, dtype=float)
    if M.ndim == 0:
        return float(M) * np.eye(k)
    if M.shape != (k, k):
        raise ValueError(f"{name} must be a scalar or {k}×{k}, got shape {M.shape}")
    return 0.5 * (M + M.T)


def _gram(B, R) -> np.ndarray:
    """G = B R⁻¹ B', symmetrized."""
    G = B @ np.linalg.solve(R, B.T)
    return 0.5 * (G + G.T)


def _ratio(num: float, den: float) -> float:
    """num / den, with 0/0 = 0 and x/0 = inf."""
    if den == 0.0:
        return 0.0 if num == 0.0 else float("inf")
    return float(num / den)


def as_R(R, m: int) -> np.ndarray:
    """The input weight ``R`` as an m×m matrix (a scalar or a diagonal broadcast).

    Parameters
    ----------
    R : float or array_like
        The weight, 1/(ft·lbf)² (a scalar, the diagonal, or the matrix).
    m : int
        Number of inputs.

    Returns
    -------
    ndarray
        R (m×m), 1/(ft·lbf)².
    """
    return _as_square(R, m, "R")


def scale_problem(A, B, Q, scale):
    """(Ã, B̃, Q̃) = (D⁻¹AD, D⁻¹B, DQD) for x = D x̃, D = diag(scale) (eq 5.4 in scaled states).

    Parameters
    ----------
    A : (N, N) array
        State matrix, physical units (1/s for rates).
    B : (N, M) array
        Input matrix, physical units (state units per s per input unit).
    Q : (N, N) array
        State weight, physical units (1 / state unit² per s).
    scale : (N,) array
        Positive nominal state magnitudes d, in the units of the states.

    Returns
    -------
    tuple of arrays
        (Ã, B̃, Q̃) in the scaled (dimensionless) states; same time units as A.

    Raises
    ------
    ValueError
        ``scale`` has the wrong shape or a non-positive or non-finite entry.
    """
    d = np.asarray(scale, dtype=float)
    if d.shape != (A.shape[0],) or not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise ValueError(f"scale must be {A.shape[0]} positive finite magnitudes")
    return A * (1.0 / d)[:, None] * d[None, :], B / d[:, None], Q * d[:, None] * d[None, :]


def care_residual(A, B, Q, R, P) -> float:
    """Relative residual of eq 5.4 (all norms Frobenius)::

        ρ = ‖A'P + PA − PGP + Q‖ / (‖Q‖ + 2‖A'P‖ + ‖PGP‖),   G = B R⁻¹ B',

    i.e. the residual relative to the sum of the sizes of the terms that cancel (ρ = 0 when
    P = Q = 0).  Computed in whatever coordinates the arguments are given in; :func:`solve_care`
    passes the scaled ones.  Independent of how P was obtained.

    Parameters
    ----------
    A : (N, N) array
        State matrix (units of the chosen coordinates, 1/s for rates).
    B : (N, M) array
        Input matrix, same coordinates (state units per s per input unit).
    Q : (N, N) array or float
        State weight (a float q means q·I), same coordinates (units of 1/s per state unit²).
    R : (M, M) array or float
        Control weight (a float r means r·I), 1 / input unit² per s.
    P : (N, N) array
        Candidate solution, units of Q times s.

    Returns
    -------
    float
        ρ, dimensionless (``inf`` when the denominator vanishes but the residual does not).
    """
    A, B, P = (np.asarray(x, dtype=float) for x in (A, B, P))
    Q = _as_square(Q, A.shape[0], "Q")
    R = as_R(R, B.shape[1])
    AtP = A.T @ P
    PB = P @ B
    PGP = PB @ np.linalg.solve(R, PB.T)
    res = AtP + AtP.T - PGP + Q
    den = np.linalg.norm(Q) + 2.0 * np.linalg.norm(AtP) + np.linalg.norm(PGP)
    return _ratio(np.linalg.norm(res), den)


def care_backward_error(A, B, Q, R, P) -> float:
    """Backward error of a candidate solution P of eq 5.4, normwise with absolute terms::

        ω = ‖A'P + PA − PGP + Q‖ / ‖ |A|ᵀ|P| + |P||A| + |P||G||P| + |Q| ‖,   G = B R⁻¹ B',

    (Frobenius norms, |·| elementwise).  The denominator is the size of the terms as floating
    point evaluates them: when large entries of P·G·P cancel (a nearly uncontrollable mode makes
    P span many orders of magnitude), even the correctly rounded exact solution has a residual of
    ε times this sum, while :func:`care_residual` divides by the size of the cancelled result
    and so can exceed any fixed tolerance for a solution that is exact to working precision.
    ω is a normwise relative backward error: P solves eq 5.4 exactly for data whose terms are
    perturbed by about ω of their absolute sizes (the residual form of the Oettli–Prager
    backward error, taken in the Frobenius norm); the error of P itself is about κ_CARE·ω
    (:func:`care_condition`).

    Parameters
    ----------
    A : (N, N) array
        State matrix (units of the chosen coordinates, 1/s for rates).
    B : (N, M) array
        Input matrix, same coordinates (state units per s per input unit).
    Q : (N, N) array or float
        State weight (a float q means q·I), same coordinates (units of 1/s per state unit²).
    R : (M, M) array or float
        Control weight (a float r means r·I), 1 / input unit² per s.
    P : (N, N) array
        Candidate solution, units of Q times s.

    Returns
    -------
    float
        ω, dimensionless (0 when P = Q = 0; ``inf`` when the denominator vanishes but the
        residual does not).
    """
    A, B, P = (np.asarray(x, dtype=float) for x in (A, B, P))
    Q = _as_square(Q, A.shape[0], "Q")
    R = as_R(R, B.shape[1])
    G = _gram(B, R)
    AtP = A.T @ P
    res = AtP + AtP.T - P @ G @ P + Q
    aP = np.abs(A).T @ np.abs(P)
    den = float(np.linalg.norm(aP + aP.T + np.abs(P) @ np.abs(G) @ np.abs(P) + np.abs(Q)))
    return _ratio(float(np.linalg.norm(0.5 * (res + res.T))), den)


def hamiltonian_check(A, B, Q, R, *, method: str = "") -> float:
    """Refuse a CARE without a stabilizing solution; return the relative spectral gap.

    Computes the eigenvalues λ_i of H = [[A, −G], [−Q, −A']] (G = BR⁻¹B') with their condition
    numbers κ_i and raises :class:`ConvergenceError` if some |Re λ_i| ≤ δ_i (module docstring):
    an eigenvalue on, or within rounding of, the imaginary axis.

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s for rates (any consistent units).
    B : (N, M) array
        Input matrix, same units.
    Q : (N, N) array
        State weight, same units.
    R : (M, M) array
        Control weight, 1 / input unit² per s.
    method : str
        Solver name, for the message only.

    Returns
    -------
    float
        min_i |Re λ_i| / ‖H_b‖_F (H_b: balanced H), dimensionless; ``inf`` for N = 0.

    Raises
    ------
    ConvergenceError
        An eigenvalue of H on, or within rounding of, the imaginary axis.
    """
    if A.shape[0] == 0:
        return float("inf")
    H = np.block([[A, -_gram(B, R)], [-Q, -A.T]])
    if np.linalg.norm(H) == 0.0:
        _refuse(f"Riccati solve (method={method!r}): no stabilizing solution "
                f"(Hamiltonian is zero: every eigenvalue on the imaginary axis)",
                method, float("nan"), other_method_hint(method))
    Hb, _ = sla.matrix_balance(H, permute=True)
    hn = float(np.linalg.norm(Hb))
    w, vl, vr = sla.eig(Hb, left=True, right=True)
    num = np.linalg.norm(vl, axis=0) * np.linalg.norm(vr, axis=0)
    den = np.abs(np.sum(vl.conj() * vr, axis=0))
    kappa = np.divide(num, den, out=np.full(num.shape, np.inf), where=den > 0)
    eps = np.finfo(float).eps
    band = np.minimum(IMAG_AXIS_RTOL * kappa * eps, np.sqrt(eps)) * hn
    bad = np.abs(w.real) <= band
    if np.any(bad):
        i = int(np.argmin(np.where(bad, np.abs(w.real) / band, np.inf)))
        _refuse(
            f"Riccati solve (method={method!r}): no stabilizing solution: the Hamiltonian has "
            f"eigenvalue {complex(w[i]):.6g} on or within rounding of the imaginary axis "
            f"(|Re λ| = {abs(w[i].real):.3g} ≤ {band[i]:.3g}; eigenvalue condition "
            f"{kappa[i]:.3g}): a mode on the axis is uncontrollable or unobservable", method,
            float("nan"), other_method_hint(method))
    return float(np.min(np.abs(w.real)) / hn)


def care_condition(A, B, Q, R, P) -> float:
    """Relative condition estimate κ_CARE of eq 5.4 at the stabilizing P (module docstring).

    ``inf`` when A − GP is not stable (Y does not exist).

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s for rates (any consistent units).
    B : (N, M) array
        Input matrix, same units.
    Q : (N, N) array
        State weight, same units.
    R : (M, M) array
        Control weight, 1 / input unit² per s.
    P : (N, N) array
        Stabilizing solution, units of Q times s.

    Returns
    -------
    float
        κ_CARE, dimensionless.
    """
    G = _gram(B, R)
    Ac = A - G @ P
    if A.shape[0] == 0:
        return 0.0
    if np.max(np.linalg.eigvals(Ac).real) >= 0:
        return float("inf")
    try:
        Y = sla.solve_continuous_lyapunov(Ac.T, -np.eye(A.shape[0]))
    except (np.linalg.LinAlgError, ValueError):
        return float("inf")
    n2 = lambda M: float(np.linalg.norm(M, 2))  # noqa: E731
    p = n2(P)
    top = n2(Q) + 2.0 * n2(A) * p + n2(G) * p * p
    if p == 0.0:
        return n2(Y) * 2.0 * n2(A)
    return n2(Y) * top / p


def _refuse(message: str, method: str, residual: float, hint: str) -> NoReturn:
    """Raise a :class:`ConvergenceError` carrying ``method`` and ``residual``."""
    exc = ConvergenceError(message, hint=hint)
    exc.method = method          # for reports (scripts/compare_riccati.py)
    exc.residual = residual
    raise exc


METHODS = ("scipy", "sign", "slycot")


def other_method_hint(method: str) -> str:
    """The hint of a failed Riccati solve: the values of ``design.riccati_method`` but ``method``.

    Parameters
    ----------
    method : str
        The method that failed (:data:`METHODS`).

    Returns
    -------
    str
        ``"try another design.riccati_method (sign or slycot)"`` and the like.
    """
    return f"try another design.riccati_method ({' or '.join(m for m in METHODS if m != method)})"


def residual_hint(method: str) -> str:
    """The hint of a Riccati solution refused on its residual or stability (acmm's settings).

    Parameters
    ----------
    method : str
        The method whose solution was refused (:data:`METHODS`).

    Returns
    -------
    str
        Raise the tolerance, try the other methods, or change the model.
    """
    return (f"raise design.residual_tol or try design.riccati_method: "
            f"{' or '.join(m for m in METHODS if m != method)}; a nearly uncontrollable model "
            "(see `acmm linearize`) needs another design.model or design.drf_mode")

#: Guard on the refinement steps of :func:`refine_care`.  The refinement stops on its criterion
#: (a step that no longer halves the backward error) after 1–5 steps on every packaged problem;
#: the guard only bounds the work on a pathological one, whose answer is then judged by its
#: backward error like any other.
REFINE_GUARD = 50


@dataclass(frozen=True)
class CareResult:
    """Stabilizing solution of eq 5.4.

    Attributes
    ----------
    P : (N, N) array
        Stabilizing solution in the caller's (physical) coordinates, symmetric; units of
        Q times s (the cost x'Px has the units of ∫x'Qx dt).
    K : (M, N) array
        Optimal gain K = R⁻¹B'P (u = −K x, eq 5.3), physical coordinates: units of u per unit
        of x.
    residual : float
        Relative residual of :func:`care_residual`, evaluated in the scaled coordinates
        (dimensionless), after refinement.
    method : str
        ``"scipy"``, ``"sign"`` or ``"slycot"``.
    iterations : int
        Sign-function iterations (0 for the direct methods).
    scale : (N,) array or None
        The state scaling d used (x = diag(d) x̃), in the units of the states.
    seconds : float
        Wall time of the solve proper (excluding the residual check), s.
    condition : float
        Relative condition estimate κ_CARE of the (scaled) Riccati equation (module docstring),
        dimensionless.
    ill_conditioned : bool
        κ_CARE > :data:`ILL_CONDITIONED`.
    hamiltonian_gap : float
        min_i |Re λ_i(H)| / ‖H_b‖_F (balanced H): relative distance of the Hamiltonian spectrum
        from the axis, dimensionless.
    backward_error : float
        Backward error ω of :func:`care_backward_error` after refinement (the accepted quantity),
        dimensionless.
    refinement_steps : int
        Newton–Kleinman steps taken by :func:`refine_care`.
    """

    P: np.ndarray
    K: np.ndarray
    residual: float
    method: str
    iterations: int = 0
    scale: np.ndarray | None = field(default=None)
    seconds: float = 0.0
    condition: float = float("nan")
    ill_conditioned: bool = False
    hamiltonian_gap: float = float("nan")
    backward_error: float = float("nan")
    refinement_steps: int = 0


def refine_care(A, B, Q, R, P) -> tuple[np.ndarray, int]:
    """Refine a stabilizing approximate solution of eq 5.4 to working accuracy.

    Newton–Kleinman steps with exact line search (Benner & Byers 1998): with A_c = A − GP and
    ℛ(P) = A'P + PA − PGP + Q, solve A_c'Δ + ΔA_c = −ℛ(P); then ℛ(P + tΔ) = (1 − t)ℛ(P) − t²ΔGΔ,
    and t ∈ (0, 2] minimizes its Frobenius norm (a root of a cubic).  Stops when a step no
    longer halves the backward error ω (:func:`care_backward_error`); the last step is kept only
    if it lowers ω and keeps A − GP stable.  A P that is not stabilizing, or a step whose Lyapunov
    solve fails, ends the refinement with the best P so far (:func:`solve_care` then judges it).

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s for rates (any consistent units).
    B : (N, M) array
        Input matrix, same units.
    Q : (N, N) array
        State weight, same units.
    R : (M, M) array
        Control weight, 1 / input unit² per s.
    P : (N, N) array
        Approximate stabilizing solution, units of Q times s.

    Returns
    -------
    tuple
        (P, steps): the refined symmetric solution and the number of steps kept.
    """
    G = _gram(B, R)
    P = 0.5 * (P + P.T)
    omega = care_backward_error(A, B, Q, R, P)
    steps = 0
    if not _stabilizing(A - G @ P):
        return P, steps
    for _ in range(REFINE_GUARD):
        if not omega > 0.0:
            break
        Ac = A - G @ P
        AtP = A.T @ P
        Res = AtP + AtP.T - P @ G @ P + Q
        Res = 0.5 * (Res + Res.T)
        try:
            D = sla.solve_continuous_lyapunov(Ac.T, -Res)
        except (np.linalg.LinAlgError, ValueError):
            break
        D = 0.5 * (D + D.T)
        Pn = P + _line_search(Res, D @ G @ D) * D
        Pn = 0.5 * (Pn + Pn.T)
        if not _stabilizing(A - G @ Pn):
            break                        # a step that loses stability is never kept
        wn = care_backward_error(A, B, Q, R, Pn)
        if wn < omega:
            P, steps = Pn, steps + 1
        if not wn <= 0.5 * omega:
            break
        omega = wn
    return P, steps


def _stabilizing(Ac: np.ndarray) -> bool:
    """Every eigenvalue of the finite matrix ``Ac`` in the open left half-plane."""
    return bool(np.all(np.isfinite(Ac)) and (Ac.size == 0 or np.max(np.linalg.eigvals(Ac).real) < 0.0))


def _line_search(Res: np.ndarray, V: np.ndarray) -> float:
    """t ∈ (0, 2] minimizing f(t) = ‖(1 − t)Res − t²V‖²_F (Benner & Byers 1998)."""
    a, b, c = float(np.sum(Res * Res)), float(np.sum(Res * V)), float(np.sum(V * V))
    f = lambda t: a * (1 - t) ** 2 - 2 * b * (1 - t) * t ** 2 + c * t ** 4  # noqa: E731
    # f'(t) = 4c t³ + 6b t² + (2a − 4b) t − 2a
    cand = [1.0, 2.0]
    if c > 0.0 or b != 0.0:
        cand += [float(r.real) for r in np.roots([4 * c, 6 * b, 2 * a - 4 * b, -2 * a])
                 if abs(r.imag) <= 1e-12 * max(1.0, abs(r)) and 0.0 < r.real <= 2.0]
    return min(cand, key=f)


def _care_sign(A, B, Q, R, scaling, evaluation, max_iter):
    n = A.shape[0]
    H = np.block([[A, -_gram(B, R)], [-Q, -A.T]])
    sr = matrix_sign(H, scaling=scaling, evaluation=evaluation, max_iter=max_iter)
    # range(I − sign H) is the stable invariant subspace span[I; P] of H
    Z, _, _ = sla.qr(np.eye(2 * n) - sr.S, pivoting=True)
    U1, U2 = Z[:n, :n], Z[n:, :n]
    return np.linalg.solve(U1.T, U2.T).T, sr.iterations


def _care_slycot(A, B, Q, R):
    try:
        from slycot import sb02md  # deferred: slycot start-up, only for method='slycot'
    except ImportError as exc:  # pragma: no cover - slycot is a declared dependency
        raise ConvergenceError("method='slycot' needs the slycot package",
                               hint=other_method_hint("slycot")) from exc
    try:
        out = sb02md(A.shape[0], A.copy(), _gram(B, R), Q.copy(), "C", scal="N", sort="S")
    except Exception as exc:  # slycot raises SlycotArithmeticError / ValueError
        raise ConvergenceError(f"Riccati solve (method='slycot', SB02MD) failed: {exc}",
                               hint=other_method_hint("slycot")) from exc
    return out[0]


def solve_unverified(A, B, Q, R, *, method: str = "scipy", sign_scaling: str = "det",
                     sign_evaluation: str = "partial_fraction", max_iter: int = 60):
    """The raw solver behind :func:`solve_care`: (P, iterations), no scaling, no checks.

    For comparisons only (``scripts/compare_riccati.py``); use :func:`solve_care`.  Solver
    failures raise :class:`ConvergenceError`.  Q and R must be arrays.

    Parameters
    ----------
    A : (N, N) array
        State matrix, 1/s for rates (any consistent units).
    B : (N, M) array
        Input matrix, same units.
    Q : (N, N) array
        State weight, same units.
    R : (M, M) array
        Control weight, 1 / input unit² per s.
    method : {"scipy", "sign", "slycot"}
        Algorithm (module docstring).
    sign_scaling : {"det", "norm", None}
        Acceleration of the sign iteration (``method="sign"`` only).
    sign_evaluation : {"partial_fraction", "polynomial"}
        Evaluation of eq 5.6 (``method="sign"`` only).
    max_iter : int
        Iteration limit of the sign iteration.

    Returns
    -------
    tuple
        (P, iterations): the unverified solution (units of Q times s) and the sign-function
        iterations (0 for the direct methods).

    Raises
    ------
    ValueError
        An unknown ``method``.
    ConvergenceError
        The solver failed.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    iterations = 0
    try:
        if method == "scipy":
            P = sla.solve_continuous_are(A, B, Q, R)
        elif method == "sign":
            P, iterations = _care_sign(A, B, Q, R, sign_scaling, sign_evaluation, max_iter)
        else:
            P = _care_slycot(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ConvergenceError(f"Riccati solve (method={method!r}) failed: {exc}",
                               hint=other_method_hint(method)) from exc
    return P, iterations


def solve_care(A, B, Q, R, *, method: str = "scipy", scale=None, tol: float = 1e-12) -> CareResult:
    """Stabilizing solution of A'P + PA − PBR⁻¹B'P + Q = 0 (eq 5.4), verified.

    Parameters
    ----------
    A : (N, N) array
        State matrix (physical units, e.g. 1/s).
    B : (N, M) array
        Input matrix (physical units: state units per s per input unit).
    Q : (N, N) array or float
        State weight, symmetric positive semidefinite (a float q means q·I), physical units.
    R : (M, M) array or float
        Control weight, symmetric positive definite (a float r means r·I), e.g. 1/(ft·lbf)².
    method : {"scipy", "sign", "slycot"}
        Algorithm (module docstring).
    scale : (N,) array or None
        Nominal state magnitudes d, in the units of the states; the solve is done on x̃ = D⁻¹x and mapped back.
    tol : float
        Largest acceptable backward error ω of the refined solution (:func:`care_backward_error`),
        dimensionless.  ``np.inf`` disables the refusal (for comparisons).

    Returns
    -------
    CareResult
        P and K in physical coordinates, the scaled relative residual, the backward error,
        method, iterations.

    Raises
    ------
    ValueError
        An unknown ``method`` or mismatched shapes.
    ConvergenceError
        The Hamiltonian has an eigenvalue on or within rounding of the imaginary axis (no
        stabilizing solution), the solver failed, the sign iteration did not converge, the
        backward error of the refined solution exceeds ``tol``, or A − BK is not stable.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    if B.ndim == 1:
        B = B[:, None]
    n, m = B.shape
    if A.shape != (n, n):
        raise ValueError(f"A must be {n}×{n} to match B, got {A.shape}")
    Q, R = _as_square(Q, n, "Q"), as_R(R, m)
    d = np.asarray(scale, dtype=float) if scale is not None else None
    As, Bs, Qs = scale_problem(A, B, Q, d) if d is not None else (A, B, Q)

    gap = hamiltonian_check(As, Bs, Qs, R, method=method)
    t0 = time.perf_counter()
    Ps, iterations = solve_unverified(As, Bs, Qs, R, method=method)
    seconds = time.perf_counter() - t0
    Ps = 0.5 * (Ps + Ps.T)
    if not np.all(np.isfinite(Ps)):
        raise ConvergenceError(f"Riccati solve (method={method!r}) returned non-finite values",
                               hint=other_method_hint(method))
    # (the refinement keeps only finite, stabilizing steps)
    Ps, steps = refine_care(As, Bs, Qs, R, Ps)
    res = care_residual(As, Bs, Qs, R, Ps)
    omega = care_backward_error(As, Bs, Qs, R, Ps)
    if not omega <= tol:
        _refuse(f"Riccati solve (method={method!r}{', state-scaled' if d is not None else ''}"
                f"): backward error {omega:.3e} after refinement exceeds tolerance {tol:.1e} "
                f"(relative residual {res:.3e})", method, omega, residual_hint(method))
    Ks = np.linalg.solve(R, Bs.T @ Ps)
    worst = float(np.max(np.linalg.eigvals(As - Bs @ Ks).real))
    if not worst < 0.0:
        _refuse(f"Riccati solve (method={method!r}): solution is not stabilizing "
                f"(closed-loop eigenvalue with real part {worst:.3e}; relative residual "
                f"{res:.3e})", method, res, residual_hint(method))
    cond = care_condition(As, Bs, Qs, R, Ps)
    d1 = np.ones(n) if d is None else d                 # (x/1.0 is exact)
    return CareResult(P=Ps / d1[:, None] / d1[None, :], K=Ks / d1[None, :], residual=res, method=method,
                      iterations=iterations, scale=d, seconds=seconds, condition=cond,
                      ill_conditioned=bool(not cond <= ILL_CONDITIONED), hamiltonian_gap=gap,
                      backward_error=omega, refinement_steps=steps)
