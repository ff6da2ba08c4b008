"""Validated ``qpp`` configuration (pydantic v2), read from YAML: the Lure plant and
servo-compensator (eqs 10.1–10.3), the H∞ design settings (ch. 11), the β thresholds of the
design procedure (section 12.1) and the simulation of ch. 13/14.

Units: time s, frequency rad/s, the exponential weighting ``a`` 1/s; plant matrices and signals
are in the user's units (the report's examples: m, rad, kg).  Unknown keys are rejected; a
validation error becomes one :class:`acmm_qpp.errors.ConfigError` line naming the field.
Numbers may be written ``"<number> <unit>"`` (converted to SI on load), within ``QPP_MAX``; the
``nonlinearity`` is sinusoidal (ch. 13), the polar arm (ch. 14, eq 14.1) or a sector-bounded
expression (:mod:`qpp.model.nonlin`), told apart by ``kind``.
"""
from __future__ import annotations

import math
import re
from typing import Annotated, Literal, Optional, Union

import numpy as np
from pydantic import AfterValidator, Field, field_validator, model_validator

from acmm_qpp.config_model import Generator, RunConfig, StrictModel, header, quantity
from acmm_qpp.configio import apply_overrides, read_yaml, remember_origin, validate_model
from acmm_qpp.errors import ConfigError
from acmm_qpp.limits import how_to_raise, limit
from acmm_qpp.results import RUN_NAME_MAX, RUN_NAME_PATTERN, ROOT_PATTERN
from qpp import LIMITS, PACKAGED_CONFIGS
from qpp.model.expression_parser import library_expression
from qpp.model.lure import LurePlant
from qpp.model.nonlin import ExpressionModel


Matrix = list[list[float]]


def _q(unit: str):
    """A number, or a ``"<number> <unit>"`` string converted (pint) to the SI unit ``unit``;
    ``None`` passes (optional fields)."""
    return quantity(unit, allow_none=True)


Seconds = Annotated[float, _q("s")]
OptSeconds = Annotated[Optional[float], _q("s")]
RadPerSecond = Annotated[float, _q("rad/s")]
PerSecond = Annotated[float, _q("1/s")]
Kilograms = Annotated[float, _q("kg")]
Metres = Annotated[float, _q("m")]
KgM2 = Annotated[float, _q("kg*m^2")]
Radians = Annotated[float, _q("rad")]
#: Largest magnitude accepted for any number of a qpp config (matrix entry, gain, weight,
#: amplitude, time); beyond it products in the design and the simulation overflow (issue 13).
QPP_MAX = 1e12


def _implausible(v):
    """The first number in ``v`` (scalar or nested list) with |x| > QPP_MAX, else ``None``."""
    if isinstance(v, (list, tuple)):
        return next((bad for bad in map(_implausible, v) if bad is not None), None)
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) > QPP_MAX else None


class SectionModel(StrictModel):
    """Strict base of every qpp config section: unknown keys, NaN, infinity and booleans given as
    numbers refused (:class:`acmm_qpp.config_model.StrictModel`), and every number within the
    plausible magnitude ``QPP_MAX``."""

    @model_validator(mode="after")
    def _plausible_magnitudes(self):
        for name in type(self).model_fields:
            bad = _implausible(getattr(self, name))
            if bad is not None:
                raise ValueError(f"{name}: {bad:.4g} is outside the plausible range |value| ≤ {QPP_MAX:g}")
        return self


def _finite_matrix(v):
    """``v`` unchanged if a non-empty list of rows of one length of finite numbers (a matrix
    field, units of its field), else ValueError saying what is wrong."""
    if not isinstance(v, list) or not v or not all(isinstance(r, list) for r in v):
        raise ValueError("must be a non-empty matrix (list of rows)")
    if len({len(r) for r in v}) != 1 or not v[0]:
        raise ValueError(f"rows must all have the same, non-zero length (got row lengths {[len(r) for r in v]})")
    a = np.asarray(v, float)
    if not np.all(np.isfinite(a)):
        raise ValueError("must contain finite numbers")
    return v


#: a matrix field (plant, published gains) checked by :func:`_finite_matrix`
FiniteMatrix = Annotated[Matrix, AfterValidator(_finite_matrix)]


