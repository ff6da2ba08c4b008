"""The design routes of one point (``design.pole_method``), resolved once into a :class:`PoleMethod`.

Every route takes the point's model and the :class:`acmm.design.settings.DesignSettings` and returns
the same record, :class:`PointGain` (the gain u = −K x of eq 5.3 and its evidence, Fig 5.2).

* ``"shift"``, ``"uniform"``: the sector LQR of report ch. 5.2 (:func:`acmm.design.sector_lqr.sector_lqr`);
* ``"lmi"``: regional pole placement by LMIs (:func:`acmm.design.regional_lmi.regional_lmi`), its
  coordinates pre-conditioned by the ``"shift"`` sector LQR of the same settings (its reference,
  kept as :attr:`PointGain.riccati`).

With ``design.robust`` (:func:`with_robust_gain`), any route's gain is the start of a gain designed
for a family of inertias around the point and certified plant by plant
(:mod:`acmm.design.robust`); the record keeps both (:attr:`PointGain.robust`).

The string is read here and only here (:func:`pole_method`, called by
:func:`acmm.design.settings.design_settings`); the rest of the program asks the method object.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Callable

import numpy as np

from acmm.design import sector_lqr
from acmm.design.regional_lmi import RegionalLMI, control_energy, regional_lmi
from acmm.design.robust import RobustDesign, RobustSettings, robust_design
from acmm.model import state_scaling as scaling
from acmm_qpp.errors import DesignError

#: Sector margin asked of the LMI route's reference LQR when it cannot reach ``min_margin``
#: (the reference only pre-conditions the LMI's coordinates), units of n.
LMI_REFERENCE_MARGIN = 0.01


@dataclass(frozen=True)
class PointGain:
    """One design point's gain and its evidence, whichever route made it.

    Attributes
    ----------
    K : (M, N) array
        Gain, u = −K x (eq 5.3), ft·lbf per state unit.
    poles : (N,) complex array
        Eigenvalues of A − BK, rad/s, sorted by real part.
    margin : float
        Worst :func:`~acmm.design.sector_lqr.sector_margin` of the poles, units of n.
    eig_condition : (N,) array
        Eigenvalue condition numbers of A − BK in the scaled coordinates (order of ``poles``),
        dimensionless.
    robustness_radius, robustness_radius_elementwise : float
        First-order sector robustness radii (:func:`~acmm.design.sector_lqr.sector_robustness`),
        normwise (scaled) and elementwise, dimensionless.
    energy : float
        H2 control energy of K (:func:`~acmm.design.regional_lmi.control_energy`), in units of
        the torque scale squared, time in 1/n.
    method : str
        The route's name (``design.pole_method``).
    riccati : acmm.design.sector_lqr.SectorLQR
        The sector LQR the gain is (``shift``, ``uniform``) or that pre-conditioned it (``lmi``):
        its Q, R, P, Riccati residual, backward error and condition.
    lmi : acmm.design.regional_lmi.RegionalLMI or None
        The LMI route's design: certificate X, certified margin, cost bound, random robustness
        re-check, solver and its statistics; None on the LQR routes.
    robust : acmm.design.robust.RobustDesign or None
        With ``design.robust``: the family, the route's nominal gain the search started from and one
        certificate per plant; K, poles, margins and energy are then the robust gain's on the
        nominal plant, ``lmi`` is None (its certificate was of the nominal gain) and ``riccati``
        is the route's reference design.  None without.
    """

    K: np.ndarray
    poles: np.ndarray
    margin: float
    eig_condition: np.ndarray
    robustness_radius: float
    robustness_radius_elementwise: float
    energy: float
    method: str
    riccati: sector_lqr.SectorLQR
    lmi: RegionalLMI | None = None
    robust: RobustDesign | None = None

    @property
    def max_eig_condition(self) -> float:
        """Largest eigenvalue condition number κ of A − BK (scaled), dimensionless."""
        return float(np.max(self.eig_condition)) if self.eig_condition.size else float("nan")


@dataclass(frozen=True)
class PoleMethod:
    """A design route (``design.pole_method``).

    Attributes
    ----------
    name : str
        Its config name.
    design : callable
        ``design(A, B, scales, s)`` → :class:`PointGain` for a model (1/s; state units per
        ft·lbf; state scales) and the design settings ``s``.
    pooled : bool
        Its points are worth designing on a process pool (seconds each, not milliseconds).
    """

    name: str
    design: Callable
    pooled: bool = False


def _reference_lqr(A, B, scales, s, method: str, min_margin: float) -> sector_lqr.SectorLQR:
    """The sector LQR of the settings ``s`` with ``method`` and ``min_margin`` (units of n)."""
    return sector_lqr.sector_lqr(A, B, s.R * np.eye(B.shape[1]), s.orbit_rate, sigma=s.sector.sigma,
                                 half_angle_deg=s.sector.half_angle_deg, Q0=s.q0_weight(A.shape[0]),
                                 scale=scales, method=method, riccati_method=s.riccati_method,
                                 residual_tol=s.residual_tol, min_margin=min_margin,
                                 line_spacing=s.line_spacing, input_scale=scaling.torque_scale(scales))


def _lqr_route(method: str, A, B, scales, s) -> PointGain:
    """The sector LQR with ``method`` (``"shift"``, ``"uniform"``) as a :class:`PointGain`."""
    r = _reference_lqr(A, B, scales, s, method, s.min_margin)
    return PointGain(K=r.K, poles=r.poles, margin=r.margin, eig_condition=r.eig_condition,
                     robustness_radius=r.robustness_radius, robustness_radius_elementwise=r.robustness_radius_elementwise,
                     energy=control_energy(A, B, r.K, s.orbit_rate, scales, scaling.torque_scale(scales)),
                     method=method, riccati=r)


def _lmi_route(A, B, scales, s) -> PointGain:
    """The regional LMI design pre-conditioned by the ``"shift"`` sector LQR (with the configured
    margin, or :data:`LMI_REFERENCE_MARGIN` when the LQR cannot reach it), as a :class:`PointGain`."""
    try:
        ref = _reference_lqr(A, B, scales, s, "shift", s.min_margin)
    except DesignError:
        if s.min_margin <= LMI_REFERENCE_MARGIN:
            raise
        ref = _reference_lqr(A, B, scales, s, "shift", LMI_REFERENCE_MARGIN)
    r = regional_lmi(A, B, s.orbit_rate, ref.K, s.lmi, scale=scales, input_scale=scaling.torque_scale(scales))
    return PointGain(K=r.K, poles=r.poles, margin=r.margin, eig_condition=r.eig_condition,
                     robustness_radius=r.robustness_radius, robustness_radius_elementwise=r.robustness_radius_elementwise,
                     energy=r.energy, method="lmi", riccati=ref, lmi=r)


def with_robust_gain(gain: PointGain, A, B, scales, inertia, bias, theta, s, st: RobustSettings) -> PointGain:
    """The point's record with the gain designed for the family ``st`` around it
    (:func:`acmm.design.robust.robust_design`, started from ``gain.K``): K, poles, margin,
    conditioning, radii and energy of the robust gain on the nominal model (A, B), and
    :attr:`PointGain.robust`.

    Parameters
    ----------
    gain : PointGain
        The route's design of the nominal plant.
    A : (N, N) array
        Nominal design model, 1/s.
    B : (N, M) array
        Its input matrix, state units per ft·lbf.
    scales : (N,) array
        State scales, in the units of each state.
    inertia : (3, 3) array
        Nominal inertia, slug·ft².
    bias : (3,) array
        Bias torque, ft·lbf.
    theta : (3,) array
        Nominal TEA, rad.
    s : acmm.design.settings.DesignSettings
        Design settings (orbital rate, sector, design model, DRF mode).
    st : acmm.design.robust.RobustSettings
        The family.

    Returns
    -------
    PointGain
        The robust design's record.
    """
    n, e = s.orbit_rate, scaling.torque_scale(scales)
    rd = robust_design(inertia, bias, theta, n, gain.K, scales, e, st, model=s.model, drf_mode=s.drf_mode,
                       sector=(s.sector.sigma, s.sector.half_angle_deg))
    d = np.asarray(scales, float)
    lam, _, _, kappa = sector_lqr.eigen_conditioning((A - B @ rd.K) / d[:, None] * d[None, :])
    order = np.lexsort((lam.imag, lam.real))
    margin = float(np.min(sector_lqr.sector_margin(lam, n, s.sector.sigma, s.sector.half_angle_deg)))
    e_norm, e_elem = sector_lqr.sector_robustness(A, B, rd.K, n, s.sector.sigma, s.sector.half_angle_deg, scales)
    # the route's LMI certificate proves things of the nominal gain, not of this one: not kept
    return replace(gain, K=rd.K, poles=lam[order], margin=margin, eig_condition=kappa[order],
                   robustness_radius=e_norm, robustness_radius_elementwise=e_elem,
                   energy=control_energy(A, B, rd.K, n, scales, e), lmi=None, robust=rd)


#: The routes by ``design.pole_method``.
METHODS = {
    "shift": PoleMethod("shift", partial(_lqr_route, "shift")),          # (partials pickle: pool workers)
    "uniform": PoleMethod("uniform", partial(_lqr_route, "uniform")),
    "lmi": PoleMethod("lmi", _lmi_route, pooled=True),
}


def pole_method(name: str) -> PoleMethod:
    """The :class:`PoleMethod` of ``design.pole_method`` ``name``.

    Parameters
    ----------
    name : str
        ``"shift"``, ``"uniform"`` or ``"lmi"``.

    Returns
    -------
    PoleMethod
        The route.

    Raises
    ------
    ValueError
        An unknown name.
    """
    try:
        return METHODS[name]
    except KeyError:
        raise ValueError(f"design.pole_method: unknown route {name!r} (one of {', '.join(METHODS)})") from None
