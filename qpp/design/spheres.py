"""Sphere bounds of theorem 2: β1 (exact H∞/L∞ norm), β3, β4, E and the threshold m.

Equations 10.36, 10.44, 10.53–10.57 and 12.1 of CR-185644.  All norms of signals are the
report's vector norms: the largest component norm (ch. 9).
"""
from __future__ import annotations

import numpy as np

from acmm_qpp.errors import ConvergenceError
from qpp.model.transfer import transfer_on_grid
from scipy.linalg import matrix_balance, solve_continuous_lyapunov, svdvals
from slycot import ab13dd
from slycot.exceptions import SlycotArithmeticError


def hinf_norm(A, B, C, D=None, *, method: str = "slycot") -> tuple[float, float]:
    """Exact L∞ norm sup_ω σ_max(C (jωI − A)⁻¹ B + D) and the peak frequency (rad/s).

    Parameters
    ----------
    A : (n, n) array
        State matrix, 1/s.
    B : (n, k) array
        Input matrix, in the units of the state per unit of input and second.
    C : (p, n) array
        Output matrix, in the units of the output per unit of state.
    D : (p, k) array, optional
        Feed-through, in the units of the output per unit of input (default zero).
    method : {"slycot", "hamiltonian"}
        ``"slycot"``: SLICOT AB13DD (Bruinsma–Steinbuch) through :func:`slycot.ab13dd`, called
        with the arguments :func:`control.linfnorm` passes (continuous time, E = I, scaling,
        tolerance 1e-10), so the result is that function's bit for bit without importing
        python-control and scipy.signal (~0.7 s per process, issue 16);
        ``"hamiltonian"``: bisection on the imaginary-axis eigenvalues of the Hamiltonian
        (Boyd–Balakrishnan), an independent implementation used as a cross-check.

    Returns
    -------
    norm : float
        The L∞ norm, in the units of the output per unit of input.
    omega_peak : float
        Frequency of the peak, rad/s.

    Raises
    ------
    ValueError
        ``method`` is neither ``"slycot"`` nor ``"hamiltonian"``.
    """
    A, B, C = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C))
    D = np.zeros((C.shape[0], B.shape[1])) if D is None else np.atleast_2d(np.asarray(D, float))
    if method == "slycot":
        return _hinf_ab13dd(A, B, C, D)
    if method == "hamiltonian":
        return _hinf_hamiltonian(A, B, C, D)
    raise ValueError(f"method must be 'slycot' or 'hamiltonian', got {method!r}")


#: Tolerance of AB13DD on the norm, relative: :func:`control.linfnorm`'s default
AB13DD_TOL = 1e-10


def _hinf_ab13dd(A, B, C, D) -> tuple[float, float]:
    """L∞ norm and peak frequency (rad/s) by SLICOT AB13DD, as :func:`control.linfnorm` calls it."""
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    if n == 0:             # AB13DD takes no empty system; a static gain's norm is its σ_max
        return float(svdvals(D)[0]), 0.0       # as control.linfnorm computes it
    jobd = "Z" if not np.any(D) else "D"
    try:
        gpeak, fpeak = ab13dd("C", "I", "S", jobd, n, m, p, A, np.eye(n), B, C, D, AB13DD_TOL)
    except SlycotArithmeticError as exc:
        raise ConvergenceError(f"L∞ norm (SLICOT AB13DD) failed: {exc}") from exc
    return float(gpeak), float(fpeak)


def _sigma(A, B, C, D, w):
    n = A.shape[0]
    G = C @ np.linalg.solve(1j * w * np.eye(n) - A, B) + D
    return np.linalg.svd(G, compute_uv=False)[0]


def _hinf_hamiltonian(A, B, C, D, tol=1e-10):
    if np.any(np.abs(D) > 0):
        raise ValueError("hamiltonian method implemented for D = 0 only")
    eig = np.linalg.eigvals(A)
    cand = [0.0] + [abs(e.imag) for e in eig] + [abs(e) for e in eig]
    lo, wpk = max(((_sigma(A, B, C, D, w), w) for w in cand), key=lambda p: p[0])     # the first maximiser
    hi = lo * 10 + 1e-12
    n = A.shape[0]

    def crossings(g):
        Hm = np.block([[A, B @ B.T / g ** 2], [-C.T @ C, -A.T]])
        ev = np.linalg.eigvals(Hm)
        scale = max(1.0, np.abs(ev).max())
        return sorted(abs(e.imag) for e in ev if abs(e.real) < 1e-7 * scale)

    while crossings(hi):
        hi *= 10
        if hi > 1e12:
            raise ConvergenceError("Hamiltonian H∞ bisection: norm unbounded (poles on the imaginary axis?)")
    for _ in range(200):
        g = 0.5 * (lo + hi)
        ws = crossings(g)
        if ws:
            mids = [0.5 * (w1 + w2) for w1, w2 in zip(ws, ws[1:])] + ws
            v, w = max((_sigma(A, B, C, D, w), w) for w in mids)
            lo, wpk = max(lo, v), w if v >= lo else wpk
            lo = max(lo, g)
        else:
            hi = g
        if hi - lo <= tol * hi:
            break
    return float(0.5 * (lo + hi)), float(wpk)