def _check_periods(field: str, omega: float, t_final: float) -> None:
    """ValueError (naming ``field``, what to lower and the limit's variable) when a periodic input
    of ``omega`` rad/s over ``t_final`` s is more periods to integrate than the ``QPP_PERIODS`` limit."""
    periods = omega * t_final / (2 * math.pi)
    if periods > limit("QPP_PERIODS", LIMITS):
        raise ValueError(f"{field}: {omega:g} rad/s over simulation.t_final = {t_final:g} s is {periods:.3g} "
                         f"periods to integrate; lower the frequency or t_final ({how_to_raise('QPP_PERIODS', LIMITS)})")


def _check_sector(field: str, sector) -> None:
    """ValueError naming ``field`` unless each pair [α_i, β_i] of a stated sector (None: none;
    dimensionless slopes) has α_i < β_i (lemma 1's critical disc)."""
    for i, (a, b) in enumerate(sector or []):
        if not a < b:
            raise ValueError(f"{field}: pair {i + 1} is [{a:g}, {b:g}]; a sector needs alpha < beta")


#: how far (fraction of the computed half-width) a stated sector may lie inside the computed one:
#: the computed bounds can exceed φ's own by the 1 % widening of a random check that found a point
STATED_SECTOR_SLACK = 0.02


def _check_stated_sector(field: str, stated, computed) -> None:
    """ValueError naming ``field`` unless the sector ``stated`` for an ``expression`` nonlinearity
    holds φ's sector ``computed`` on the stated ranges (one [α, β] pair per channel, dimensionless
    slopes; to :data:`STATED_SECTOR_SLACK`): the circle check and the thresholds of a narrower
    one would certify another nonlinearity."""
    for i, ((a, b), (ca, cb)) in enumerate(zip(np.asarray(stated, float), np.asarray(computed, float))):
        slack = STATED_SECTOR_SLACK * max(0.5 * (cb - ca), 1e-12)
        if a > ca + slack or b < cb - slack:
            raise ValueError(f"{field}: pair {i + 1} [{a:g}, {b:g}] does not hold φ_{i + 1}, whose sector on the "
                             f"stated ranges is [{ca:.6g}, {cb:.6g}]; a certificate for a narrower sector is not one "
                             "for this nonlinearity (widen the pair, or leave the sector out to use the computed one)")


def _check_sample_count(model) -> None:
    """ValueError when the points at which :meth:`qpp.model.nonlin.ExpressionModel.sector_info`
    samples φ (:meth:`~qpp.model.sector_grid.SampleGrid.sector_points`) exceed the
    ``QPP_SECTOR_POINTS`` limit; the message gives the factors and what the config can lower."""
    points = model.sector_points()
    if points <= limit("QPP_SECTOR_POINTS", LIMITS):
        return
    r, k = len(model.phi), len(model.names)
    n_theta, n_t = model.theta_sample_count(), model.time_sample_count()
    sizes = [model.sector_grid_size(i) for i in range(r)]
    widest = int(np.argmax(sizes))
    d = len(model.channel_outputs(widest))
    factors = (f"over {r} channel{'s' * (r != 1)}: {n_theta:.3g} samples of {k} uncertain parameter"
               f"{'s' * (k != 1)} × the channel's output grid, {sum(sizes):.3g} points in all, the largest "
               f"{max(sizes):.3g} (channel {widest + 1}, on {d} output{'s' * (d != 1)})"
               + (f", × {n_t} times on the channels that depend on t" if n_t > 1 else ""))
    # what the config can lower: the parameters (a factor of every point), and whichever grids hold
    # most of the points: those of channels on three or more outputs, or the n_grid-point ones
    wide = sum(n for i, n in enumerate(sizes) if len(model.channel_outputs(i)) >= 3)
    advice = ["fewer uncertain parameters (nonlinearity.parameters)"] if k > 1 else []
    if 2 * wide >= sum(sizes):
        advice.append("fewer outputs per channel (nonlinearity.f1)")
    elif model.n_grid > 5:
        advice.append(f"a coarser nonlinearity.n_grid (now {model.n_grid})")
    raise ValueError(f"nonlinearity: finding the sector samples φ at {points:.3g} points ({factors}); "
                     f"use {' or '.join(advice) or 'fewer nonlinear channels'} "
                     f"({how_to_raise('QPP_SECTOR_POINTS', LIMITS)})")


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

    def _texts(self) -> list[str]:
        """The channel expressions (one per control input, in y1…yp, t and the parameter names),
        library forms expanded."""
        return [e if isinstance(e, str) else repr(float(e)) if isinstance(e, (int, float))
                else library_expression(e.form, e.output, str(e.gain), e.level) for e in self.f1]

    def _param_table(self) -> dict:
        """The uncertain parameters as ``{name: (min, max, θ°)}``, in the units of each parameter."""
        return {k: (r.min, r.max, r.nominal_value) for k, r in self.parameters.items()}


