"""Lure plant, servo-compensator and the closed loop of eq 10.7 (CR-185644 ch. 10.1).

Sign conventions (``docs/ERRATA.md`` § QPP signs, confirmed by rebuilding the printed A_z of eq 13.6 and
Table 14.1 from the printed gains):

* control ``u = K1 x̂ + Kc x_c − f1o``  (closed loop ``A + B K``, eq 10.6);
* observer ``x̂' = A x̂ + B u + B f1o + L (y − C x̂)`` with ``L = −H`` where ``H`` is the
  observer gain *as printed* (eq 10.5 / 13.6);
* the plant nonlinearity enters with ``+f`` (eqs 13.1, 14.2; eq 10.1 prints ``−f``) and the
  observer's ``f_o`` follows the plant.

Two readings of ``B_z`` exist: eq 10.7 (zeros in the observer rows) and the printed matrices of
13.6 / Table 14.1, which carry ``H`` in the reference columns of the observer rows.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm_qpp.errors import ConfigError
from scipy.linalg import matrix_balance

BZ_READINGS = ("eq10.7", "printed")


def _m(x, name: str) -> np.ndarray:
    a = np.atleast_2d(np.asarray(x, dtype=float))
    if not np.all(np.isfinite(a)):
        raise ConfigError(f"{name}: must contain finite numbers")
    return a


@dataclass(frozen=True)
class LurePlant:
    """Matrices of the Lure plant (eq 10.1) and of the servo-compensator (eq 10.2).

    ``x' = A x + B u + G d + B f1(x, y, γ, t)``, ``y = C x``;
    ``x_c' = Ac x_c + Bc (r − y)``, ``y_c = Cc x_c`` (the H∞ output weight W_s = S_c, eq 13.5).

    Attributes
    ----------
    A : (n, n) ndarray
        Plant state matrix, 1/s.
    B : (n, m) ndarray
        Control matrix, in the units of x per unit of u and second.
    C : (p, n) ndarray
        Output matrix, in the units of y per unit of x.
    G : (n, r) ndarray
        Disturbance matrix, in the units of x per unit of d and second.
    Ac : (q, q) ndarray
        Servo-compensator state matrix, 1/s.
    Bc : (q, p) ndarray
        Servo-compensator input matrix, in the units of x_c per unit of y and second.
    Cc : (k, q) ndarray
        Servo-compensator output matrix (H∞ weight W_s), in the units of y_c per unit of x_c.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    G: np.ndarray
    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray

    def __post_init__(self):
        for name in ("A", "B", "C", "G", "Ac", "Bc", "Cc"):
            object.__setattr__(self, name, _m(getattr(self, name), name))
        n, m, p, r, q = self.n, self.m, self.p, self.r, self.q
        checks = [("A", self.A.shape, (n, n)), ("B", self.B.shape, (n, m)), ("C", self.C.shape, (p, n)),
                  ("G", self.G.shape, (n, r)), ("Ac", self.Ac.shape, (q, q)), ("Bc", self.Bc.shape, (q, p)),
                  ("Cc", self.Cc.shape[1:], (q,))]
        for name, got, want in checks:
            if tuple(got) != tuple(want):
                raise ConfigError(f"{name}: shape {tuple(got)} does not match {tuple(want)}")

    @property
    def n(self) -> int:
        """Plant order (dimensionless count)."""
        return self.A.shape[0]

    @property
    def m(self) -> int:
        """Number of controls (dimensionless count)."""
        return self.B.shape[1]

    @property
    def p(self) -> int:
        """Number of outputs, equal to the number of references (dimensionless count)."""
        return self.C.shape[0]

    @property
    def r(self) -> int:
        """Number of disturbances (dimensionless count)."""
        return self.G.shape[1]

    @property
    def q(self) -> int:
        """Servo-compensator order (dimensionless count)."""
        return self.Ac.shape[0]

    def N(self) -> np.ndarray:
        """The matrix N of assumption (iii), ``B = G N`` (least squares; checked exactly).

        Returns
        -------
        (r, m) ndarray
            N, in the units of d per unit of u.

        Raises
        ------
        ConfigError
            If B is not in the range of G (the matching assumption fails).
        """
        N, *_ = np.linalg.lstsq(self.G, self.B, rcond=None)
        atol = 1e-10 * max(1.0, np.abs(self.B).max())
        if not np.allclose(self.G @ N, self.B, atol=atol):
            raise ConfigError("plant: B is not G·N for any N (assumption (iii) of ch. 10.1 fails)")
        # entries at the level of the solve's round-off are zeros (B = G N exactly with them zeroed):
        # kept, a 1e-16 would couple a φ channel to every output (the circle test, the sector grid)
        N0 = np.where(np.abs(N) <= 1e-13 * np.abs(N).max(initial=0.0), 0.0, N)
        return N0 if np.allclose(self.G @ N0, self.B, atol=atol) else N


def augmented(plant: LurePlant):
    """Plant plus servo-compensator, eqs 10.3–10.4.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.

    Returns
    -------
    Aa, Ba, Ga, Ca : ndarray
        ``x_a' = Aa x_a + Ba u + Ga w``, ``y = Ca x_a`` with ``x_a = [x; x_c]`` and ``w = [r; d]``;
        in the units of the blocks of :class:`LurePlant`.
    """
    P = plant
    n, q, p, r, m = P.n, P.q, P.p, P.r, P.m
    Aa = np.block([[P.A, np.zeros((n, q))], [-P.Bc @ P.C, P.Ac]])
    Ba = np.vstack([P.B, np.zeros((q, m))])
    Ga = np.block([[np.zeros((n, p)), P.G], [P.Bc, np.zeros((q, r))]])
    Ca = np.hstack([P.C, np.zeros((p, q))])
    return Aa, Ba, Ga, Ca