def grid_norm(A, B, C, omega) -> tuple[float, float]:
    """max over a frequency grid of σ_max(C (jωI − A)⁻¹ B) — a lower bound for the cross-check.

    Parameters
    ----------
    A : (n, n) array
        State matrix, 1/s.
    B : (n, k) array
        Input matrix, in the units of the state per unit of input and second.
    C : (p, n) array
        Output matrix, in the units of the output per unit of state.
    omega : (N,) array
        Frequency grid, rad/s.

    Returns
    -------
    norm : float
        Largest σ_max on the grid, in the units of the output per unit of input.
    omega_peak : float
        Grid frequency of that largest value, rad/s.
    """
    omega = np.asarray(omega, float)
    G = transfer_on_grid(A, B, C, 1j * omega)
    vals = np.linalg.svd(G, compute_uv=False)[:, 0]
    i = int(np.argmax(vals))
    return float(vals[i]), float(omega[i])


def beta1(Az, Bz, Cz, a: float, *, method: str = "slycot", omega=None) -> dict:
    """β1 = ‖C_z (sI − A_n)⁻¹ B_z‖∞ with A_n = aI + A_z (theorem 2), exactly and on a grid.

    Parameters
    ----------
    Az : (k, k) array
        Closed-loop state matrix of eq 10.7, 1/s.
    Bz : (k, p+r) array
        Closed-loop input matrix of eq 10.7, in the units of the closed loop's state and inputs.
    Cz : (p, k) array
        Closed-loop output matrix of eq 10.7, in the units of y per unit of state.
    a : float
        Exponential weighting, 1/s.
    method : {"slycot", "hamiltonian"}
        Exact norm algorithm (:func:`hinf_norm`).
    omega : (N,) array, optional
        Grid of the cross-check, rad/s.

    Returns
    -------
    dict with ``value`` (exact), ``omega_peak`` (rad/s), ``grid_value`` and ``grid_omega`` (the
    independent cross-check on ``omega``, default 0 and 4000 log-spaced points 1e-3…1e4 rad/s).
    """
    An = np.asarray(Az, float) + a * np.eye(np.shape(Az)[0])
    if np.max(np.linalg.eigvals(An).real) >= 0:
        return {"value": np.inf, "omega_peak": np.nan, "grid_value": np.inf, "grid_omega": np.nan}
    val, wp = hinf_norm(An, Bz, Cz, method=method)
    if omega is None:
        omega = np.concatenate([[0.0], np.logspace(-3, 4, 4000)])
    gv, gw = grid_norm(An, Bz, Cz, omega)
    return {"value": val, "omega_peak": wp, "grid_value": gv, "grid_omega": gw}


def l2_to_peak_gain(An, B, C) -> float:
    """Induced gain from L2 (Euclidean) to the pointwise Euclidean norm of C e^{A_n t} B:
    (λ_max(C P Cᵀ))^½ with A_n P + P A_nᵀ + B Bᵀ = 0 (the step from the L2 sphere of eq 10.43 to
    the L∞ sphere of 10.45: |y_a(t) − y_ao(t)| ≤ this gain × ‖(v)_T‖₂).

    Parameters
    ----------
    An : (k, k) array
        Hurwitz state matrix A_z + aI, 1/s.
    B : (k, q) array
        Input matrix, state units per input unit per s.
    C : (p, k) array
        Output matrix, output units per state unit.

    Returns
    -------
    float
        The gain, output units per input unit per s^½ (inf when A_n is not Hurwitz).
    """
    An, B, C = (np.atleast_2d(np.asarray(x, float)) for x in (An, B, C))
    if np.max(np.linalg.eigvals(An).real) >= 0:
        return float(np.inf)
    # in LAPACK's balanced coordinates (D⁻¹ A_n D, D⁻¹ B, C D; D diagonal, powers of 2, so C P Cᵀ is
    # unchanged exactly): a loop with large gains has ‖A_n‖ orders above its eigenvalues, and the
    # Lyapunov solve in the original coordinates loses digits (ch. 13's qpp_siso_certified: 1e-5
    # relative, below the true gain)
    Ab, (d, _) = matrix_balance(An, permute=False, separate=True)
    Bb, Cb = B / d[:, None], C * d[None, :]
    Pg = solve_continuous_lyapunov(Ab, -Bb @ Bb.T)
    Pg = 0.5 * (Pg + Pg.T)
    return float(np.sqrt(max(np.max(np.linalg.eigvalsh(Cb @ Pg @ Cb.T)), 0.0)))


