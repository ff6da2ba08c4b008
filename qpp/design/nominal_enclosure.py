"""The nominal loop enclosed on time cells, so that β4, m and the range premise hold for every
truncation time, not only on the samples (CR-185644 eqs 10.44, 10.53–10.57, 12.1; issue 43).

At the nominal parameter the controller's f1o cancels the plant's f1 exactly (u = K1 x̂ + Kc x_c − f1o,
f1o = f1(x, t, γ°): :mod:`qpp.simulate.closed_loop`), so the nominal loop is linear, ż = A_z z + B_r r_o(t)
(A_z and the reference columns B_r of B_z, eq 10.7).  r_o is a sum of sines, steps and ramps
(:func:`qpp.simulate.closed_loop.eval_signal`): between the switching times of its steps and ramps it is the output
of a linear exosystem (a sine is two states, a channel's ramp and constant two more), so

* the samples z(t_j) at the cell edges are a matrix exponential of the loop and its exosystem
  (no integrator, no step-size control);
* on a cell [t_j, t_j + h] every z(t) lies in z(t_j) ± δ_j with the a-priori (Picard) bound
  δ_j ≤ h (|ż(t_j)| + |A_z| δ_j + |B_r| Δr_j), Δr_j ≥ sup |r_o(t) − r_o(t_j)| on the cell
  (|A| min(2, ωh) per sine, |slope| h per ramp; steps switch only at cell edges), solved by a
  monotone iteration that starts from the ∞-norm solution (each iterate is itself a bound), in
  coordinates balanced by a diagonal scaling (powers of 2) so that h ‖A_z‖∞ is small with few cells.

The enclosures turn the truncated integrals into upper bounds (a cell contributes h × the largest
integrand on its box) and a truncation time T' anywhere in a cell into worst cases of the cell's
ends: :func:`qpp.design.thresholds.consistent`.  What stays assumed is the floating-point
evaluation of the matrix exponential (as of the eigenvalues and the H∞ norm); every bound is
widened by :data:`PAD` relative against the rounding of the sums and products here.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm, matrix_balance

#: cells of [0, T] of the enclosure (and more where r_o switches); the enclosure's gap on y is about
#: h·|ẏ| with h = T / CELLS
CELLS = 32768
#: largest h ‖A_z‖∞ of a cell (the a-priori bound needs it below 1; a stiff loop gets more cells)
STIFF = 0.25
#: most cells of one enclosure (a loop stiffer than that is refused: no bound)
MAX_CELLS = 2_000_000
#: relative widening of every computed bound against floating-point rounding (≫ the few ulps of the
#: sums and products of one cell)
PAD = 1e-10


@dataclass
class NominalEnclosure:
    """The nominal loop ż = A_z z + B_r r_o(t) on [0, T], sampled and enclosed on cells.

    Attributes
    ----------
    edges : (K + 1,) ndarray
        Cell edges, 0 … T, s.
    z : (N, K + 1) ndarray
        z at the edges, in the units of the loop's state.
    lo, hi : (N, K) ndarray
        Bounds of z(t) over each cell [edges[j], edges[j + 1]], units of the state.
    """

    edges: np.ndarray
    z: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def box(self, C) -> tuple:
        """Bounds of C z(t) over each cell (interval matrix product, widened by :data:`PAD`).

        Parameters
        ----------
        C : (k, N) array
            Output matrix, output units per state unit.

        Returns
        -------
        tuple
            (lo, hi), two (k, K) arrays in the output's units.
        """
        C = np.atleast_2d(np.asarray(C, float))
        c, r = 0.5 * (self.lo + self.hi), 0.5 * (self.hi - self.lo)
        yc, yr = C @ c, np.abs(C) @ r
        yr = yr + PAD * (np.abs(C) @ np.abs(c) + yr) + 1e-300
        return yc - yr, yc + yr

    @property
    def h(self) -> np.ndarray:
        """Cell widths, s."""
        return np.diff(self.edges)


def breakpoints(r_o, T: float) -> list:
    """Times in (0, T) where a step or ramp term of r_o switches, s.

    Parameters
    ----------
    r_o : list of list of Term
        The nominal reference, one list of terms per channel.
    T : float
        Horizon, s.

    Returns
    -------
    list of float
        The switching times, sorted, s.
    """
    out = set()
    for ch in r_o or []:
        for tm in ch:
            if tm.kind in ("step", "ramp"):
                out.update(x for x in (tm.t_on, tm.t_off) if x is not None and 0.0 < x < T)
    return sorted(out)


def _exosystem(r_o, t_a: float, t_b: float):
    """(S, Q, w(t_a)) of r_o on [t_a, t_b) (no switching inside): w' = S w, r_o = Q w."""
    p = len(r_o)
    sines = [(i, tm) for i, ch in enumerate(r_o) for tm in ch if tm.kind == "sin"]
    n = 2 * len(sines) + 2 * p
    S, Q, w = np.zeros((n, n)), np.zeros((p, n)), np.zeros(n)
    for k, (i, tm) in enumerate(sines):
        a, b = 2 * k, 2 * k + 1
        S[a, b], S[b, a] = tm.omega, -tm.omega                   # (A sin, A cos)' = ω (A cos, −A sin)
        Q[i, a] = 1.0
        w[a] = tm.amplitude * np.sin(tm.omega * t_a + tm.phase)
        w[b] = tm.amplitude * np.cos(tm.omega * t_a + tm.phase)
    mid = 0.5 * (t_a + t_b)
    for i, ch in enumerate(r_o):
        c, s = 2 * len(sines) + 2 * i, 2 * len(sines) + 2 * i + 1
        S[c, s] = 1.0                                            # constant' = slope
        Q[i, c] = 1.0
        for tm in ch:
            if tm.kind == "step":
                on = -np.inf if tm.t_on is None else tm.t_on
                off = np.inf if tm.t_off is None else tm.t_off
                w[c] += tm.amplitude if on <= mid < off else 0.0
            elif tm.kind == "ramp":
                on = 0.0 if tm.t_on is None else tm.t_on
                off = np.inf if tm.t_off is None else tm.t_off
                w[c] += tm.amplitude * (min(max(t_a, on), off) - on)
                w[s] += tm.amplitude if on <= mid < off else 0.0
    return S, Q, w


