"""Validated run configuration (pydantic v2), read from YAML.

Every field documents its unit.  Numbers may also be written as ``"<number> <unit>"``
strings (e.g. ``"31.5e6 kg*m^2"``, ``"2 N*m"``); they are converted to the report's units
(slug·ft², ft·lbf, ft·lbf·s, deg, rad/s, s) on load.  Unknown keys, non-finite numbers,
impossible inertias and inconsistent sections are rejected with one message naming the
field (:class:`acmm_qpp.errors.ConfigError`).  The sections follow the report: inertia (Table 1,
eq 3.2), disturbance (eq 3.9), sector LQR design (ch. 5.2), gain schedule (ch. 5.3) and the
stair-case simulation (ch. 6).

A quantity (:func:`acmm_qpp.config_model.quantity`) must lie within a physically plausible
range (:data:`_RANGE`).  An inertia may also be written as a symmetric 3×3 list; it must be
positive definite and obey the triangle inequality of principal moments.  The disturbance gives
either its bias or the attitude whose equilibrium bias it is (``bias_from_tea``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal, Optional

import numpy as np
from pydantic import BeforeValidator, Field, field_validator, model_validator

from acmm_qpp.config_model import RunConfig, StrictModel, quantity
from acmm_qpp.errors import ConfigError
from acmm_qpp.units import to_canonical
from acmm.model.inertia import MAX_INERTIA
from acmm.model.unit_systems import pretty
from acmm_qpp.results import RUN_NAME_MAX, RUN_NAME_PATTERN, ROOT_PATTERN
from acmm import DEFAULT_CONFIG, LIMITS, PACKAGED_CONFIGS
from acmm_qpp.configio import read_yaml, validate_model
from acmm_qpp.configio import apply_overrides, looks_like_override, remember_origin
from acmm_qpp.limits import how_to_raise, limit


# ---------------------------------------------------------------------------------------------
# field types: quantities in the report's units (Table 1, eq 3.9)
# ---------------------------------------------------------------------------------------------
#: |value| bound per dimension, canonical units (issue 13: no overflow accepted): beyond it a value
#: is refused as a typo or an overflow hazard (bias torques are a few ft·lbf, CMG momentum ~1e4
#: ft·lbf·s; the inertia's reasoning is :data:`acmm.model.inertia.MAX_INERTIA`'s).
_RANGE = {"inertia": MAX_INERTIA, "torque": 1e9, "momentum": 1e12, "angle": 3600.0, "rate": 1.0, "time": 1e9}
#: The report's unit of each dimension kind of the config (pint syntax): a bare number is in it.
UNITS = {"inertia": "slug*ft^2", "torque": "ft*lbf", "momentum": "ft*lbf*s", "angle": "deg", "rate": "rad/s",
         "time": "s", "weight_torque": "1/(ft*lbf)^2"}


#: Smallest accepted principal moment of inertia, slug·ft² (a 1 cm, 1 g body is ~1e-8; below
#: this the linear model's scaling underflows and "uncontrollable" would be reported instead).
MIN_PRINCIPAL_MOMENT = 1e-6


def _plausible_value(x: float, dimension: str) -> float:
    """``x`` (in the unit of :data:`UNITS`) unchanged when its magnitude is physically
    plausible for ``dimension`` (``inertia``, ``torque``…), else a ValueError naming both."""
    bound = _RANGE.get(dimension)
    if bound is not None and abs(x) > bound:
        unit = pretty(UNITS[dimension])
        raise ValueError(f"{x:.4g} {unit} is outside the physically plausible range |value| ≤ {bound:g} {unit}")
    return x


def _q(dimension: str):
    """The quantity validator of the acmm config: in :data:`UNITS`, finite and within :data:`_RANGE`."""
    return quantity(UNITS[dimension], lambda x: _plausible_value(x, dimension))


def _vec3(dimension: str):
    def conv(v):
        if isinstance(v, (str, int, float)) or not hasattr(v, "__len__"):
            raise ValueError("must be a list of three values [roll, pitch, yaw]")
        if len(v) != 3:
            raise ValueError(f"must have three values [roll, pitch, yaw], got {len(v)}")
        return [_q(dimension).func(x) for x in v]
    return BeforeValidator(conv)


InertiaValue = Annotated[float, _q("inertia")]
Torque = Annotated[float, _q("torque")]
Momentum = Annotated[float, _q("momentum")]
Angle = Annotated[float, _q("angle")]
Rate = Annotated[float, _q("rate")]
Time = Annotated[float, _q("time")]
TorqueVec = Annotated[list[float], _vec3("torque")]
AngleVec = Annotated[list[float], _vec3("angle")]
WeightTorque = Annotated[float, _q("weight_torque")]


class SectionModel(StrictModel):
    """Strict base of every config section: unknown keys, NaN, infinity and booleans given as
    numbers refused (:class:`acmm_qpp.config_model.StrictModel`)."""


# ---------------------------------------------------------------------------------------------
# the station: inertia (Table 1, eq 3.2), disturbance (eq 3.9), CMGs
# ---------------------------------------------------------------------------------------------
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
                _plausible_value(float(x), "inertia")
            if not np.allclose(m, m.T, rtol=1e-9, atol=0.0):
                raise ValueError("inertia matrix is not symmetric (I_ij must equal I_ji)")
            return {"I11": m[0, 0], "I22": m[1, 1], "I33": m[2, 2],
                    "I12": m[0, 1], "I13": m[0, 2], "I23": m[1, 2]}
        return data

    @model_validator(mode="after")
    def _physical(self):
        eig = np.linalg.eigvalsh(self.matrix())
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


class Sector(SectionModel):
    """Closed-loop pole region of ch. 5.2: Re λ ≤ −sigma·n and |Im λ| ≤ tan(half_angle)·|Re λ|."""

    sigma: float = Field(0.5, gt=0, le=1000, description="minimum decay rate in units of the orbital rate n")
    half_angle_deg: Angle = Field(45.0, gt=0, lt=90, description="sector half-angle about the negative real axis, deg")


class Q0Groups(SectionModel):
    """Diagonal initial state weight on the *scaled* states (dimensionless), one value per state
    group (x̃ = D⁻¹x, :func:`acmm.model.linearize.state_scales`); added to ``Q0``·I."""

    rates: float = Field(0.0, ge=0, description="weight on the scaled body-rate errors δω1, θ̇2, δω3")
    attitudes: float = Field(0.0, ge=0, description="weight on the scaled attitude errors δθ1..3")
    momentum: float = Field(0.0, ge=0, description="weight on the scaled CMG momentum h1..3")
    momentum_integral: float = Field(0.0, ge=0, description="weight on the scaled momentum integrals ∫h1..3")
    drf: float = Field(0.0, ge=0, description="weight on the 12 scaled disturbance-rejection-filter states")

    def diagonal(self) -> np.ndarray:
        """The 24 diagonal entries in the state order of eq 4.47.

        Returns
        -------
        (24,) ndarray
            The weights on the scaled states, dimensionless.
        """
        return np.array([self.rates] * 3 + [self.attitudes] * 3 + [self.momentum] * 3
                        + [self.momentum_integral] * 3 + [self.drf] * 12)


class RegionalLMI(SectionModel):
    """The regional pole placement by LMIs (``pole_method: lmi``, :mod:`acmm.design.regional_lmi`)."""

    dilation: float = Field(0.35, gt=0, le=100, description="β of the dilated H2 energy bound, units of 1/n")
    solver: Literal["conelp", "dsdp", "clarabel"] = Field(
        "conelp", description="SDP solver tried first: cvxopt's conelp with the program's structured KKT solver "
                              "or DSDP 5 (both cvxopt, GPL-3), or Clarabel through cvxpy (Apache-2.0, the "
                              "reference); the others follow, in that order, when an answer fails the checks")
    regularization: float = Field(1e-5, ge=0, le=1, description="ε of ε(tr X + tr X2) in the objective, in the "
                                                               "reference loop's coordinates: makes the optimum attained")
    tol: float = Field(1e-7, ge=1e-10, le=1e-3, description="the solvers' gap tolerance of the final pass")
    backoff: float = Field(0.002, ge=0, le=1, description="the regions are imposed with margin min_margin + backoff, "
                                                          "units of n (so the certificate proves min_margin)")
    disk_radius: float = Field(0.0, ge=0, le=1e4, description="> 0: also |λ| ≤ disk_radius·n (fastest pole); 0: none")
    n_random: int = Field(100, strict=True, ge=0, le=100000, description="random gain perturbations of the "
                                                                          "robustness re-check")
    seed: int = Field(0, strict=True, ge=0, description="seed of those perturbations")


class Robust(SectionModel):
    """A gain designed for a family of inertias and certified per plant (:mod:`acmm.design.robust`)."""

    inertia_percent: float = Field(0.0, ge=0, lt=100, description="half-width of the element draws I∘(1+δ), "
                                   "δ ~ U(±p %), and of the uniform scalings (1 ± p %)·I; 0: off")
    samples: int = Field(20, strict=True, ge=1, le=500, description="physical element draws with an equilibrium "
                         "connected to the design TEA in the family (besides the nominal plant and the scalings)")
    seed: int = Field(1, strict=True, ge=0, description="seed of the draws (not the sweep's: the gain is judged on "
                      "draws it never saw)")


class Design(SectionModel):
    """Linear design model (eq 4.46) and the sector LQR (ch. 5.2)."""

    model: Literal["coupled", "no_cross_inertia", "small_angle"] = Field(
        "coupled", description="design model: fully coupled (eq 4.46), I12=I13=I23=0, or theta*=0 (LVLH)")
    drf_mode: Literal["attitude_hold", "momentum_hold"] = Field(
        "attitude_hold", description="DRF inputs: (h1, θ2, θ3) or (h1, h2, θ3), filters at n and 2n")
    sector: Sector = Sector()
    R: WeightTorque = Field(1e-4, ge=1e-20, le=1e12, description="control weight R = r·I, 1/(ft·lbf)²")
    Q0: float = Field(0.0, ge=0, le=1e12, description="state weight Q0 = q·I on the scaled states (dimensionless)")
    riccati_method: Literal["sign", "scipy", "slycot"] = Field("scipy", description="CARE solver")
    pole_method: Literal["shift", "uniform", "lmi"] = Field(
        "shift", description="sector enforcement: optimal pole shifting of the stray poles, a uniform shift, or "
                             "regional pole placement by LMIs with an H2 energy bound (design.lmi)")
    lmi: RegionalLMI = RegionalLMI()
    robust: Robust = Robust()
    residual_tol: float = Field(1e-12, gt=0, lt=1, description="largest accepted Riccati backward error after "
                                                                 "refinement (acmm.design.riccati.care_backward_error)")
    Q0_groups: Optional[Q0Groups] = Field(
        None, description="per-group diagonal weights on the scaled states, added to Q0·I (dimensionless)")
    min_margin: float = Field(0.01, ge=0, lt=10, description="required sector margin of every design pole, units of n")
    line_spacing: float = Field(0.0, ge=0, lt=10, description="pole shifting: 0 mirrors a group of stray poles about one "
                                                          "line; > 0 one pole at a time about distinct lines, units of n")


class DesignPoint(SectionModel):
    """A named station configuration used as a design point of the gain schedule."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX, description="name of the design point")
    inertia: Inertia
    disturbance: Disturbance = Disturbance()


