"""Popov–Belevitch–Hautus controllability of the 24-state design model (eq 4.46, ch. 5.2).

The test runs on the state-scaled (A, B) (:meth:`acmm.model.linearize.LinearModel.scaled`), the
torque in the unit of :func:`acmm.model.linearize.torque_scale`, so that the ratio
σmin([A − λI, B]) / σmax([A, B]) depends neither on the states' units nor, beyond the band of
:data:`acmm.model.linearize.MOMENTUM_BAND`, on the station's size (within it the fixed scales stand): a
station 1e-8 times the size of Space Station Freedom was otherwise "uncontrollable" at 3e-13.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from acmm.model.state_scaling import torque_scale

if TYPE_CHECKING:
    from acmm.model.linearize import LinearModel


@dataclass(frozen=True)
class Controllability:
    """PBH controllability of the scaled model.

    ``ratios[i]`` = σmin([A − λ_i I, B]) / σmax([A, B]) at each open-loop eigenvalue λ_i (and
    at s = 0); ``rank`` counts the eigenvalues whose ratio exceeds ``tol``.  See
    ``docs/ERRATA.md`` § Sector LQR for the nearly uncontrollable cross-inertia-free MB3 model.

    Attributes
    ----------
    rank : int
        Number of eigenvalues whose PBH ratio exceeds ``tol`` (of ``order``).
    order : int
        Number of states (24).
    min_ratio : float
        Smallest PBH ratio, dimensionless.
    worst_s : complex
        Point (eigenvalue of the scaled A, or 0) where the ratio is smallest, 1/s.
    tol : float
        Ratio below which an eigenvalue counts as uncontrollable, dimensionless.
    """

    rank: int
    order: int
    min_ratio: float
    worst_s: complex
    tol: float


def controllability(model: LinearModel, tol: float = 1e-10) -> Controllability:
    """Popov–Belevitch–Hautus test on the state-scaled (A, B).

    Parameters
    ----------
    model : LinearModel
        Model of eq 4.46; its state-scaled form (:meth:`LinearModel.scaled`) is tested.
    tol : float
        PBH ratio below which an eigenvalue counts as uncontrollable, dimensionless.

    Returns
    -------
    Controllability
        Rank, smallest ratio and where it occurs.
    """
    a, b, _ = model.scaled()
    b = b * torque_scale(model.scales)            # 1.0 within the band: the report's stations
    nx = a.shape[0]
    points = list(np.linalg.eigvals(a)) + [0.0]
    ratios = pbh_ratios(a, b, points)
    rank = nx - int(np.sum(ratios[:-1] <= tol))        # the last point is s = 0
    i = int(np.argmin(ratios))
    return Controllability(rank=rank, order=nx, min_ratio=float(ratios[i]), worst_s=complex(points[i]),
                           tol=tol)


def pbh_ratios(a: np.ndarray, b: np.ndarray, points) -> np.ndarray:
    """σmin([A − sI, B]) / ‖[A, B]‖₂ at each ``s`` of ``points``.

    Parameters
    ----------
    a : (nx, nx) array
        State matrix (scaled states), 1/s.
    b : (nx, nu) array
        Input matrix, in the input unit of the solve (:func:`acmm.model.linearize.torque_scale`).
    points : sequence of complex
        Where to evaluate, 1/s.

    Returns
    -------
    array
        The ratios, dimensionless.
    """
    nx = a.shape[0]
    norm = np.linalg.norm(np.hstack([a, b]), 2)
    return np.array([np.linalg.svd(np.hstack([a - s * np.eye(nx), b]), compute_uv=False)[-1] / norm
                     for s in points])
