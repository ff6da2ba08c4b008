"""The scheduled gain judged on the closed loop along the whole path (CR-185644 ch. 5.3).

Design models at ``schedule.n_check`` TEAs evenly spaced along the blend (:func:`path_models`),
the disk margin at the plant input (:func:`acmm.design.disk_margin.disk_margin_input`, batched over
the path) and the path check itself (:func:`check_path`: largest Re λ, worst sector margin, disk
margin).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm.model import linearize as lin
from acmm.design import sector_lqr
from acmm.design.disk_margin import disk_alpha_batch, disk_gain_phase, disk_parts
from acmm.design.schedule import PointDesign
from acmm.design.schedule_points import tea_spaced_blend
from acmm.design.settings import DesignSettings
from acmm.model.tea import solve_tea, solve_tea_near

@dataclass
class PathModels:
    """Local design models at TEAs evenly spaced along the blend path (``schedule.n_check``).

    Attributes
    ----------
    theta2 : (P,) array
        Pitch TEA of each model, rad.
    s : (P,) array
        Blend parameter of each model, dimensionless.
    A : (P, N, N) array
        State matrices, physical units (1/s).
    B : (P, N, M) array
        Control input matrices, state units per ft·lbf.
    scales : (N,) array
        State scaling of the design models, in the units of each state.
    """

    theta2: np.ndarray          # (P,) pitch TEA, rad
    s: np.ndarray               # (P,) blend parameter
    A: np.ndarray               # (P, N, N) physical units
    B: np.ndarray               # (P, N, M)
    scales: np.ndarray          # (N,) state scaling of the design models


@dataclass
class PathCheck:
    """The scheduled gain on the local model at every TEA of a :class:`PathModels`.

    Attributes
    ----------
    theta2 : (P,) array
        Pitch TEA, rad.
    s : (P,) array
        Blend parameter, dimensionless.
    max_real : (P,) array
        Largest Re λ(A − BK(θ2*)), units of n.
    margin : (P,) array
        Worst :func:`acmm.design.sector_lqr.sector_margin`, units of n (> 0: every pole in the sector).
    disk_margin : (P,) array
        Balanced (skew 0) multiloop disk margin α at the plant input (loop broken at u),
        dimensionless (:func:`disk_margin_input`).
    disk_gain_margin_db, disk_phase_margin_deg : (P,) arrays
        The gain (dB) and phase (deg) variations that α guarantees simultaneously in all loops.
    poles : (P, N) complex array
        Closed-loop poles, rad/s.
    """

    theta2: np.ndarray
    s: np.ndarray
    max_real: np.ndarray
    margin: np.ndarray
    disk_margin: np.ndarray
    disk_gain_margin_db: np.ndarray
    disk_phase_margin_deg: np.ndarray
    poles: np.ndarray

    @property
    def fraction_in_sector(self) -> float:
        """Fraction of the TEAs at which every pole lies in the sector, dimensionless."""
        return float(np.mean(self.margin >= 0.0))


def path_models(points: list[PointDesign], s: DesignSettings, n_check: int) -> PathModels | None:
    """Design models at ``n_check`` TEAs evenly spaced between the first and last blend point
    of the designed ``points``.

    None when the config has no blend (``schedule.to``).  The TEA of each model is solved
    exactly (Newton from the continuation guess), so the θ2* are evenly spaced to within the
    interpolation of the 81-point continuation track.

    Parameters
    ----------
    points : list of acmm.design.schedule.PointDesign
        The design points; the first and last blend points bound the path.
    s : DesignSettings
        The design settings (orbital rate, design model, DRF mode).
    n_check : int
        Number of TEAs along the path.

    Returns
    -------
    PathModels or None
        The models, None without a blend.
    """
    n = s.orbit_rate
    blended = sorted((p.spec for p in points if np.isfinite(p.spec.s)), key=lambda p: p.s)
    if len(blended) < 2:
        return None
    track = tea_spaced_blend(blended[0], blended[-1], n_check, n)
    teas = [solve_tea(sp.inertia, n, sp.bias, expected=sp.expected) if sp.theta_guess is None
            else solve_tea_near(sp.inertia, n, sp.bias, sp.theta_guess, expected=sp.expected) for sp in track]
    models = [lin.design_point(sp.inertia, t.theta, n, model=s.model, drf_mode=s.drf_mode)
              for sp, t in zip(track, teas)]
    return PathModels(np.array([t.theta[1] for t in teas]), np.array([sp.s for sp in track]),
                      np.array([m.A for m in models]), np.array([m.B for m in models]), models[-1].scales)


def check_path(gain_at, path: PathModels, n: float, sigma: float = 0.5,
               half_angle_deg: float = 45.0, disk: bool = True) -> PathCheck:
    """Largest Re λ, worst sector margin and disk margin of the scheduled gain along a path.

    ``gain_at(θ2*)`` returns the scheduled K (physical units) at pitch TEA θ2* (rad).

    Parameters
    ----------
    gain_at : callable
        θ2* (rad) → scheduled K (3, N), physical units.
    path : PathModels
        The local models along the path.
    n : float
        Orbital rate, rad/s.
    sigma : float
        Minimum decay rate σ, in units of n.
    half_angle_deg : float
        Sector half-angle φ, deg.
    disk : bool
        Also compute the disk margins (else NaN).

    Returns
    -------
    PathCheck
        The closed-loop measures at every TEA of the path.
    """
    P = path.theta2.size
    dm, dg, dp = (np.full(P, np.nan) for _ in range(3))
    d = path.scales
    Ks = np.array([gain_at(path.theta2[j]) for j in range(P)]) * d[None, None, :]
    As = path.A / d[None, :, None] * d[None, None, :]
    Bs = path.B / d[None, :, None]
    # one batched eigendecomposition of every closed loop, reused by the disk margin
    lam_all, V_all = np.linalg.eig(As - Bs @ Ks)
    poles = np.array([lam[np.lexsort((lam.imag, lam.real))] for lam in lam_all])
    mr = np.max(poles.real, axis=1) / n
    mg = np.min(sector_lqr.sector_margin(poles, n, sigma, half_angle_deg), axis=1)
    if disk:
        # batched branch and bound over every TEA's frequencies
        dm[:] = disk_alpha_batch(disk_parts(As, Bs, Ks, n, eig=(lam_all, V_all)))
        for j in range(P):
            dg[j], dp[j] = disk_gain_phase(dm[j]) if dm[j] > 0 else (0.0, 0.0)
    return PathCheck(path.theta2.copy(), path.s.copy(), mr, mg, dm, dg, dp, poles)