class Schedule(SectionModel):
    """Design points of the gain schedule (ch. 5.3)."""

    # a string is resolved to the mapping by Config's before-validator (resolve_references), so
    # the validated type stays DesignPoint; a JSON schema should allow a string here too
    to: Optional[DesignPoint] = Field(
        None, description="end configuration of the blend I(s) = (1−s)·I_start + s·I_to (bias blended alike): "
                          "a mapping, or a config file (path relative to the referring file) or packaged name "
                          "whose name, inertia and disturbance are used")
    n_points: int = Field(12, strict=True, ge=3, le=200, description="number of blend points including both ends")
    spacing: Literal["tea", "blend"] = Field(
        "tea", description="blend points evenly spaced in pitch TEA (tea) or in the blend parameter s (blend)")
    form: Literal["polynomial", "table"] = Field(
        "polynomial", description="gain schedule: least-squares polynomial in θ2* (report ch. 5.3) or "
                                  "table look-up, linear in θ2* between design points (ch. 7 alternative)")
    points: list[DesignPoint] = Field([], description="additional named design points")
    order: int = Field(2, strict=True, ge=1, le=4, description="polynomial order of K_ij(θ2*) (the report uses 2)")
    fit: Optional[Literal["least_squares", "shifted_lqr"]] = Field(
        None, description="how a polynomial schedule is fitted (null: the form's default, resolved at design time "
                          "and stored as fit_method in design.h5).  shifted_lqr (the default of a polynomial with "
                          "schedule.to): the report's quadratic converged, the coefficients that minimize the "
                          "path's summed LQR cost shifted by 0.3n and rotated into a 70° cone, by Newton's method "
                          "to a step tolerance (acmm.design.schedule_shifted_lqr.refit_shifted_lqr); "
                          "least_squares: least squares on the design points' gains, as the report fits them "
                          "(the default without schedule.to, which the refit needs for its path; a table "
                          "interpolates the gains themselves)")
    n_check: int = Field(201, strict=True, ge=2, le=2001, description="TEAs evenly spaced along the blend path at which "
                                                         "the scheduled gain is checked on the local model")
    refine_points: int = Field(
        0, strict=True, ge=0, le=200,
        description="table schedule: at most this many gain nodes added by bisecting, in the blend parameter s, "
                    "each interval between nodes that holds a path check TEA whose sector margin is below "
                    "refine_margin; the added nodes are schedule gains, not stair-case levels (0: none; a "
                    "polynomial has no nodes: it ignores this and refine_margin)")
    refine_margin: float = Field(
        0.0, ge=0, le=1, description="sector margin, units of n, that refine_points asks of every path check TEA")

    @property
    def fit_method(self) -> str:
        """The fit ``fit`` names, or the form's default: a polynomial toward ``to`` converged on the
        path (``"shifted_lqr"``), least squares otherwise (a table interpolates the gains)."""
        if self.fit is not None:
            return self.fit
        return "shifted_lqr" if self.form == "polynomial" and self.to is not None else "least_squares"

    @model_validator(mode="after")
    def _fit_of_the_form(self):
        if self.form == "table" and self.fit == "shifted_lqr":
            raise ValueError(f"fit: {self.fit} refines a polynomial schedule; form: table interpolates the "
                             "design points' gains themselves (give one or the other)")
        if self.fit == "shifted_lqr" and self.to is None:
            raise ValueError("fit: shifted_lqr refits the polynomial along the blend path toward schedule.to, "
                             "which is not given")
        if self.refine_points and self.form == "table" and self.to is None:
            raise ValueError("refine_points bisects the blend toward schedule.to, which is not given")
        return self