def E_factor(a: float, T):
    """E = [(e^{2aT} − 1)/(2a)]^{1/2} (eq 10.44); √T in the limit a → 0.

    Parameters
    ----------
    a : float
        Exponential weighting, 1/s.
    T : float or array
        Horizon(s), s.

    Returns
    -------
    float or ndarray
        E, in s^{1/2} (units: square root of seconds), one per horizon.
    """
    aT = a * np.asarray(T, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        E = np.where(aT < 1e-8, np.sqrt(T * (1 + aT)), np.sqrt(np.expm1(2 * aT) / (2 * a if a else 1.0)))
    return float(E) if E.ndim == 0 else E


def truncated_l2(t, y, T: float) -> float:
    """‖(y)_T‖₂ = max_i (∫₀^T y_i² dt)^{1/2} (ch. 9) by the trapezoidal rule on samples.

    ``y`` has shape (len(t),) or (k, len(t)).

    Parameters
    ----------
    t : (N,) array
        Sample times, s.
    y : (N,) or (k, N) array
        Samples of the signal, in its own units.
    T : float
        Horizon, s.

    Returns
    -------
    float
        The truncated L2 norm, in the units of ``y`` times s^{1/2} (0 with fewer than two samples).
    """
    t = np.asarray(t, float)
    y = np.atleast_2d(np.asarray(y, float))
    mask = t <= T + 1e-12
    if mask.sum() < 2:
        return 0.0
    return float(np.sqrt(np.max(np.trapezoid(y[:, mask] ** 2, t[mask], axis=1))))


def sup_abs_sin(omega: float, t0: float, t1):
    """sup |sin ωt| over [t0, t1] (0 ≤ t0 ≤ t1; ``t1`` may be an array), in closed form: 1 when a
    peak ωt = π/2 + kπ lies in the interval, else the larger end.

    Parameters
    ----------
    omega : float
        ω, rad/s.
    t0 : float
        Start, s.
    t1 : float or array
        End(s), s.

    Returns
    -------
    float or array
        The supremum, dimensionless.
    """
    t1 = np.asarray(t1, float)
    peak = (np.pi / 2 + np.ceil((omega * t0 - np.pi / 2) / np.pi) * np.pi) / omega if omega > 0 else np.inf
    return np.where(peak <= t1, 1.0, np.maximum(abs(np.sin(omega * t0)), np.abs(np.sin(omega * t1))))


def sin_l2(omega: float, T: float) -> float:
    """‖(sin ωt)_T‖₂ = (T/2 − sin(2ωT)/(4ω))^{1/2}, exactly; √T for ω = 0 means ‖(1)_T‖₂.

    Parameters
    ----------
    omega : float
        Frequency ω, rad/s.
    T : float
        Horizon, s.

    Returns
    -------
    float
        The truncated L2 norm, in s^{1/2} (units: square root of seconds).
    """
    if omega == 0:
        return float(np.sqrt(T))
    return float(np.sqrt(T / 2 - np.sin(2 * omega * T) / (4 * omega)))


def beta3_sinusoidal(half_width: float, omega: float, T: float) -> float:
    """β3 (eq 10.54) for φ = k·γ̂·y·sin(ωt), |γ̂| ≤ 1: ∇_yφ = k sin ωt, so β3 = k ‖(sin ωt)_T‖₂.

    Parameters
    ----------
    half_width : float
        Gain k, dimensionless (φ per unit of y).
    omega : float
        Frequency ω, rad/s.
    T : float
        Horizon, s.

    Returns
    -------
    float
        β3, in s^{1/2} (units: square root of seconds).
    """
    return float(abs(half_width) * sin_l2(omega, T))


def beta4_sector(half_width: float, t, y_o, T: float) -> float:
    """β4 = ((β − α)/2) ‖(y_o)_T‖₂ (eq 10.55) with φ_o = ((α + β)/2) y_o.

    Parameters
    ----------
    half_width : float
        (β − α)/2, dimensionless.
    t : (N,) array
        Sample times, s.
    y_o : (N,) or (p, N) array
        Observer output samples, in the units of y.
    T : float
        Horizon, s.

    Returns
    -------
    float
        β4, in the units of y times s^{1/2}.
    """
    return float(abs(half_width) * truncated_l2(t, y_o, T))


def threshold_m(beta_o: float, beta_ri: float, d_inf: float, beta3: float, beta4: float) -> float:
    """m = β_o / (β_ri + ‖d‖∞ + β_o β3 + β4) (eqs 10.57, 12.1).

    Parameters
    ----------
    beta_o : float
        β_o, in the units of the truncated L2 norms of the loop's signals.
    beta_ri : float
        β_ri, same units as ``beta_o``.
    d_inf : float
        ‖d‖∞, same units as ``beta_o``.
    beta3 : float
        β3, in the units that make β_o β3 those of ``beta_o``.
    beta4 : float
        β4, same units as ``beta_o``.

    Returns
    -------
    float
        The threshold m, in the units of β_o divided by those of the denominator
        (dimensionless when they agree).
    """
    return float(beta_o / (beta_ri + d_inf + beta_o * beta3 + beta4))
