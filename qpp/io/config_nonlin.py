"""The ``nonlinearity`` section of a ``qpp`` configuration: the sinusoidal Lure nonlinearity of
ch. 13, the polar arm of ch. 14 (eq 14.1) and general sector-bounded expressions
(:mod:`qpp.model.nonlin`), discriminated by ``kind``.

Moved out of :mod:`qpp.io.config` (issue 12).
"""
from __future__ import annotations

from typing import Annotated, Literal, Optional, Union

from pydantic import Field, field_validator, model_validator

from qpp.io.config_fields import KgM2, Kilograms, Matrix, Metres, RadPerSecond, SectionModel
import re
from qpp.model.expression_parser import library_expression


class SinusoidalNonlinearity(SectionModel):
    """f1(y, γ, t) = F0 y + (F1 + γ F_unc) y sin(ω t), |γ| ≤ gamma_max (ch. 13: F0 = 2, F1 = 1.5, γ = Δm).

    The controller and observer cancel the nominal part f1o = F0 y + F1 y sin(ωt) (γ = 0).
    """

    kind: Literal["sinusoidal"] = "sinusoidal"
    F0: Matrix = Field(description="constant output feedback part (m×p)")
    F1: Matrix = Field(description="nominal time-varying part (m×p), multiplies y sin(ωt)")
    F_unc: Matrix = Field(description="uncertain direction (m×p), multiplies γ y sin(ωt)")
    omega: RadPerSecond = Field(1.0, ge=0, description="frequency of the time variation, rad/s (0: constant)")
    gamma_max: float = Field(gt=0, description="uncertainty bound |γ| ≤ gamma_max (dimensionless)")


class PolarArmNonlinearity(SectionModel):
    """Two-DOF extend/rotate arm of ch. 14 (eq 14.1), uncertain payload M ∈ [M_min, M_max] (kg).

    f1 = [R/(μ+M) x4²; −2 R x3 x4 / I], R = μ x1 + M (x1 + a), I = J1 + J2 + μ x1² + M (x1 + a)².
    """

    kind: Literal["polar_arm"] = "polar_arm"
    mu: Kilograms = Field(gt=0, description="arm mass μ, kg (not printed in the report)")
    M_min: Kilograms = Field(gt=0, description="lower payload bound, kg")
    M_max: Kilograms = Field(gt=0, description="upper payload bound, kg")
    J1: KgM2 = Field(100.0, gt=0, description="inertia of the mechanism about O, kg·m²")
    J2: KgM2 = Field(100.0, gt=0, description="inertia of the arm about C, kg·m²")
    a: Metres = Field(1.0, gt=0, description="distance from the arm's mass centre C to the load, m")

    @model_validator(mode="after")
    def _bounds(self):
        if self.M_max < self.M_min:
            raise ValueError("M_max must be ≥ M_min")
        return self

    @property
    def M_nominal(self) -> float:
        """M° = (M_min + M_max)/2, kg."""
        return 0.5 * (self.M_min + self.M_max)


class ParameterRange(SectionModel):
    """An uncertain parameter θ ∈ [min, max] with its nominal value θ° (default: the midpoint)."""

    min: float
    max: float
    nominal: Optional[float] = Field(None, description="value cancelled by the controller (f1o = f1(θ°))")

    @model_validator(mode="after")
    def _order(self):
        if self.max < self.min:
            raise ValueError("max must be ≥ min")
        if self.nominal is not None and not self.min <= self.nominal <= self.max:
            raise ValueError("nominal must lie in [min, max]")
        return self

    @property
    def nominal_value(self) -> float:
        """θ°: ``nominal``, else the midpoint of [min, max] (units of the parameter)."""
        return 0.5 * (self.min + self.max) if self.nominal is None else self.nominal


class LibraryForm(SectionModel):
    """A library nonlinearity on one output: gain·form(y_output) (qpp.model.nonlin.library_expression)."""

    form: Literal["saturation", "dead_zone", "cubic", "sin"]
    output: int = Field(1, strict=True, ge=1, description="output index (1-based) the form acts on")
    gain: Union[float, str] = Field(1.0, description="number or an expression in the parameters, e.g. 'k'")
    level: Optional[float] = Field(None, gt=0, description="saturation level / dead-zone half-width")


class ExpressionNonlinearity(SectionModel):
    """General sector-bounded f1(y, t, θ) per control channel (qpp.model.nonlin), parsed without eval.

    ``f1`` has one entry per control input: an expression in y1…yp, t and the parameter names
    (functions: sin cos tan exp log sqrt tanh atan abs sign min max sat deadzone cubic), or a
    library form.  The sector, β3 and β4 are computed over ``y_range`` × parameter ranges ×
    [0, t_range]; ``sector``, ``beta3``, ``beta4`` override the computed values.
    """

    kind: Literal["expression"] = "expression"
    f1: list[Union[str, float, LibraryForm]] = Field(min_length=1, description="one entry per control input (m)")
    parameters: dict[str, ParameterRange] = Field(default_factory=dict, description="uncertain parameters")
    y_range: Matrix = Field(description="[[lo, hi], ...] per output: the set on which φ is sector-bounded")
    t_range: Optional[float] = Field(None, gt=0, description="sampled time horizon, s (default: simulation.t_final)")
    sector: Optional[Matrix] = Field(None, description="stated sector [[α, β], ...] of φ (overrides the computed one)")
    beta3: Optional[float] = Field(None, ge=0, description="stated β3 (overrides the computed one)")
    beta4: Optional[float] = Field(None, ge=0, description="stated β4 (overrides the computed one)")
    n_grid: int = Field(41, strict=True, ge=5, le=401, description="grid points per output for the sampled bounds")

    @field_validator("parameters")
    @classmethod
    def _names(cls, v):
        for k in v:
            if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,30}", k):
                raise ValueError(f"parameter name {k!r} is not an identifier")
        return v

    def texts(self) -> list[str]:
        """The channel expressions, library forms expanded.

        Returns
        -------
        list of str
            One expression per control input, in y1…yp, t and the parameter names.
        """
        return [e if isinstance(e, str) else repr(float(e)) if isinstance(e, (int, float))
                else library_expression(e.form, e.output, str(e.gain), e.level) for e in self.f1]

    def param_table(self) -> dict:
        """The uncertain parameters as ``{name: (min, max, nominal)}``.

        Returns
        -------
        dict
            Name → (min, max, θ°), in the units of each parameter.
        """
        return {k: (r.min, r.max, r.nominal_value) for k, r in self.parameters.items()}


Nonlinearity = Annotated[Union[SinusoidalNonlinearity, PolarArmNonlinearity, ExpressionNonlinearity],
                         Field(discriminator="kind")]