class Simulation(SectionModel):
    """Nonlinear closed-loop simulation (ch. 6)."""

    orbits: float = Field(5.0, gt=0, le=10000, description="simulated time, orbits (2π/n s each)")
    levels: Optional[list[float]] = Field(
        None, description="orbit at which each stair-case level (a design point of the blend or "
                    "schedule.points, not a node schedule.refine_points adds) starts (default: equal dwell)")
    initial_offset: AngleVec = Field([0.0, 0.0, 0.0], description="initial attitude minus TEA, deg")
    sample_interval: Time = Field(60.0, gt=0, description="output sample interval, s")
    rtol: float = Field(1e-8, ge=1e-14, lt=1, description="integrator relative tolerance (≥ 1e-14: ~100 ulp)")
    atol_scale: float = Field(1e-8, ge=1e-20, lt=1, description="absolute tolerance relative to state scales")
    divergence_deg: Angle = Field(60.0, gt=0, description="stop as diverged when an angle error exceeds this, deg")
    max_saturation_orbits: float = Field(
        1.0, gt=0, description="stop as diverged when a CMG axis stays saturated this long, orbits")


class Output(SectionModel):
    """Where results go."""

    root: str = Field("runs", pattern=ROOT_PATTERN, description="results root; files go to <root>/<name>/")
    figures: bool = Field(True, description="write matplotlib figures next to the HDF5 files")
    units: Literal["imperial", "SI"] = Field(
        "imperial", description="unit system of the HDF5 values and units attributes, prints, CSV and figures: "
                                "imperial (the report's slug·ft², ft·lbf, ft·lbf·s) or SI (kg·m², N·m, N·m·s); "
                                "angles are stored in rad in both (the name in any case: si, Imperial)")

    @field_validator("units", mode="before")
    @classmethod
    def _unit_system_in_any_case(cls, v):
        """``si``, ``Si``, ``IMPERIAL``: the unit system's name, whatever its case."""
        return {"si": "SI", "imperial": "imperial"}.get(v.strip().lower(), v) if isinstance(v, str) else v


