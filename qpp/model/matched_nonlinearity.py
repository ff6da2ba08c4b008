"""The matched nonlinearity f1 (f = B f1, eq 10.1) of a qpp config as a function f1(x, t, γ).

Three kinds (CR-185644 ch. 13–14 and ch. 10.4): a user expression in the outputs
(:mod:`qpp.model.nonlin`), the sinusoidally varying output feedback of ch. 13 and the polar
manipulator arm of ch. 14 (eq 14.2).
"""
from __future__ import annotations

import numpy as np

from qpp.io.config import ExpressionNonlinearity, PolarArmNonlinearity, QppConfig, SinusoidalNonlinearity
from qpp.model.lure import LurePlant


def config_f1(cfg: QppConfig, plant: LurePlant):
    """Matched nonlinearity f1(x, t, γ) ∈ R^m (f = B f1) of the config's kind and the nominal γ
    (for ``kind: expression`` γ is the vector of parameter values, f1 that of the config's
    :meth:`~qpp.io.config.QppConfig.expression_model`, compiled here).

    Parameters
    ----------
    cfg : QppConfig
        The validated config.
    plant : LurePlant
        The Lure plant and servo-compensator.

    Returns
    -------
    f1 : callable
        ``f1(x, t, γ)``, in the units of the config's u.
    gamma_nominal : float or ndarray
        The nominal γ (M for the polar arm, the parameter vector for expressions), in the
        config's units.

    Raises
    ------
    TypeError
        The nonlinearity is of no known kind.
    """
    nl, C = cfg.nonlinearity, plant.C
    if isinstance(nl, ExpressionNonlinearity):
        model = cfg.expression_model()

        def f1(x, t, g):
            return model.f1(C @ x, t, g)
        return f1, model.nom.copy()
    if isinstance(nl, SinusoidalNonlinearity):
        F0, F1, Fu = (np.asarray(getattr(nl, k), float) for k in ("F0", "F1", "F_unc"))

        def f1(x, t, g):
            y = C @ x
            return F0 @ y + (F1 + g * Fu) @ y * np.sin(nl.omega * t)
        return f1, 0.0
    if isinstance(nl, PolarArmNonlinearity):
        mu, J, a = nl.mu, nl.J1 + nl.J2, nl.a

        def f1(x, t, M):
            x1, _, x3, x4 = x
            R = mu * x1 + M * (x1 + a)
            I = J + mu * x1 ** 2 + M * (x1 + a) ** 2
            return np.array([R / (mu + M) * x4 ** 2, -2.0 * R * x3 * x4 / I])
        return f1, nl.M_nominal
    raise TypeError(f"unknown nonlinearity {type(nl).__name__}")