Nonlinearity = Annotated[Union[SinusoidalNonlinearity, PolarArmNonlinearity, ExpressionNonlinearity],
                         Field(discriminator="kind")]


class Term(SectionModel):
    """One additive term of a signal: sin, step (on [t_on, t_off)), or ramp held after t_end."""

    kind: Literal["sin", "step", "ramp"]
    amplitude: float = Field(1.0, description="sin amplitude / step value / ramp slope (per s)")
    omega: RadPerSecond = Field(0.0, ge=0, description="sin frequency, rad/s")
    phase: Radians = Field(0.0, description="sin phase, rad")
    t_on: OptSeconds = Field(None, description="step/ramp start, s (default: −∞ for a step, 0 for a ramp)")
    t_off: OptSeconds = Field(None, description="step end / ramp hold time, s (default: never)")


Signal = list[list[Term]]   # one list of terms per channel


class Scenario(SectionModel):
    """A simulation case: r = r_o + delta_r, uncertain parameter value, disturbance impulse."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX)
    delta_r: Optional[Signal] = Field(None, description="reference perturbation r − r_o per channel")
    gamma: float = Field(0.0, description="uncertain parameter: γ (sinusoidal) or payload M in kg (polar_arm)")
    parameters: Optional[dict[str, float]] = Field(None, description="expression kind: parameter values "
                                                                     "(missing ones nominal)")
    impulse_time: OptSeconds = Field(None, ge=0, description="time of a disturbance impulse d = I δ(t − t_i), s")
    impulse: Optional[list[float]] = Field(None, description="impulse size I per disturbance channel (r)")


class Simulation(SectionModel):
    """Nonlinear closed-loop simulation (ch. 13.4 / 14.5)."""

    t_final: Seconds = Field(10.0, ge=1e-9, le=1e5, description="simulated time, s (1 ns … 1e5 s)")
    n_samples: int = Field(2001, strict=True, ge=11, le=200001, description="output samples")
    rtol: float = Field(1e-8, ge=1e-14, lt=1, description="integrator relative tolerance (≥ 1e-14: ~100 ulp)")
    atol: float = Field(1e-10, ge=1e-20, lt=1, description="integrator absolute tolerance")
    r_o: Signal = Field(description="nominal reference r_o(t), one list of terms per output")
    scenarios: list[Scenario] = Field(min_length=1)


class Plant(SectionModel):
    """Lure plant x' = A x + B u + G d + B f1(·), y = C x (eqs 10.1, 13.1, 14.2) and servo-compensator."""

    A: FiniteMatrix = Field(description="plant state matrix (n×n), 1/s")
    B: FiniteMatrix = Field(description="control input matrix (n×m)")
    C: FiniteMatrix = Field(description="output matrix (p×n)")
    G: FiniteMatrix = Field(description="disturbance input matrix (n×r), B = G N (assumption iii)")
    Ac: FiniteMatrix = Field(description="servo-compensator matrix (q×q), eq 10.2: internal model of r_o")
    Bc: FiniteMatrix = Field(description="servo-compensator input matrix (q×p), driven by e = r − y")
    Cc: FiniteMatrix = Field(description="servo output matrix (·×q): the H∞ weight W_s e = C_c x_c (13.5)")
    x0: Optional[list[float]] = Field(None, description="initial plant state (n), default 0; observer starts equal")
    xc0: Union[Literal["zero", "equilibrium"], list[float]] = Field(
        "zero", description="initial servo state: 0, 'equilibrium' (K_c x_c = −K_1 x0, least squares) or a list")


