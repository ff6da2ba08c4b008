"""Config sections describing the station: inertia (Table 1, eq 3.2), disturbance (eq 3.9), CMGs.

An inertia may also be written as a symmetric 3×3 list; it must be positive definite, obey the
triangle inequality of principal moments and lie in a plausible range.  The disturbance gives
either its bias or the attitude whose equilibrium bias it is (``bias_from_tea``).

Moved out of :mod:`acmm.io.config` (issue 12).
"""
from __future__ import annotations

from typing import Optional

import numpy as np
from pydantic import Field, field_validator, model_validator

from acmm.io.config_fields import (MIN_PRINCIPAL_MOMENT, AngleVec, InertiaValue, Momentum, Torque,
                                TorqueVec, UNITS, SectionModel, plausible_value)
from acmm_qpp.units import to_canonical


class Inertia(SectionModel):
    """Inertia matrix about the body control axes (slug·ft²), eq 3.2; I_ij = I_ji."""

    I11: InertiaValue = Field(description="roll moment of inertia, slug·ft²")
    I22: InertiaValue = Field(description="pitch moment of inertia, slug·ft²")
    I33: InertiaValue = Field(description="yaw moment of inertia, slug·ft²")
    I12: InertiaValue = Field(0.0, description="product of inertia I12 = I21, slug·ft²")
    I13: InertiaValue = Field(0.0, description="product of inertia I13 = I31, slug·ft²")
    I23: InertiaValue = Field(0.0, description="product of inertia I23 = I32, slug·ft²")

    @model_validator(mode="before")
    @classmethod
    def _from_matrix(cls, data):
        """Accept a 3×3 nested list too; it must then be symmetric."""
        if isinstance(data, (list, tuple)):
            try:
                m = np.array([[to_canonical(x, UNITS["inertia"]) for x in row] for row in data], float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"inertia matrix must be 3×3 numbers: {exc}") from None
            if m.shape != (3, 3):
                raise ValueError(f"inertia matrix must be 3×3, got shape {m.shape}")
            if not np.all(np.isfinite(m)):
                raise ValueError("inertia matrix must contain finite numbers")
            for x in m.ravel():
                plausible_value(float(x), "inertia")
            if not np.allclose(m, m.T, rtol=1e-9, atol=0.0):
                raise ValueError("inertia matrix is not symmetric (I_ij must equal I_ji)")
            return {"I11": m[0, 0], "I22": m[1, 1], "I33": m[2, 2],
                    "I12": m[0, 1], "I13": m[0, 2], "I23": m[1, 2]}
        return data

    @model_validator(mode="after")
    def _physical(self):
        m = self.matrix()
        eig = np.linalg.eigvalsh(m)
        if eig[0] <= 0:
            raise ValueError(
                f"inertia matrix is not positive definite (smallest principal moment {eig[0]:.4g} slug·ft²)")
        if eig[0] < MIN_PRINCIPAL_MOMENT:
            raise ValueError(f"smallest principal moment {eig[0]:.4g} slug·ft² is below the physically plausible "
                             f"{MIN_PRINCIPAL_MOMENT:g} slug·ft²")
        a, b, c = eig
        if a + b < c * (1 - 1e-12):
            raise ValueError(
                "principal moments violate the triangle inequality "
                f"({a:.4g} + {b:.4g} < {c:.4g} slug·ft²): no rigid body has this inertia")
        return self

    def matrix(self) -> np.ndarray:
        """The symmetric 3×3 inertia matrix.

        Returns
        -------
        (3, 3) ndarray
            I, slug·ft².
        """
        return np.array([[self.I11, self.I12, self.I13],
                         [self.I12, self.I22, self.I23],
                         [self.I13, self.I23, self.I33]])


class Disturbance(SectionModel):
    """External torque per body axis, eq 3.9: w_i = bias_i + A_i sin(nt) + B_i sin(2nt) (ft·lbf).

    Give the bias either directly (``bias``) or as ``bias_from_tea``: the attitude (deg) that
    the bias must make a torque equilibrium (eq 4.1).  Neither means zero bias.
    """

    bias: Optional[TorqueVec] = Field(None, description="constant torque [roll, pitch, yaw], ft·lbf")
    bias_from_tea: Optional[AngleVec] = Field(
        None, description="attitude [roll, pitch, yaw] in deg whose equilibrium bias (eq 4.1) is used")
    A: TorqueVec = Field([1.0, 2.0, 1.0], description="amplitude of sin(n t) per axis, ft·lbf")
    B: TorqueVec = Field([0.5, 0.5, 0.5], description="amplitude of sin(2 n t) per axis, ft·lbf")

    @model_validator(mode="after")
    def _one_bias(self):
        if self.bias is not None and self.bias_from_tea is not None:
            raise ValueError("give either 'bias' or 'bias_from_tea', not both")
        if self.bias_from_tea is not None and any(abs(a) >= 89.0 for a in self.bias_from_tea):
            raise ValueError("bias_from_tea angles must lie within ±89 deg (eq 3.6 is singular at 90 deg)")
        return self

    def requested_tea(self) -> np.ndarray | None:
        """The TEA this section asks for (``bias_from_tea``), the ``expected`` root of
        :func:`acmm.model.tea.solve_tea` (its bias may have several equilibria; this one is meant).

        Returns
        -------
        (3,) ndarray or None
            The attitude, rad; None without ``bias_from_tea``.
        """
        return None if self.bias_from_tea is None else np.radians(np.asarray(self.bias_from_tea, float))


class Actuators(SectionModel):
    """CMG actuator limits (report ch. 5.1)."""

    torque_limit: Torque = Field(150.0, description="control torque limit per axis, ft·lbf")
    momentum_limit: Momentum = Field(20000.0, description="CMG momentum limit per axis, ft·lbf·s")

    @field_validator("torque_limit", "momentum_limit")
    @classmethod
    def _positive(cls, v):
        if v <= 0:
            raise ValueError("must be > 0")
        return v
