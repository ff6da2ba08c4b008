"""Matrix sign function by the fifth-order rational iteration of eq 5.6 (CR-185644 ch. 5), used
by :mod:`acmm.design.riccati` (``method="sign"``) on the Hamiltonian of eq 5.5.

The iteration, with the *corrected* denominator (``docs/ERRATA.md`` § Riccati sign function)::

    S(k+1) = S(k) [5I + 10S²(k) + S⁴(k)] [I + 10S²(k) + 5S⁴(k)]⁻¹,   S(0) = M,

evaluated in partial fractions (the same rational map, conditioned like κ(S) instead of κ(S)⁴)
and accelerated by determinantal (or norm) scaling.  The printed denominator I + 10S + 5S⁴ does
not converge to the sign (from the left half-line it either ends at +1 or wanders near −2); it is
kept as ``form="printed"`` only so that tests can show it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm_qpp.errors import ConvergenceError

#: The hint of every failure of the iteration: which setting to change (acmm's config).
SIGN_HINT = "use design.riccati_method: scipy or slycot (the sign iteration needs a well-conditioned model)"

__all__ = ["SignResult", "matrix_sign"]


@dataclass(frozen=True)
class SignResult:
    """Matrix sign function by eq 5.6.

    Attributes
    ----------
    S : (n, n) array
        The limit, sign(M) (dimensionless: S² = I).
    iterations : int
        Iterations taken.
    step : float
        Final relative step ‖S(k+1) − S(k)‖₁ / ‖S(k+1)‖₁, dimensionless.
    """

    S: np.ndarray
    iterations: int
    step: float


#: Partial fractions of eq 5.6 (corrected):  x(5 + 10x² + x⁴)/(1 + 10x² + 5x⁴)
#: = x/5 + Σ c_i x/(x² + a_i),  a_{1,2} = 1 ∓ √0.8 (the roots of 5t² + 10t + 1 are −a_i).
_A1, _A2 = 1.0 - np.sqrt(0.8), 1.0 + np.sqrt(0.8)
_PF = ((float((4.8 - 8.0 * _A1) / (5.0 * (_A2 - _A1))), float(_A1)),
       (float((4.8 - 8.0 * _A2) / (5.0 * (_A1 - _A2))), float(_A2)))


def _accelerated(S, scaling, n):
    """μ S with the determinantal or norm factor μ (S unchanged when μ is unusable)."""
    if scaling == "det":
        sgn, logdet = np.linalg.slogdet(S)
        mu = np.exp(-logdet / n) if sgn != 0 and np.isfinite(logdet) else 1.0
    else:
        try:
            mu = np.sqrt(np.linalg.norm(np.linalg.inv(S)) / np.linalg.norm(S))
        except np.linalg.LinAlgError:
            mu = 1.0
    return mu * S if np.isfinite(mu) and mu > 0 else S


def _step(S, eye, form, evaluation, k):
    """One step S ↦ f(S) of eq 5.6."""
    try:
        if form == "corrected" and evaluation == "partial_fraction":
            # f(S) = S/5 + Σ c_i S (S² + a_i I)⁻¹ and S (S² + a I)⁻¹ = Re (S + i√a I)⁻¹
            S_new = S / 5.0
            for c, a in _PF:
                S_new = S_new + c * np.linalg.inv(S + 1j * np.sqrt(a) * eye).real
        else:
            S2 = S @ S
            S4 = S2 @ S2
            num = S @ (5.0 * eye + 10.0 * S2 + S4)
            den = eye + (10.0 * S2 if form == "corrected" else 10.0 * S) + 5.0 * S4
            S_new = np.linalg.solve(den, num)
    except np.linalg.LinAlgError as exc:
        raise ConvergenceError(f"matrix sign (eq 5.6, {form}): singular denominator "
                               f"at iteration {k}", hint=SIGN_HINT) from exc
    if not np.all(np.isfinite(S_new)):
        raise ConvergenceError(f"matrix sign (eq 5.6, {form}): iteration overflowed "
                               f"at iteration {k}", hint=SIGN_HINT)
    return S_new


def _check_limit(S, M0, eye, tol, form, k) -> None:
    """Refuse a settled S that is not involutory, or involutory but not sign(M)."""
    inv = np.linalg.norm(S @ S - eye, 1)
    if inv > np.sqrt(tol) * max(1.0, np.linalg.norm(S, 1)) ** 2:
        raise ConvergenceError(
            f"matrix sign (eq 5.6, {form}): iteration settled after {k} steps on a "
            f"matrix that is not a sign (‖S²−I‖₁ = {inv:.3g})", hint=SIGN_HINT)
    # sign(M)·M = (M²)^½ has its spectrum in the open right half-plane; a wrong
    # involutory limit (e.g. I for a matrix with stable eigenvalues) fails this.
    mineig = float(np.min(np.linalg.eigvals(S @ M0).real))
    if not mineig > 0.0:
        raise ConvergenceError(
            f"matrix sign (eq 5.6, {form}): iteration converged after {k} steps to an "
            f"involutory matrix that is not sign(M) (eigenvalue of S·M with real part "
            f"{mineig:.3g} ≤ 0)", hint=SIGN_HINT)


def matrix_sign(M, *, scaling: str = "det", tol: float = 1e-13, max_iter: int = 60,
                form: str = "corrected", evaluation: str = "partial_fraction") -> SignResult:
    """Matrix sign function by the fifth-order rational iteration of eq 5.6.

    Parameters
    ----------
    M : (n, n) array
        A matrix with no eigenvalue on the imaginary axis (units of the Hamiltonian, 1/s).
    scaling : {"det", "norm", None}
        Acceleration applied before each step while the step is still large (> 1e-2):
        determinantal μ = |det S|^(−1/n) or norm μ = (‖S⁻¹‖_F / ‖S‖_F)^½; S ← μ S.
    tol : float
        Stop when the relative step ‖S(k+1) − S(k)‖₁/‖S(k+1)‖₁ ≤ tol (dimensionless), or when
        the step stops decreasing after it has fallen below 1e-6 (round-off floor).
    max_iter : int
        Iteration limit.
    form : {"corrected", "printed"}
        ``"corrected"``: denominator I + 10S² + 5S⁴ (``docs/ERRATA.md`` § Riccati sign function).
        ``"printed"``: the report's misprint I + 10S + 5S⁴, kept only to demonstrate that it
        does not converge.
    evaluation : {"partial_fraction", "polynomial"}
        How the corrected rational map is evaluated.  ``"polynomial"`` forms S⁴ and solves with
        I + 10S² + 5S⁴ as printed, whose condition grows like κ(S)⁴ and loses the eigenvalues
        near the imaginary axis when |λ| is widely spread.  ``"partial_fraction"`` (default)
        evaluates the same function as S/5 + Σ c_i Re (S + i√a_i I)⁻¹ (Kenney–Laub; Higham,
        *Functions of Matrices*, sect. 5.4), conditioned like κ(S).  The printed form is always
        evaluated as a polynomial.

    Returns
    -------
    SignResult
        The limit S, the iterations and the last relative step.

    Raises
    ------
    ValueError
        An unknown ``scaling``, ``form`` or ``evaluation``.
    ConvergenceError
        No convergence within ``max_iter``, a singular step, a limit that is not
        involutory (‖S² − I‖₁ > √tol·max(1, ‖S‖₁)²), or an involutory limit that is not the sign
        (S·M must have its spectrum in the open right half-plane).
    """
    M0 = np.array(M, dtype=float)
    S = M0.copy()
    n = S.shape[0]
    eye = np.eye(n)
    if form not in ("corrected", "printed"):
        raise ValueError(f"form must be 'corrected' or 'printed', got {form!r}")
    if evaluation not in ("partial_fraction", "polynomial"):
        raise ValueError(f"evaluation must be 'partial_fraction' or 'polynomial', got {evaluation!r}")
    if scaling not in ("det", "norm", None, "none"):
        raise ValueError(f"scaling must be 'det', 'norm' or None, got {scaling!r}")
    step = np.inf
    for k in range(1, max_iter + 1):
        if scaling in ("det", "norm") and step > 1e-2:
            S = _accelerated(S, scaling, n)
        S_new = _step(S, eye, form, evaluation, k)
        prev, step = step, np.linalg.norm(S_new - S, 1) / np.linalg.norm(S_new, 1)
        S = S_new
        if step <= tol or (step < 1e-6 and step >= prev):
            _check_limit(S, M0, eye, tol, form, k)
            return SignResult(S=S, iterations=k, step=float(step))
    raise ConvergenceError(f"matrix sign (eq 5.6, {form}): no convergence in {max_iter} "
                           f"iterations (last relative step {step:.3g}, tolerance {tol:.1e})", hint=SIGN_HINT)