class Hinf(SectionModel):
    """Chapter 11 H∞ gains (Riccati 11.1 and the observer Riccati)."""

    rho: float = Field(gt=0, description="control weight ρ in z = [ρ u; W_s e] (dimensionless)")
    a: PerSecond = Field(ge=0, description="exponential weighting a, 1/s (10.27); the report uses 1e-8 / 1e-9")
    nu: float = Field(1.0, gt=0, description="H∞ level ν of the scaling 11.3 (γ = ν)")
    weight: Literal["servo", "output"] = Field("servo", description="state weight [0 Cc] or printed [C 0]")
    observer: Literal["filter", "dgkf"] = Field("filter", description="observer gain formula")
    w: float = Field(1.0, gt=0, description="output weight scale w in W_s = w·S_c of z = [ρ u; W_s e] "
                                            "(13.5), dimensionless; the report uses 1")
    search: bool = Field(False, description="run the ch. 11 steps 1-8 search over ν and ρ")


class Published(SectionModel):
    """Gains and numbers printed in the report, for comparison (and optionally for use)."""

    K1: Optional[FiniteMatrix] = Field(None, description="printed K1 (m×n)")
    Kc: Optional[FiniteMatrix] = Field(None, description="printed Kc (m×q)")
    H: Optional[FiniteMatrix] = Field(None, description="printed observer gain H (n×p), report's sign")
    beta1: Optional[float] = Field(None, description="printed β1")
    beta3: Optional[float] = Field(None, description="printed β3")
    beta4: Optional[float] = Field(None, description="printed β4")
    m: Optional[float] = Field(None, description="printed threshold m")


class Spheres(SectionModel):
    """Input/output spheres (eqs 10.34–10.35) and the truncation time T."""

    beta_o: float = Field(gt=0, description="output sphere radius β_o, output units")
    beta_ri: float = Field(ge=0, description="reference sphere radius β_ri, output units")
    d_inf: float = Field(0.0, ge=0, description="‖d‖∞ used in the threshold m (12.1)")
    T: Seconds = Field(gt=0, le=1e4, description="truncation time T, s (settling time; 10.44)")
    adapt_T: bool = Field(True, description="12.1 step 3: adapt T to the closed loop's settling time")
    settle_band: float = Field(0.05, gt=0, lt=1, description="settling: |y_o − r_o| stays below this "
                                                             "fraction of its peak after T")


class Design(SectionModel):
    """Design procedure of ch. 12.1."""

    gains: Literal["design", "published"] = Field("design", description="use the H∞ gains or the printed ones")
    sector: Optional[Matrix] = Field(None, description="sector [[α_i, β_i], ...] of φ for the circle check; "
                                                        "default from the nonlinearity")
    bz: Literal["eq10.7", "printed"] = Field("eq10.7", description="B_z reading for the design loop")
    bookkeeping: Literal["consistent", "printed", "report", "circle", "trajectory"] = Field(
        "consistent", description="threshold m the design iterates against: consistent (the certificate's, "
        "one sector and one norm), or a reproduction of the report's bookkeeping (printed, report, circle, "
        "trajectory; never a certificate by itself; see docs/qpp-certificates.md)")
    max_iter: int = Field(8, strict=True, ge=1, le=100, description="iterations of ch. 12.1 (ρ ← ρ·rho_factor when β1 > m)")
    rho_factor: float = Field(0.5, gt=0, lt=1, description="ρ reduction per iteration")
    a_factor: float = Field(0.1, gt=0, lt=1, description="a reduction when the circle criterion fails")
    a_min: Optional[float] = Field(None, ge=0, description="smallest a tried, 1/s (default a·1e-4)")
    a_max: Optional[float] = Field(None, ge=0, description="largest a tried, 1/s (default the configured a)")
    rho_min: float = Field(1e-8, gt=0, description="ε of ch. 11 step 6: smallest ρ")
    rho_max: float = Field(1e2, gt=0, description="largest ρ of the wider bracketing search")
    wider_search: bool = Field(True, description="when 12.1 fails: other W_s weights and a bracketing ρ search")
    ws_scales: list[float] = Field([1.0, 0.3, 3.0, 0.1, 10.0], min_length=1,
                                   description="W_s = w·S_c scalings tried by the wider search (absolute, not scaled by hinf.w)")


