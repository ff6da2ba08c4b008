"""Nominal magnitudes of a station's states and torque, for the state-scaled design of eq 4.46
(``docs/ERRATA.md`` § Scaling): a 0.01 rad attitude and, within a band of station sizes that
holds the report's, 1000 ft·lbf·s of CMG momentum and a 1 ft·lbf torque; beyond the band both
follow the station's size, so that a station k times larger or smaller is the same scaled
problem.  :func:`acmm.model.linearize.state_scales` builds the 24 scales from these.
"""
from __future__ import annotations

import numpy as np

#: nominal magnitudes used to scale the states (rad, ft·lbf·s): a 0.01 rad attitude error and
#: 1000 ft·lbf·s of CMG momentum.
NOMINAL_ANGLE = 0.01
NOMINAL_MOMENTUM = 1000.0
#: the stations whose momentum scale is :data:`NOMINAL_MOMENTUM`: natural momentum
#: λmax(I)·n·:data:`NOMINAL_ANGLE` within this band times NOMINAL_MOMENTUM (the report's stations
#: have 261–644 ft·lbf·s; the band holds λmax(I) ≈ 1e6 … 1e10 slug·ft² at n = 0.0011 rad/s)
MOMENTUM_BAND = (1e-2, 1e2)


def momentum_scale(n: float, inertia=None) -> float:
    """Nominal CMG momentum of a station, ft·lbf·s: :data:`NOMINAL_MOMENTUM`, or for a station
    whose natural momentum λmax(I)·n·:data:`NOMINAL_ANGLE` lies outside :data:`MOMENTUM_BAND`
    (times NOMINAL_MOMENTUM), NOMINAL_MOMENTUM times its distance beyond the band.

    A station k times larger in every inertia (its bias, limits and R⁻¹ᐟ² scaled alike) is then,
    beyond the band, the same scaled problem: without it a 0.05 slug·ft² or a 5e12 slug·ft²
    station was called uncontrollable or had no Riccati solution (``docs/ERRATA.md`` § Scaling).

    Parameters
    ----------
    n : float
        Orbital rate, rad/s.
    inertia : (3, 3) or (L, 3, 3) array, optional
        The station's inertia (or several: the largest moment counts), slug·ft²; None:
        :data:`NOMINAL_MOMENTUM`.

    Returns
    -------
    float
        The momentum scale, ft·lbf·s.
    """
    if inertia is None:
        return NOMINAL_MOMENTUM
    inertia = np.asarray(inertia, float)
    largest = float(np.max(np.linalg.eigvalsh(0.5 * (inertia + np.swapaxes(inertia, -1, -2)))))
    ratio = largest * n * NOMINAL_ANGLE / NOMINAL_MOMENTUM
    lo, hi = MOMENTUM_BAND
    if not np.isfinite(ratio) or lo <= ratio <= hi:
        return NOMINAL_MOMENTUM
    return NOMINAL_MOMENTUM * ratio / (lo if ratio < lo else hi)


def torque_scale(scales: np.ndarray) -> float:
    """The torque unit in which a station's LQR is solved, ft·lbf: its momentum scale over
    :data:`NOMINAL_MOMENTUM` (1 for the stations within :data:`MOMENTUM_BAND`), so that beyond
    the band a station k times smaller, with torques k times smaller and R k² times larger,
    is the same scaled problem (:func:`acmm.design.sector_lqr.sector_lqr`, ``input_scale``).

    Parameters
    ----------
    scales : (24,) array
        The state scales of :func:`state_scales` (momentum at index 6, ft·lbf·s).

    Returns
    -------
    float
        The torque unit, ft·lbf.
    """
    return float(scales[6]) / NOMINAL_MOMENTUM