class Config(SectionModel, RunConfig):
    """A complete acmm run configuration."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX,
                      description="run name (letters, digits, _ . -; not starting with a dot); results go to runs/<name>/")
    description: str = Field("", description="free text describing the run")
    inertia: Inertia
    orbit_rate: Rate = Field(0.0011, description="circular orbit rate n, rad/s")
    disturbance: Disturbance = Disturbance()
    actuators: Actuators = Actuators()
    design: Design = Design()
    schedule: Optional[Schedule] = None
    simulation: Simulation = Simulation()
    output: Output = Output()

    @model_validator(mode="before")
    @classmethod
    def _references(cls, data):
        """``schedule.to`` naming a file (relative to the working directory here; to the
        referring file through :func:`load_config`) or a packaged config."""
        try:
            return resolve_references(data, ".")
        except ConfigError as exc:
            raise ValueError(str(exc)) from None

    @field_validator("orbit_rate")
    @classmethod
    def _n_positive(cls, v):
        if v <= 0:
            raise ValueError("must be > 0 rad/s")
        if v > 0.01:
            raise ValueError("must be ≤ 0.01 rad/s (below low-Earth-orbit rates ~0.0011 rad/s)")
        return v

    @model_validator(mode="after")
    def _simulation_consistent(self):
        sim = self.simulation
        lv = sim.levels
        if lv is not None:
            if any(b <= a for a, b in zip(lv, lv[1:])) or (lv and lv[0] != 0):
                raise ValueError("simulation.levels must start at 0 and increase")
            if lv and lv[-1] >= sim.orbits:
                raise ValueError("simulation.levels must all start before simulation.orbits")
            if len(lv) != self.n_design_points():
                raise ValueError(f"simulation.levels has {len(lv)} entries but the design has "
                                 f"{self.n_design_points()} point(s), one level each")

        if self.n_design_points() > limit("DESIGN_POINTS", LIMITS):
            raise ValueError(f"schedule: {self.n_design_points()} design points (one sector LQR each); use fewer "
                             f"schedule.n_points or schedule.points ({how_to_raise('DESIGN_POINTS', LIMITS)})")
        samples = self.output_samples()
        if samples > limit("SIM_SAMPLES", LIMITS):
            raise ValueError(f"simulation.sample_interval: {sim.sample_interval:g} s gives {samples:.3g} output "
                             f"samples over {sim.orbits:g} orbits; raise sample_interval or lower orbits "
                             f"({how_to_raise('SIM_SAMPLES', LIMITS)})")
        return self

    def output_samples(self, orbits: float | None = None) -> float:
        """Output samples of one simulation of ``orbits`` (default ``simulation.orbits``) at
        ``simulation.sample_interval``: what the ``SIM_SAMPLES`` limit bounds.

        Parameters
        ----------
        orbits : float, optional
            Orbits simulated (a sweep's own ``sweep.orbits``), dimensionless.

        Returns
        -------
        float
            Number of samples, dimensionless.
        """
        sim = self.simulation
        return (sim.orbits if orbits is None else orbits) * 2 * math.pi / self.orbit_rate / sim.sample_interval

    def n_design_points(self) -> int:
        """Number of design points (= stair-case levels): the blend points plus the named ones.

        Returns
        -------
        int
            The number of design points.
        """
        sch = self.schedule
        if sch is None:
            return 1
        return (sch.n_points if sch.to is not None else 1) + len(sch.points)


def parse_config(data: object, source: str = "config") -> Config:
    """Validate a mapping (e.g. parsed YAML) into a :class:`Config` (one-line ConfigError).

    Parameters
    ----------
    data : object
        The parsed YAML.
    source : str
        Where it was read from, for error messages.

    Returns
    -------
    Config
        The validated config.
    """
    return validate_model(Config, data, source)


def load_config(path: str | Path | None = None, overrides: list[str] | None = None) -> Config:
    """Read and validate a YAML config file (``None``: the packaged default stair-case).

    Parameters
    ----------
    path : path-like, optional
        A YAML file or a packaged config name; None: the packaged stair-case.
    overrides : list of str, optional
        ``["simulation.orbits=10", ...]`` (see :mod:`acmm_qpp.configio`), applied to the raw
        mapping before validation.

    Returns
    -------
    Config
        The validated config.
    """
    data, p = read_yaml(DEFAULT_CONFIG if path is None else path, PACKAGED_CONFIGS)
    data = resolve_references(apply_overrides(data, overrides), p.parent, str(p))
    cfg = parse_config(data, source=str(p))
    return remember_origin(cfg, str(p), overrides)


def split_overrides(config, overrides) -> tuple[object, list[str]]:
    """Separate a positional CONFIG that is really an override (``acmm simulate a.b=1``, using the
    packaged default) from the override list: returns (config or None, overrides).

    Parameters
    ----------
    config : str or path-like or None
        The positional CONFIG argument.
    overrides : list of str or None
        The KEY=VALUE arguments.

    Returns
    -------
    tuple
        (config, or None when it was an override and no such file exists; list of overrides).
    """
    overrides = list(overrides or [])
    if config is not None and looks_like_override(str(config)) and not Path(str(config)).exists():
        return None, [str(config)] + overrides
    return config, overrides


def resolve_references(data: object, base_dir: str | Path = ".", source: str = "config",
                       _depth: int = 0) -> object:
    """Replace ``schedule.to: <file or packaged name>`` by that config's end point.

    The string is a YAML path relative to ``base_dir`` (the referring file's folder), else
    the name of a packaged config.  The referred config is validated in full; its ``name``,
    ``inertia`` and ``disturbance`` become the mapping ``schedule.to`` of eq 5.3's blend (its
    own ``schedule`` and other sections are not used).

    Parameters
    ----------
    data : object
        The parsed YAML of the referring config.
    base_dir : path-like
        The referring file's folder.
    source : str
        Where ``data`` was read from, for error messages.
    _depth : int
        Nesting depth of references (internal; at most 8).

    Returns
    -------
    object
        ``data`` with ``schedule.to`` replaced by a mapping (unchanged when it is none).

    Raises
    ------
    ConfigError
        The referred config is missing or invalid, or references nest too deep.
    """
    if not isinstance(data, dict) or not isinstance(data.get("schedule"), dict):
        return data
    ref = data["schedule"].get("to")
    if not isinstance(ref, (str, Path)):
        return data
    p = Path(base_dir) / ref
    try:
        sub, sub_path = read_yaml(p if p.is_file() else ref, PACKAGED_CONFIGS)
    except ConfigError as exc:
        raise ConfigError(f"{source}: schedule.to: {exc}") from None
    if _depth >= 8:
        raise ConfigError(f"{source}: schedule.to: references nest deeper than 8 files (a cycle?)")
    sub = resolve_references(sub, sub_path.parent, str(sub_path), _depth + 1)
    other = parse_config(sub, source=str(sub_path))
    end = {"name": other.name, "inertia": sub["inertia"], "disturbance": sub.get("disturbance", {})}
    return {**data, "schedule": {**data["schedule"], "to": end}}