class Output(SectionModel):
    """Where results go."""

    root: str = Field("runs", pattern=ROOT_PATTERN, description="results root; files go to <root>/<name>/")
    figures: bool = Field(True, description="write PNG figures next to the HDF5 files")
    units: Literal["SI"] = Field("SI", description="unit system of the results: qpp works in SI (s, rad/s, kg, m); "
                                                   "plant signals are in the user's units")

    @field_validator("units", mode="before")
    @classmethod
    def _unit_system_in_any_case(cls, v):
        """``si`` or ``Si``: the unit system's name, whatever its case."""
        return "SI" if isinstance(v, str) and v.strip().lower() == "si" else v


_EXPR_CACHE: dict = {}


class QppConfig(SectionModel, RunConfig):
    """A complete ``qpp`` configuration."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX,
                      description="run name (as for acmm: letters, digits, _ . -, not starting with a dot); "
                                  "results go to <root>/<name>/")
    description: str = ""
    plant: Plant
    nonlinearity: Nonlinearity
    hinf: Hinf
    spheres: Spheres
    design: Design = Design()
    published: Published = Published()
    simulation: Simulation
    output: Output = Output()

    @model_validator(mode="after")
    def _consistent(self):
        try:
            P = self.lure_plant()
        except ConfigError as exc:
            msg = str(exc)
            raise ValueError(("plant." + msg) if msg.split(":")[0] in ("A", "B", "C", "G", "Ac", "Bc", "Cc")
                             else msg) from None
        if self.plant.x0 is not None and len(self.plant.x0) != P.n:
            raise ValueError(f"plant.x0 must have {P.n} entries")
        if isinstance(self.plant.xc0, list) and len(self.plant.xc0) != P.q:
            raise ValueError(f"plant.xc0 must have {P.q} entries")
        self._check_nonlinearity(P)
        self._check_signals_and_gains(P)
        self._check_resolution_and_limits()
        return self

    def _check_nonlinearity(self, P):
        """Shapes of the nonlinearity section against the plant P; its parameters per scenario."""
        nl = self.nonlinearity
        if P.r != P.p:
            raise ValueError(f"nonlinearity.kind {nl.kind} needs as many disturbance channels as outputs "
                             f"(G has {P.r} columns, C {P.p} rows) for the circle criterion")
        if isinstance(nl, SinusoidalNonlinearity):
            for nm in ("F0", "F1", "F_unc"):
                if np.shape(getattr(nl, nm)) != (P.m, P.p):
                    raise ValueError(f"nonlinearity.{nm} must be {P.m}×{P.p}")
            self._check_gamma_scenarios(nl.kind, -nl.gamma_max, nl.gamma_max)
        elif isinstance(nl, ExpressionNonlinearity):
            if len(nl.f1) != P.m:
                raise ValueError(f"nonlinearity.f1 must have {P.m} entries (one per control input)")
            if np.shape(nl.y_range) != (P.p, 2) or any(lo >= hi for lo, hi in nl.y_range):
                raise ValueError(f"nonlinearity.y_range must be {P.p} pairs [lo, hi] with lo < hi")
            for e in nl.f1:
                if isinstance(e, LibraryForm) and e.output > P.p:
                    raise ValueError(f"nonlinearity.f1: output {e.output} > p = {P.p}")
            if nl.sector is not None and np.shape(nl.sector) != (P.r, 2):
                raise ValueError(f"nonlinearity.sector must be {P.r} pairs [alpha, beta]")
            _check_sector("nonlinearity.sector", nl.sector)
            try:
                model = self.expression_model()
                _check_sample_count(model)
                info = model.sector_info                 # parse, check singular / sector-bounded
            except ConfigError as exc:
                raise ValueError(str(exc)) from None
            for field, stated in (("nonlinearity.sector", nl.sector), ("design.sector", self.design.sector)):
                if stated is not None:
                    _check_stated_sector(field, stated, info.sector)
            self._check_expression_scenarios(nl)
        elif (P.n, P.m, P.p) != (4, 2, 2):
            raise ValueError("nonlinearity.kind polar_arm needs n=4, m=2, p=2 (eq 14.2)")
        else:
            self._check_gamma_scenarios(nl.kind, nl.M_min, nl.M_max)

    def _check_gamma_scenarios(self, kind: str, lo: float, hi: float):
        """The scenarios of a ``sinusoidal`` (γ = Δm) or ``polar_arm`` (γ = M, kg) nonlinearity set
        γ within [lo, hi] and no expression parameters."""
        for s in self.simulation.scenarios:
            if s.parameters:
                raise ValueError(f"scenario {s.name}: nonlinearity.kind {kind} takes gamma, not parameters")
            if not lo <= s.gamma <= hi:
                raise ValueError(f"scenario {s.name}: gamma = {s.gamma:g} outside [{lo:g}, {hi:g}] "
                                 f"(nonlinearity.kind {kind})")

    def _check_expression_scenarios(self, nl):
        """The scenarios of an ``expression`` nonlinearity set its parameters within their ranges."""
        for s in self.simulation.scenarios:
            if s.gamma != 0.0:
                raise ValueError(f"scenario {s.name}: nonlinearity.kind expression takes parameters: "
                                 "{name: value}, not gamma")
            for k in (s.parameters or {}):
                if k not in nl.parameters:
                    raise ValueError(f"scenario {s.name}: unknown parameter {k!r}")
                rg = nl.parameters[k]
                if not rg.min <= s.parameters[k] <= rg.max:
                    raise ValueError(f"scenario {s.name}: parameter {k} = {s.parameters[k]} outside "
                                     f"[{rg.min}, {rg.max}]")

    def _check_signals_and_gains(self, P):
        """Channel counts of the reference, the scenarios, the design sector and published gains."""
        if len(self.simulation.r_o) != P.p:
            raise ValueError(f"simulation.r_o must have {P.p} channels (one per output)")
        for s in self.simulation.scenarios:
            if s.delta_r is not None and len(s.delta_r) != P.p:
                raise ValueError(f"scenario {s.name}: delta_r must have {P.p} channels")
            if s.impulse is not None and len(s.impulse) != P.r:
                raise ValueError(f"scenario {s.name}: impulse must have {P.r} entries")
            if (s.impulse is None) != (s.impulse_time is None):
                raise ValueError(f"scenario {s.name}: give both impulse and impulse_time")
        if self.design.sector is not None and np.shape(self.design.sector) != (P.r, 2):
            raise ValueError(f"design.sector must be {P.r} pairs [alpha, beta]")
        _check_sector("design.sector", self.design.sector)
        names = [s.name for s in self.simulation.scenarios]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"simulation.scenarios: duplicate name {dup[0]!r} (each run is stored under its name)")
        if "cartesian" in names and isinstance(self.nonlinearity, PolarArmNonlinearity):
            raise ValueError("simulation.scenarios: the name 'cartesian' is the polar arm's cartesian figure "
                             "(qpp_sim_cartesian.png); give the scenario another name")
        d = self.design
        if d.rho_min >= d.rho_max:
            raise ValueError(f"design.rho_min = {d.rho_min:g} must be below design.rho_max = {d.rho_max:g}")
        if d.a_min is not None and d.a_max is not None and d.a_min > d.a_max:
            raise ValueError(f"design.a_min = {d.a_min:g} must not exceed design.a_max = {d.a_max:g}")
        if self.design.gains == "published" and any(
                x is None for x in (self.published.K1, self.published.Kc, self.published.H)):
            raise ValueError("design.gains = published needs published.K1, Kc and H")
        pub = self.published
        for nm, want in (("K1", (P.m, P.n)), ("Kc", (P.m, P.q)), ("H", (P.n, P.p))):
            got = getattr(pub, nm)
            if got is not None and np.shape(got) != want:
                raise ValueError(f"published.{nm} must be {want[0]}×{want[1]}, got {np.shape(got)[0]}×"
                                 f"{np.shape(got)[1]}")

    def _check_resolution_and_limits(self):
        """Sinusoids resolved by the integrator, sample budget, no overflow of e^(2aT) (eq 10.44)."""
        nl = self.nonlinearity
        if isinstance(nl, SinusoidalNonlinearity) and nl.omega > 0:
            # the nonlinearity's sin(ω t) must be resolved by the integrator: bound the periods
            _check_periods("nonlinearity.omega", nl.omega, self.simulation.t_final)
        for sig_name, sig in [("simulation.r_o", self.simulation.r_o)] + [
                (f"simulation.scenarios.{s.name}.delta_r", s.delta_r) for s in self.simulation.scenarios]:
            for chan in sig or []:
                for term in chan:
                    if term.kind == "sin" and term.omega > 0:
                        _check_periods(f"{sig_name} omega", term.omega, self.simulation.t_final)

        runs = len(self.simulation.scenarios) + 1
        if self.simulation.n_samples * runs > limit("QPP_SAMPLES", LIMITS):
            raise ValueError(f"simulation.n_samples: {self.simulation.n_samples} samples × {runs} runs (scenarios + "
                             f"the nominal loop) is too many; lower n_samples or the scenarios "
                             f"({how_to_raise('QPP_SAMPLES', LIMITS)})")
        if 2 * self.hinf.a * self.spheres.T > 600:
            raise ValueError(f"hinf.a × spheres.T = {self.hinf.a * self.spheres.T:.4g}: e^(2aT) of eq 10.44 "
                             "overflows; lower hinf.a or spheres.T")

    def lure_plant(self):
        """The Lure plant of this config (eqs 10.1–10.3).

        Returns
        -------
        qpp.model.lure.LurePlant
            Plant (A, B, C, G) and servo-compensator (Ac, Bc, Cc), in the user's units.
        """
        p = self.plant
        return LurePlant(p.A, p.B, p.C, p.G, p.Ac, p.Bc, p.Cc)

    def sinusoidal_half_widths(self) -> np.ndarray:
        """φ's own sector half-width per output for the ``sinusoidal`` kind, |N F_unc|·1·γ_max (row
        sums; φ = N (γ F_unc) y sin ωt is the uncertain part, eq 13.6).

        Returns
        -------
        (p,) array
            Half-widths, φ units per unit of y.
        """
        nl = self.nonlinearity
        return np.abs(self.lure_plant().N() @ np.asarray(nl.F_unc, float)).sum(axis=1) * nl.gamma_max

    def expression_model(self):
        """The compiled model of an ``expression`` nonlinearity f1 (eq 10.1), cached.

        Returns
        -------
        qpp.model.nonlin.ExpressionModel
            The compiled expression with its sector and Lipschitz bounds.

        Raises
        ------
        TypeError
            If ``nonlinearity.kind`` is not ``expression``.
        """
        nl = self.nonlinearity
        if not isinstance(nl, ExpressionNonlinearity):
            raise TypeError("expression_model() needs nonlinearity.kind = expression")
        P = self.lure_plant()
        t_range = nl.t_range or max(self.simulation.t_final, self.spheres.T)
        key = (tuple(nl._texts()), tuple(sorted(nl._param_table().items())), np.asarray(nl.y_range).tobytes(),
               P.N().tobytes(), t_range, nl.n_grid)
        if key not in _EXPR_CACHE:
            if len(_EXPR_CACHE) > 32:
                _EXPR_CACHE.clear()
            _EXPR_CACHE[key] = ExpressionModel(nl._texts(), P.p, nl._param_table(), nl.y_range, P.N(), t_range,
                                               n_grid=nl.n_grid)
        return _EXPR_CACHE[key]


def parse_config(data: object, source: str = "config") -> QppConfig:
    """Validate a mapping into a :class:`QppConfig`.

    Parameters
    ----------
    data : object
        The parsed YAML (a mapping).
    source : str, optional
        Name of the source, used in the error message.

    Returns
    -------
    QppConfig
        The validated config.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        One line naming the offending field.
    """
    return validate_model(QppConfig, data, source)


def load_config(path, overrides: list[str] | None = None) -> QppConfig:
    """Read and validate a YAML file; a bare name (``qpp_siso``) falls back to the packaged configs.

    Parameters
    ----------
    path : str or path-like
        YAML file, or the name of a packaged config.
    overrides : list of str, optional
        Dotted ``key=value`` edits (:mod:`acmm_qpp.configio`), applied before validation.

    Returns
    -------
    QppConfig
        The validated config.

    Raises
    ------
    acmm_qpp.errors.ConfigError
        A missing or unreadable file, bad YAML or an invalid field (one line).
    """
    data, p = read_yaml(path, PACKAGED_CONFIGS)
    cfg = parse_config(apply_overrides(data, overrides), source=str(p))
    return remember_origin(cfg, str(p), overrides)


def qpp_schema() -> dict:
    """Schema of a qpp config (:class:`qpp.io.config.QppConfig`).

    Returns
    -------
    dict
        JSON schema (draft 2020-12); dimensional fields accept a number or a quantity string in
        any unit of the field's dimension.
    """
    return header(QppConfig.model_json_schema(mode="validation", schema_generator=Generator),
                  "qpp config (CR-185644 Part III)")