def structural_obstacles(plant: LurePlant, tol: float = 1e-9) -> list[str]:
    """Why no output feedback of eqs 10.5–10.6 can stabilize the loop, if the structure says so
    (PBH tests at the closed right-half-plane eigenvalues): an unstable mode of A that u cannot
    move or y does not see, or a servo-compensator pole that the augmented plant (eqs 10.3–10.4)
    cannot move (a plant zero at a servo pole, or more servo channels than inputs can serve).

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    tol : float, optional
        Relative rank tolerance of the PBH tests (singular values below ``tol`` times the
        largest are zero), dimensionless.

    Returns
    -------
    list of str
        One sentence per obstacle found (empty: none; the failure is then numerical).
    """
    def deficient(M, size: int) -> bool:
        return np.linalg.matrix_rank(M, tol * max(1.0, float(np.abs(M).max()))) < size

    out = []
    n = plant.n
    A, B, C = _balanced(plant.A, plant.B, plant.C)          # a rank test blind to state scaling
    for lam in np.linalg.eigvals(A):
        if lam.real < -1e-12:
            continue
        shifted = A - lam * np.eye(n)
        if deficient(np.hstack([shifted, B]), n):
            out.append(f"the plant's mode at s = {lam:.4g} is not controllable from u (PBH test)")
        if deficient(np.vstack([shifted, C]), n):
            out.append(f"the plant's mode at s = {lam:.4g} is not observable from y (PBH test)")
    Aa, Ba, _, Ca = augmented(plant)
    Aa, Ba, _ = _balanced(Aa, Ba, Ca)
    na = Aa.shape[0]
    for lam in np.linalg.eigvals(plant.Ac):
        if lam.real < -1e-12:
            continue
        if deficient(np.hstack([Aa - lam * np.eye(na), Ba]), na):
            out.append(f"the servo-compensator's pole at s = {lam:.4g} cannot be moved by u: the plant has a "
                       "transmission zero there, or fewer inputs than servo channels (eqs 10.3–10.4)")
    return list(dict.fromkeys(out))


def _balanced(A, B, C):
    """(D⁻¹AD, D⁻¹B, CD) with D the diagonal balancing of A (LAPACK gebal, scipy), the columns
    of B and the rows of C then of unit norm: the same controllability and observability, with
    the magnitudes that make a relative rank tolerance meaningful."""
    _, (scale, _) = matrix_balance(np.asarray(A, float), permute=False, separate=True)
    Ab = A / scale[:, None] * scale[None, :]
    Bb = np.asarray(B, float) / scale[:, None]
    Cb = np.asarray(C, float) * scale[None, :]
    Bb = Bb / np.maximum(np.linalg.norm(Bb, axis=0, keepdims=True), 1e-300)
    Cb = Cb / np.maximum(np.linalg.norm(Cb, axis=1, keepdims=True), 1e-300)
    return Ab, Bb, Cb


def closed_loop(plant: LurePlant, K1, Kc, H, *, bz: str = "eq10.7"):
    """Closed-loop matrices (A_z, B_z, C_z) of eq 10.7, state ``z = [x; x_c; x̂]``.

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.
    K1 : (m, n) array
        Observer-state feedback gain (eq 10.6), in the units of u per unit of x.
    Kc : (m, q) array
        Servo-compensator state gain (eq 10.6), in the units of u per unit of x_c.
    H : (n, p) array
        Observer gain with the report's printed sign (``L = −H`` is the output-injection gain),
        in the units of x per unit of y and second.
    bz : {"eq10.7", "printed"}
        ``"eq10.7"``: B_z = [[0, G], [Bc, 0], [0, 0]]; ``"printed"``: the observer rows carry ``H`` in
        the reference columns as in 13.6 and Table 14.1.

    Returns
    -------
    Az : (2n+q, 2n+q) ndarray
        Closed-loop state matrix, 1/s.
    Bz : (2n+q, p+r) ndarray
        Columns ``[r, d]``; the sector nonlinearity φ enters through the ``d`` columns (eq 10.7);
        in the units of z per unit of r, d and second.
    Cz : (p, 2n+q) ndarray
        Output matrix, in the units of y per unit of z.

    Raises
    ------
    ValueError
        ``bz`` is not one of :data:`BZ_READINGS`.
    """
    P = plant
    n, q, p, r = P.n, P.q, P.p, P.r
    K1 = _m(K1, "K1").reshape(P.m, n)
    Kc = _m(Kc, "Kc").reshape(P.m, q)
    H = _m(H, "H").reshape(n, p)
    L = -H
    Az = np.block([
        [P.A, P.B @ Kc, P.B @ K1],
        [-P.Bc @ P.C, P.Ac, np.zeros((q, n))],
        [L @ P.C, P.B @ Kc, P.A + P.B @ K1 - L @ P.C],
    ])
    Bz = np.block([
        [np.zeros((n, p)), P.G],
        [P.Bc, np.zeros((q, r))],
        [np.zeros((n, p + r))],
    ])
    if bz == "printed":
        Bz[n + q:, :p] = H
    elif bz != "eq10.7":
        raise ValueError(f"bz must be one of {BZ_READINGS}, got {bz!r}")
    Cz = np.hstack([P.C, np.zeros((p, q + n))])
    return Az, Bz, Cz


def channels(plant: LurePlant) -> tuple[slice, slice]:
    """Column slices of B_z: (reference columns, disturbance/φ columns).

    Parameters
    ----------
    plant : LurePlant
        The Lure plant and servo-compensator.

    Returns
    -------
    tuple of slice
        (reference columns, disturbance/φ columns).
    """
    return slice(0, plant.p), slice(plant.p, plant.p + plant.r)
