"""Verification of a solution of the continuous algebraic Riccati equation (eq 5.4, CR-185644
ch. 5): the relative residual, the existence check on the Hamiltonian (eq 5.5) and the condition
estimate κ_CARE, and the backward error that decides acceptance, as described in
:mod:`acmm.design.riccati`.

Moved out of :mod:`acmm.design.riccati` (issue 12).
"""
from __future__ import annotations

from typing import NoReturn

import numpy as np
import scipy.linalg as sla

from acmm_qpp.errors import ConvergenceError

#: Relative factor of the rounding band about the imaginary axis (:mod:`acmm.design.riccati`).
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


def _as_R(R, m: int) -> np.ndarray:
    return _as_square(R, m, "R")


def _as_Q(Q, n: int) -> np.ndarray:
    return _as_square(Q, n, "Q")


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
    Q = _as_Q(Q, A.shape[0])
    R = _as_R(R, B.shape[1])
    AtP = A.T @ P
    PB = P @ B
    PGP = PB @ np.linalg.solve(R, PB.T)
    res = AtP + AtP.T - PGP + Q
    den = np.linalg.norm(Q) + 2.0 * np.linalg.norm(AtP) + np.linalg.norm(PGP)
    num = np.linalg.norm(res)
    if den == 0.0:
        return 0.0 if num == 0.0 else float("inf")
    return float(num / den)


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
    Q = _as_Q(Q, A.shape[0])
    R = _as_R(R, B.shape[1])
    G = B @ np.linalg.solve(R, B.T)
    G = 0.5 * (G + G.T)
    AtP = A.T @ P
    res = AtP + AtP.T - P @ G @ P + Q
    aP = np.abs(A).T @ np.abs(P)
    den = float(np.linalg.norm(aP + aP.T + np.abs(P) @ np.abs(G) @ np.abs(P) + np.abs(Q)))
    num = float(np.linalg.norm(0.5 * (res + res.T)))
    if den == 0.0:
        return 0.0 if num == 0.0 else float("inf")
    return num / den


def hamiltonian_check(A, B, Q, R, *, method: str = "") -> float:
    """Refuse a CARE without a stabilizing solution; return the relative spectral gap.

    Computes the eigenvalues λ_i of H = [[A, −G], [−Q, −A']] (G = BR⁻¹B') with their condition
    numbers κ_i and raises :class:`ConvergenceError` if some |Re λ_i| ≤ δ_i (:mod:`acmm.design.riccati`):
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
    n = A.shape[0]
    G = B @ np.linalg.solve(R, B.T)
    H = np.block([[A, -0.5 * (G + G.T)], [-Q, -A.T]])
    hn = float(np.linalg.norm(H))
    if n == 0 or hn == 0.0:
        if n:
            _refuse(f"Riccati solve (method={method!r}): no stabilizing solution "
                           f"(Hamiltonian is zero: every eigenvalue on the imaginary axis)",
                           method, float("nan"))
        return float("inf")
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
            float("nan"))
    return float(np.min(np.abs(w.real)) / hn)


def care_condition(A, B, Q, R, P) -> float:
    """Relative condition estimate κ_CARE of eq 5.4 at the stabilizing P (:mod:`acmm.design.riccati`).

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
    G = B @ np.linalg.solve(R, B.T)
    G = 0.5 * (G + G.T)
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


def _refuse(message: str, method: str, residual: float) -> NoReturn:
    """Raise the :class:`ConvergenceError` of :func:`_refusal`."""
    raise _refusal(message, method, residual)


def _refusal(message: str, method: str, residual: float) -> ConvergenceError:
    exc = ConvergenceError(message)
    exc.method = method          # for reports (scripts/compare_riccati.py)
    exc.residual = residual
    return exc
