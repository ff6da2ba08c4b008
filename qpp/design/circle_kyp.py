"""The circle criterion decided by the KYP lemma, not on a frequency grid (issue 43; lemma 1, ch. 9.2).

A sector [α_i, β_i] of φ_i is written φ = C_0 y + Δ(y, t) with C_0 = diag(c_i), c_i the centre
(α_i + β_i)/2 of a diagonal channel (0 for a coupled one) and |Δ_i| ≤ r_i |y_i|, r_i the half-width
(the loop transformation of the circle criterion; Desoer & Vidyasagar, *Feedback Systems*, ch. VI).
The loop ż = A z + B φ(C z) is exponentially stable with rate a when

* A_c = A + B C_0 C + aI is Hurwitz (eigenvalues), and
* the small-gain inequality ‖D R C (sI − A_c)⁻¹ B D⁻¹‖∞ < 1 holds, R = diag(r_i), D a positive
  diagonal scaling (it commutes with a diagonal Δ; for a coupled φ, D = I and R = ρI with ρ of
  :mod:`qpp.design.circle`'s small-gain form).

The frequency-domain inequality is a KYP statement; it is decided by the Hamiltonian matrix
[[A_c, B̃B̃ᵀ], [−C̃ᵀC̃, −A_cᵀ]] (B̃ = B D⁻¹, C̃ = D R C): with A_c Hurwitz the H∞ norm is < 1 exactly
when it has no eigenvalue on the imaginary axis (Boyd, Balakrishnan & Kabamba 1989), the test by
which β1 is computed.  For one channel this is the circle criterion itself (the disc, half-plane or
encirclement condition is the image of the small-gain condition under the loop transformation);
for several diagonal channels it is the scaled small-gain form, a sufficient condition beside
the Gershgorin bands of lemma 1.  The frequency grid of :mod:`qpp.design.circle` remains for the
figures and as a cross-check in the tests.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from qpp.design.spheres import hinf_norm

#: the H∞ norm must be below 1 by this much (relative) for the Hamiltonian test to be taken
MARGIN = 1e-9
#: an eigenvalue of the Hamiltonian with |Re λ| below this fraction of its largest |λ| is on the axis
AXIS_TOL = 1e-9


@dataclass
class KypResult:
    """Outcome of :func:`circle_kyp`.

    Attributes
    ----------
    proved : bool
        The centred loop is Hurwitz and the scaled small-gain inequality holds (KYP, Hamiltonian).
    gain : float
        ‖D R H_c‖∞ at the scaling chosen (< 1 when proved), dimensionless.
    scaling : (m,) ndarray
        The diagonal of D, dimensionless.
    centre : (m,) ndarray
        C_0's diagonal, dimensionless gains.
    radius : (m,) ndarray
        R's diagonal, dimensionless gains.
    hurwitz : bool
        A + B C_0 C + aI Hurwitz.
    text : str
        The outcome in words.
    """

    proved: bool
    gain: float
    scaling: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    hurwitz: bool
    text: str


def _hamiltonian_clear(A, B, C) -> bool:
    """Whether the Hamiltonian [[A, BBᵀ], [−CᵀC, −Aᵀ]] of ‖C (sI − A)⁻¹ B‖∞ < 1 has no eigenvalue on the
    imaginary axis (|Re λ| ≤ AXIS_TOL·max |λ|); with A (1/s) Hurwitz this is the norm being below 1."""
    H = np.block([[A, B @ B.T], [-C.T @ C, -A.T]])
    ev = np.linalg.eigvals(H)
    scale = max(1.0, float(np.abs(ev).max()))
    return bool(np.all(np.abs(ev.real) > AXIS_TOL * scale))


def circle_kyp(A, B, C, sector, a: float = 0.0, coupled=None) -> KypResult:
    """The circle criterion of the sector on ż = A z + B φ(C z), decided by the KYP lemma.

    Parameters
    ----------
    A, B, C : arrays
        Realization of H (A_z, the φ columns of B_z, C_z of eq 10.7), in the units of the
        closed loop's state, φ and y.
    sector : (m, 2) array
        [α_i, β_i] per channel, α_i < β_i, dimensionless gains.
    a : float
        Exponential weighting, 1/s.
    coupled : (m,) bool array, optional
        Channels whose φ_i depends on other outputs (default none).

    Returns
    -------
    KypResult
        The decision, the gain and the scaling.
    """
    A = np.atleast_2d(np.asarray(A, float))
    B = np.atleast_2d(np.asarray(B, float))
    C = np.atleast_2d(np.asarray(C, float))
    s = np.atleast_2d(np.asarray(sector, float))
    m = s.shape[0]
    coupled = np.zeros(m, bool) if coupled is None else np.asarray(coupled, bool)
    centre = np.where(coupled, 0.0, 0.5 * (s[:, 0] + s[:, 1]))
    half = np.where(coupled, np.maximum(np.abs(s[:, 0]), np.abs(s[:, 1])), 0.5 * (s[:, 1] - s[:, 0]))
    if coupled.any():      # Δ is not diagonal: one radius ρ for all, no scaling
        diag_part = float(np.max(half[~coupled] ** 2)) if (~coupled).any() else 0.0
        radius = np.full(m, np.sqrt(diag_part + np.sum(half[coupled] ** 2)))
    else:
        radius = half
    Ac = A + B @ (centre[:, None] * C) + a * np.eye(A.shape[0])
    worst = float(np.max(np.linalg.eigvals(Ac).real))
    if not worst < 0:
        return KypResult(False, np.inf, np.ones(m), centre, radius, False,
                         f"not proved: the centred loop A + B C0 C + aI is not Hurwitz (largest Re = {worst:.4g})")

    def gain(logd):
        d = np.exp(np.concatenate([[0.0], logd]))
        return hinf_norm(Ac, B / d[None, :], (d * radius)[:, None] * C)[0]

    logd = np.zeros(m - 1)
    g = gain(logd)
    if m > 1 and not coupled.any() and g >= 1.0 - MARGIN:
        res = minimize(lambda x: gain(np.clip(x, -30, 30)), logd, method="Nelder-Mead",
                       options={"maxiter": 200 * (m - 1), "xatol": 1e-4, "fatol": 1e-9})
        if res.fun < g:
            logd, g = np.clip(res.x, -30, 30), float(res.fun)
    d = np.exp(np.concatenate([[0.0], logd]))
    clear = g < 1.0 - MARGIN and _hamiltonian_clear(Ac, B / d[None, :], (d * radius)[:, None] * C)
    form = "||R H_c||" if m == 1 else ("rho ||H_c||" if coupled.any() else "||D R H_c D^-1||")
    text = (f"proved by the KYP lemma: centred loop Hurwitz and {form}_inf = {g:.6g} < 1 (Hamiltonian without "
            "imaginary-axis eigenvalues)" if clear else
            f"not proved: {form}_inf = {g:.6g} is not below 1 (KYP lemma, Hamiltonian test)")
    return KypResult(bool(clear), float(g), d, centre, radius, True, text)
