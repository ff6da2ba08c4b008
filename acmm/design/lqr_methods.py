"""The two sector-enforcement methods of :func:`acmm.design.lqr.sector_lqr` (CR-185644 ch. 5.2).

``"uniform"`` (:func:`_sector_uniform`): the smallest uniform shift α ≥ σn whose LQR puts every
pole in the sector.  ``"shift"`` (:func:`_sector_shift`): the LQR shifted by σn, then optimal
pole shifting of the stray poles, group by group (:func:`_mirror_group`).  See the module
docstring of :mod:`acmm.design.lqr` and ``docs/ERRATA.md`` § Sector LQR.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from acmm_qpp.errors import ConvergenceError, DesignError
from acmm.design.sector import SectorLQR, _check_movable, _finish, _group, _required_h, sector_margin
from acmm.design.riccati import _as_R, scale_problem, solve_care


@dataclass
class _SectorProblem:
    """One sector-LQR problem in the coordinates it is solved in (scaled when ``d`` is given)."""

    As: np.ndarray
    Bs: np.ndarray
    Q0s: np.ndarray
    R: np.ndarray
    d: np.ndarray | None
    n: float
    sigma: float
    half_angle_deg: float
    min_margin: float
    residual_tol: float
    method: str
    riccati_method: str
    e: float = 1.0              # input unit of the solve: Bs and R are B·e and R·e²

    @property
    def alpha(self) -> float:
        return self.sigma * self.n

    def lqr_shifted(self, a):
        """The LQR of (As + a·I, Bs, Q0s, R)."""
        eye = np.eye(self.As.shape[0])
        try:
            return solve_care(self.As + a * eye, self.Bs, self.Q0s, self.R, method=self.riccati_method,
                              tol=self.residual_tol)
        except ConvergenceError as exc:
            raise ConvergenceError(f"sector LQR ({self.method}) at shift α = {a / self.n:.4g}n: {exc}") from exc

    def finish(self, Qs, Ps, shift, mirror_shifts) -> SectorLQR:
        return _finish(self.As, self.Bs, Qs, self.R, Ps, shift, self.n, self.sigma, self.half_angle_deg,
                       self.d, self.min_margin, self.residual_tol, self.method, self.riccati_method,
                       mirror_shifts, self.e)


def _problem(A, B, R, n, sigma, half_angle_deg, Q0, scale, method, riccati_method, residual_tol,
             min_margin, input_scale: float = 1.0) -> _SectorProblem:
    """The arguments of :func:`sector_lqr` as a :class:`_SectorProblem` (scaled, the input in
    units of ``input_scale``, Q0 as a matrix, every pole checked movable)."""
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    nx, m = B.shape
    R = _as_R(R, m)
    if Q0 is None:
        Q0s = np.zeros((nx, nx))
    else:
        Q0s = np.asarray(Q0, dtype=float)
        Q0s = float(Q0s) * np.eye(nx) if Q0s.ndim == 0 else 0.5 * (Q0s + Q0s.T)
    if scale is not None:
        d = np.asarray(scale, dtype=float)
        As, Bs, _ = scale_problem(A, B, np.zeros((nx, nx)), d)
    else:
        d = None
        As, Bs = A, B
    if input_scale != 1.0:
        Bs, R = Bs * input_scale, R * input_scale ** 2
    _check_movable(As, Bs, n, sigma, half_angle_deg, min_margin)
    return _SectorProblem(As, Bs, Q0s, R, d, n, sigma, half_angle_deg, min_margin, residual_tol, method,
                          riccati_method, float(input_scale))


def _sector_uniform(p: _SectorProblem, max_uniform_shift: float) -> SectorLQR:
    """``method="uniform"``: the smallest uniform shift α ≥ σn whose LQR puts every pole in the
    sector (bracketing by 1.25×, then bisection to 0.1 %)."""
    n, alpha = p.n, p.alpha

    def ok(a):
        r = p.lqr_shifted(a)
        lam = np.linalg.eigvals(p.As - p.Bs @ r.K)
        return np.min(sector_margin(lam, n, p.sigma, p.half_angle_deg)) >= p.min_margin, r

    good, r = ok(alpha)
    if good:
        return p.finish(p.Q0s, r.P, alpha, ())
    # Gentle bracketing: the minimum-energy gains grow steeply with α (every mirrored pole
    # moves by 2α), and so does the Riccati condition number.
    lo, hi = alpha, 1.25 * alpha
    while True:
        good, r_hi = ok(hi)
        if good:
            break
        lo = hi
        hi *= 1.25
        if hi > max_uniform_shift * n:
            raise DesignError(f"sector LQR (uniform): no shift α ≤ {max_uniform_shift}n puts "
                              f"every pole in the sector")
    while hi - lo > 1e-3 * hi:
        mid = 0.5 * (lo + hi)
        good, r_mid = ok(mid)
        if good:
            hi, r_hi = mid, r_mid
        else:
            lo = mid
    return p.finish(p.Q0s, r_hi.P, hi, ())


def _sector_shift(p: _SectorProblem, line_spacing: float) -> SectorLQR:
    """``method="shift"``: the LQR shifted by σn, then optimal pole shifting of the stray poles
    (up to 4 sweeps; each group of stray poles needing about the same line is mirrored)."""
    As, Bs, R, n = p.As, p.Bs, p.R, p.n
    phi = np.deg2rad(p.half_angle_deg)
    r0 = p.lqr_shifted(p.alpha)
    Ps = r0.P.copy()
    Qs = p.Q0s.copy()
    target = 1.5 * p.min_margin
    mirror_shifts = []
    for _sweep in range(4):
        Acl = As - Bs @ np.linalg.solve(R, Bs.T @ Ps)
        lam = np.linalg.eigvals(Acl)
        stray = lam[sector_margin(lam, n, p.sigma, p.half_angle_deg) < p.min_margin]
        if stray.size == 0:
            break
        for lo, hi in _group(_required_h(stray, n, p.sigma, phi, target)):
            Ps, Qs = _mirror_group(p, Ps, Qs, lo, hi, line_spacing, target, mirror_shifts)
    return p.finish(Qs, Ps, p.alpha, mirror_shifts)


def _mirror_group(p: _SectorProblem, Ps, Qs, lo, hi, line_spacing, target, mirror_shifts):
    """Mirror the stray poles whose required line h lies in [lo, hi] (all about one line, or
    with ``line_spacing`` > 0 one real-Schur block at a time); returns the updated (P, Q) and
    appends each line used to ``mirror_shifts``."""
    As, Bs, R, n, alpha = p.As, p.Bs, p.R, p.n, p.alpha
    nx = As.shape[0]
    phi = np.deg2rad(p.half_angle_deg)
    Acl = As - Bs @ np.linalg.solve(R, Bs.T @ Ps)

    def select(re, im, lo=lo, hi=hi):
        z = np.array([complex(re, im)])
        if sector_margin(z, n, p.sigma, p.half_angle_deg)[0] >= p.min_margin:
            return False
        h = _required_h(z, n, p.sigma, phi, target)[0]
        return bool(lo * (1 - 0.01) <= h <= hi * (1 + 0.01))

    for k in range(nx if line_spacing > 0 else 1):
        if k:
            Acl = As - Bs @ np.linalg.solve(R, Bs.T @ Ps)
        T, Z, sdim = sla.schur(Acl.T, output="real", sort=select)
        if sdim == 0:
            break
        if line_spacing > 0:
            # one real-Schur block at a time (the leading block is invariant), each
            # about its own line: distinct poles instead of a near-defective cluster
            sdim = 2 if sdim > 1 and T[1, 0] != 0.0 else 1
        T11, U1 = T[:sdim, :sdim], Z[:, :sdim]
        lam1 = np.linalg.eigvals(T11)
        h = float(np.max(_required_h(lam1, n, p.sigma, phi, target)))
        h = max(h, alpha) + k * line_spacing * n
        if line_spacing > 0:
            h = _clear_line(h, lam1, np.linalg.eigvals(T[sdim:, sdim:]), line_spacing, n)
        try:
            sub = solve_care(T11.T + h * np.eye(sdim), U1.T @ Bs, np.zeros((sdim, sdim)), R,
                             method=p.riccati_method, tol=p.residual_tol)
        except ConvergenceError as exc:
            raise DesignError(f"sector LQR (shift): cannot shift the poles λ/n = "
                              f"{np.round(lam1 / n, 4).tolist()} (uncontrollable?): {exc}") from exc
        dP = U1 @ sub.P @ U1.T
        dP = 0.5 * (dP + dP.T)
        Ps = Ps + dP
        Qs = Qs + 2.0 * (h - alpha) * dP
        mirror_shifts.append(h)
    return Ps, Qs


def _clear_line(h: float, lam1, rest, line_spacing: float, n: float) -> float:
    """Raise the mirror line h until the mirrored poles of ``lam1`` land at least
    ``line_spacing``·n from every pole in ``rest`` (nor onto or next to a pole already there)."""
    for _bump in range(400):
        moved = -(2.0 * h + lam1.real) + 1j * np.abs(lam1.imag)
        gap = np.min(np.abs(rest[None, :] - moved[:, None])) if rest.size else np.inf
        if gap >= line_spacing * n:
            break
        h += 0.25 * line_spacing * n
    return h