def _picard(X: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The least bound δ ≥ 0 of δ ≤ v + X δ (X ≥ 0 with ‖X‖∞ < 1, v ≥ 0 per column), from above:
    ‖δ‖∞ ≤ ‖v‖∞ / (1 − ‖X‖∞), then three steps δ ← v + X δ (each one a bound)."""
    q = float(np.max(X.sum(axis=1)))
    d = np.broadcast_to(np.max(v, axis=0) / (1.0 - q), v.shape).copy()
    for _ in range(3):
        d = np.minimum(d, v + X @ d)
    return d


#: steps propagated by one product with the stacked powers Φ, Φ², …, Φ^BLOCK (:func:`_propagate`)
BLOCK = 64


def _propagate(Phi: np.ndarray, x0: np.ndarray, n: int) -> np.ndarray:
    """x0, Φ x0, …, Φⁿ x0 as columns, BLOCK steps per matrix product (the powers formed once)."""
    k = min(BLOCK, n)
    powers = [Phi]
    for _ in range(k - 1):
        powers.append(Phi @ powers[-1])
    stack = np.vstack(powers)                                      # (k·d, d)
    d = x0.size
    cols = [x0[:, None]]
    for done in range(0, n, k):
        step = min(k, n - done)
        cols.append((stack[:step * d] @ cols[-1][:, -1]).reshape(step, d).T)
    return np.hstack(cols)


def enclose(Az, Br, z0, r_o, T: float, cells: int = CELLS) -> NominalEnclosure:
    """The nominal loop ż = A_z z + B_r r_o(t), z(0) = z0, sampled and enclosed on cells of [0, T].

    Parameters
    ----------
    Az : (N, N) array
        Closed-loop state matrix of eq 10.7, 1/s.
    Br : (N, p) array
        Its reference columns (B_z of eq 10.7), state units per output unit per s.
    z0 : (N,) array
        z(0), state units.
    r_o : list of list of Term
        The nominal reference, output units.
    T : float
        Horizon, s.
    cells : int
        Cells of [0, T] (more where r_o switches), dimensionless.

    Returns
    -------
    NominalEnclosure
        Samples at the edges and bounds on every cell.

    Raises
    ------
    ValueError
        More than :data:`MAX_CELLS` cells would be needed (h ‖D⁻¹ A_z D‖∞ ≤ :data:`STIFF`).
    """
    Az, Br = np.asarray(Az, float), np.atleast_2d(np.asarray(Br, float))
    N, p = Az.shape[0], Br.shape[1]
    r_o = list(r_o or [[] for _ in range(p)])
    # the a-priori bound in balanced coordinates ẑ = D⁻¹z (D diagonal, powers of 2: exact), where
    # ‖D⁻¹ A_z D‖∞ is often orders of magnitude below ‖A_z‖∞ (states of very different sizes)
    scale = matrix_balance(Az, permute=False, separate=True)[1][0] if N else np.ones(0)
    absA = np.abs(Az) * scale[None, :] / scale[:, None]
    absB = np.abs(Br) / scale[:, None]
    norm_a = float(np.max(absA.sum(axis=1))) if N else 0.0
    h0 = min(float(T) / int(cells), STIFF / max(norm_a, 1e-300))
    if T / h0 > MAX_CELLS:
        raise ValueError(f"enclosure needs {T / h0:.3g} cells (T = {T:.3g} s, balanced ‖A_z‖∞ = {norm_a:.3g} 1/s), "
                         f"more than {MAX_CELLS}")
    seg = [0.0, *breakpoints(r_o, T), float(T)]
    edges, Z, LO, HI = [0.0], [np.asarray(z0, float)], [], []
    z = np.asarray(z0, float)
    for t_a, t_b in zip(seg[:-1], seg[1:]):
        n = max(1, int(np.ceil((t_b - t_a) / h0 - 1e-9)))
        h = (t_b - t_a) / n
        S, Q, w = _exosystem(r_o, t_a, t_b)
        M = np.block([[Az, Br @ Q], [np.zeros((S.shape[0], N)), S]])
        Phi = expm(M * h)
        slopes = w[2 * (S.shape[0] // 2 - p) + 1::2][:p] if p else np.zeros(0)
        dr = np.abs(slopes) * h        # per channel, a bound on sup |r_o(t) − r_o(t_j)| over a cell
        for i, ch in enumerate(r_o):
            for tm in ch:
                if tm.kind == "sin":
                    dr[i] += abs(tm.amplitude) * min(2.0, tm.omega * h)
        ZW = _propagate(Phi, np.concatenate([z, w]), n)             # (N + nw, n + 1)
        zs, rs = ZW[:N], Q @ ZW[N:]
        F = np.abs(Az @ zs[:, :-1] + Br @ rs[:, :-1]) / scale[:, None]   # |D⁻¹ ż(t_j)|
        v = h * (F + (absB @ dr)[:, None])
        d = _picard(h * absA, v) * scale[:, None]
        d = d * (1 + PAD) + PAD * np.abs(zs[:, :-1]) + 1e-300
        LO.append(zs[:, :-1] - d)
        HI.append(zs[:, :-1] + d)
        edges.extend(t_a + h * np.arange(1, n + 1))
        edges[-1] = t_b
        Z.extend(zs[:, 1:].T)
        z = zs[:, -1]
    return NominalEnclosure(np.asarray(edges), np.array(Z).T, np.hstack(LO), np.hstack(HI))
