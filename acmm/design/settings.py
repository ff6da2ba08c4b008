"""The design settings the numerical core takes, built from a Config at one place.

The core (:mod:`acmm.design.schedule`, :mod:`acmm.design.path_check`, :mod:`acmm.design.schedule_shifted_lqr`,
:mod:`acmm.design.sector_lqr`) takes arrays and these small frozen objects, never the whole Config:
:func:`design_settings` and :func:`schedule_settings` are the only readers of ``cfg.design`` and
``cfg.schedule``'s numerical settings on the design path.

The settings are those of the sector LQR of report ch. 5.2 (sector of Fig 5.2, eqs 5.2–5.4) and
of the gain schedule of ch. 5.3.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm.design.methods import PoleMethod, pole_method
from acmm.design.regional_lmi import RegionalLMISettings
from acmm.design.robust import RobustSettings


@dataclass(frozen=True)
class Sector:
    """The pole sector of Fig 5.2: Re λ ≤ −σ·n and |arg(−λ)| ≤ half angle.

    Attributes
    ----------
    sigma : float
        Minimum decay rate σ, in units of n.
    half_angle_deg : float
        Sector half-angle φ, deg.
    """

    sigma: float            # units of n
    half_angle_deg: float   # deg


@dataclass(frozen=True, eq=False)
class DesignSettings:
    """Everything one sector design of one point needs besides its inertia and bias.

    ``Q0`` is the scalar weight q of Q0 = q·I on the scaled states and ``Q0_groups`` the optional
    per-state diagonal added to it (:meth:`q0_weight`).

    Attributes
    ----------
    orbit_rate : float
        Orbital rate n, rad/s.
    R : float
        Control weight r of R = r·I, 1/(ft·lbf)².
    Q0 : float
        Scaled-state weight q, dimensionless.
    Q0_groups : (nx,) array or None
        Diagonal added to Q0 on the scaled states, dimensionless; or None.
    sector : Sector
        The pole sector.
    method : acmm.design.methods.PoleMethod
        The design route of ``design.pole_method`` (:mod:`acmm.design.methods`): the sector LQR
        (``"shift"``, ``"uniform"``) or the regional LMI (``"lmi"``).
    riccati_method : str
        ``"sign"``, ``"scipy"`` or ``"slycot"``.
    residual_tol : float
        Largest accepted Riccati backward error after refinement
        (:func:`acmm.design.riccati.care_backward_error`), dimensionless.
    min_margin : float
        Required sector margin of every pole, units of n.
    line_spacing : float
        Spacing of the mirror lines of pole shifting, units of n.
    model : str
        Design model (eq 4.46 or a simplification).
    drf_mode : str
        ``"attitude_hold"`` or ``"momentum_hold"``.
    robust : acmm.design.robust.RobustSettings or None
        The family each point's gain is designed for (``design.robust``); None: the nominal plant only.
    lmi : acmm.design.regional_lmi.RegionalLMISettings or None
        The regional LMI design's settings (read by the ``"lmi"`` route only).
    """

    orbit_rate: float                 # rad/s
    R: float                          # control weight R = r·I, 1/(ft·lbf)²
    Q0: float                         # scaled-state weight q (dimensionless)
    Q0_groups: np.ndarray | None      # (nx,) diagonal added to Q0 on the scaled states, or None
    sector: Sector
    method: PoleMethod                # the route of design.pole_method
    riccati_method: str               # "sign", "scipy" or "slycot"
    residual_tol: float
    min_margin: float                 # units of n
    line_spacing: float
    model: str                        # design model (eq 4.46 or a simplification)
    drf_mode: str                     # "attitude_hold" or "momentum_hold"
    lmi: RegionalLMISettings | None = None
    robust: RobustSettings | None = None

    def q0_weight(self, nx: int):
        """The initial state weight on the scaled states: Q0·I plus ``Q0_groups`` on the
        diagonal; None when zero (minimum energy).

        Parameters
        ----------
        nx : int
            Number of states of the model.

        Returns
        -------
        (nx, nx) array or None
            Q0 on the scaled states, dimensionless; None when zero.

        Raises
        ------
        ValueError
            ``Q0_groups`` does not have ``nx`` entries.
        """
        q = np.full(nx, float(self.Q0))
        if self.Q0_groups is not None:
            if self.Q0_groups.size != nx:
                raise ValueError(f"Q0_groups gives {self.Q0_groups.size} weights for a {nx}-state model")
            q = q + self.Q0_groups
        return np.diag(q) if np.any(q > 0) else None


@dataclass(frozen=True)
class ScheduleSettings:
    """How the point gains become a schedule and how it is checked (``cfg.schedule``).

    Attributes
    ----------
    order : int
        Polynomial order of K_ij(θ2*).
    form : str
        ``"polynomial"`` or ``"table"``.
    fit : str
        ``"least_squares"`` or ``"shifted_lqr"`` (the converged quadratic,
        :func:`acmm.design.schedule_shifted_lqr.refit_shifted_lqr`).
    n_check : int or None
        TEAs along the path of the path check (None: no path check).
    spacing : str
        Blend points evenly spaced in ``"tea"`` or in ``"blend"`` s.
    n_points : int
        Blend points including both ends.
    refine_points : int
        At most this many table nodes added where the path check leaves the sector (0: none;
        :func:`acmm.design.design_core.design_schedule`).
    refine_margin : float
        Sector margin the refinement asks of every path check TEA, units of n.
    """

    order: int = 2                    # polynomial order of K_ij(θ2*)
    form: str = "polynomial"          # "polynomial" or "table"
    fit: str = "least_squares"        # or "shifted_lqr" (refit_shifted_lqr)
    n_check: int | None = None        # TEAs along the path of the path check (None: no path)
    spacing: str = "tea"              # blend points evenly spaced in "tea" or in "blend" s
    n_points: int = 12                # blend points including both ends
    refine_points: int = 0            # table nodes added where the path leaves the sector
    refine_margin: float = 0.0        # sector margin asked of every path TEA, units of n


def design_settings(cfg) -> DesignSettings:
    """The :class:`DesignSettings` of a validated :class:`acmm.io.config.Config` (its ``design``
    section and orbital rate) — the one place the design path reads them.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        A validated configuration.

    Returns
    -------
    DesignSettings
        Its design settings.
    """
    d = cfg.design
    return DesignSettings(
        orbit_rate=cfg.orbit_rate, R=d.R, Q0=d.Q0,
        Q0_groups=None if d.Q0_groups is None else d.Q0_groups.diagonal(),
        sector=Sector(d.sector.sigma, d.sector.half_angle_deg),
        method=pole_method(d.pole_method), riccati_method=d.riccati_method, residual_tol=d.residual_tol,
        min_margin=d.min_margin, line_spacing=d.line_spacing, model=d.model, drf_mode=d.drf_mode,
        lmi=RegionalLMISettings(
            sigma=d.sector.sigma, half_angle_deg=d.sector.half_angle_deg, min_margin=d.min_margin,
            backoff=d.lmi.backoff, disk_radius=d.lmi.disk_radius, dilation=d.lmi.dilation, tol=d.lmi.tol,
            regularization=d.lmi.regularization, solver=d.lmi.solver,
            n_random=d.lmi.n_random, seed=d.lmi.seed),
        robust=(RobustSettings(d.robust.inertia_percent, d.robust.samples, d.robust.seed)
                if d.robust.inertia_percent > 0 else None))


def schedule_settings(cfg) -> ScheduleSettings | None:
    """The :class:`ScheduleSettings` of a config, None without a ``schedule`` section.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        A validated configuration.

    Returns
    -------
    ScheduleSettings or None
        Its schedule settings, None without a ``schedule`` section.
    """
    sc = cfg.schedule
    if sc is None:
        return None
    return ScheduleSettings(order=sc.order, form=sc.form, fit=sc.fit_method, n_check=sc.n_check,
                            spacing=sc.spacing, n_points=sc.n_points, refine_points=sc.refine_points,
                            refine_margin=sc.refine_margin)
