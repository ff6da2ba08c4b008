"""Validated ``qpp`` configuration (pydantic v2), read from YAML: the Lure plant and
servo-compensator (eqs 10.1–10.3), the H∞ design settings (ch. 11), the β thresholds of the
design procedure (section 12.1) and the simulation of ch. 13/14.

Units: time s, frequency rad/s, the exponential weighting ``a`` 1/s; plant matrices and signals
are in the user's units (the report's examples: m, rad, kg).  Unknown keys are rejected; a
validation error becomes one :class:`acmm_qpp.errors.ConfigError` line naming the field.
"""
from __future__ import annotations

from pathlib import Path
from typing import Literal, Optional, Union

import numpy as np
import yaml
from pydantic import Field, field_validator, model_validator

from acmm_qpp.errors import ConfigError
from acmm_qpp.results import RUN_NAME_MAX, RUN_NAME_PATTERN, ROOT_PATTERN
from qpp.io.config_checks import check_periods, check_sample_count, check_sector, check_stated_sector
from qpp.io.config_fields import Matrix, PerSecond, Seconds, finite_matrix, SectionModel
from qpp.io.config_simulation import Simulation
from qpp.io.config_nonlin import (ExpressionNonlinearity, LibraryForm, Nonlinearity, PolarArmNonlinearity, SinusoidalNonlinearity)
from acmm_qpp.configio import read_yaml, validate_model
from acmm_qpp.overrides import apply_overrides, remember_origin
from qpp import LIMITS, PACKAGED_CONFIGS
from acmm_qpp.limits import how_to_raise, limit
from qpp.model.lure import LurePlant
from qpp.model.nonlin import ExpressionModel


class Plant(SectionModel):
    """Lure plant x' = A x + B u + G d + B f1(·), y = C x (eqs 10.1, 13.1, 14.2) and servo-compensator."""

    A: Matrix = Field(description="plant state matrix (n×n), 1/s")
    B: Matrix = Field(description="control input matrix (n×m)")
    C: Matrix = Field(description="output matrix (p×n)")
    G: Matrix = Field(description="disturbance input matrix (n×r), B = G N (assumption iii)")
    Ac: Matrix = Field(description="servo-compensator matrix (q×q), eq 10.2: internal model of r_o")
    Bc: Matrix = Field(description="servo-compensator input matrix (q×p), driven by e = r − y")
    Cc: Matrix = Field(description="servo output matrix (·×q): the H∞ weight W_s e = C_c x_c (13.5)")
    x0: Optional[list[float]] = Field(None, description="initial plant state (n), default 0; observer starts equal")
    xc0: Union[Literal["zero", "equilibrium"], list[float]] = Field(
        "zero", description="initial servo state: 0, 'equilibrium' (K_c x_c = −K_1 x0, least squares) or a list")

    @field_validator("A", "B", "C", "G", "Ac", "Bc", "Cc")
    @classmethod
    def _mats(cls, v):
        return finite_matrix(v)


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

    K1: Optional[Matrix] = Field(None, description="printed K1 (m×n)")
    Kc: Optional[Matrix] = Field(None, description="printed Kc (m×q)")
    H: Optional[Matrix] = Field(None, description="printed observer gain H (n×p), report's sign")
    beta1: Optional[float] = Field(None, description="printed β1")
    beta3: Optional[float] = Field(None, description="printed β3")
    beta4: Optional[float] = Field(None, description="printed β4")
    m: Optional[float] = Field(None, description="printed threshold m")

    @field_validator("K1", "Kc", "H")
    @classmethod
    def _mats(cls, v):
        return v if v is None else finite_matrix(v)


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


class QppConfig(SectionModel):
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
            check_sector("nonlinearity.sector", nl.sector)
            try:
                model = self.expression_model()
                check_sample_count(model)
                info = model.sector_info                 # parse, check singular / sector-bounded
            except ConfigError as exc:
                raise ValueError(str(exc)) from None
            for field, stated in (("nonlinearity.sector", nl.sector), ("design.sector", self.design.sector)):
                if stated is not None:
                    check_stated_sector(field, stated, info.sector)
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
        check_sector("design.sector", self.design.sector)
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
            check_periods("nonlinearity.omega", nl.omega, self.simulation.t_final)
        for sig_name, sig in [("simulation.r_o", self.simulation.r_o)] + [
                (f"simulation.scenarios.{s.name}.delta_r", s.delta_r) for s in self.simulation.scenarios]:
            for chan in sig or []:
                for term in chan:
                    if term.kind == "sin" and term.omega > 0:
                        check_periods(f"{sig_name} omega", term.omega, self.simulation.t_final)

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
        key = (tuple(nl.texts()), tuple(sorted(nl.param_table().items())), np.asarray(nl.y_range).tobytes(),
               P.N().tobytes(), t_range, nl.n_grid)
        if key not in _EXPR_CACHE:
            if len(_EXPR_CACHE) > 32:
                _EXPR_CACHE.clear()
            _EXPR_CACHE[key] = ExpressionModel(nl.texts(), P.p, nl.param_table(), nl.y_range, P.N(), t_range,
                                               n_grid=nl.n_grid)
        return _EXPR_CACHE[key]

    def run_dir(self) -> Path:
        """The results directory of this run.

        Returns
        -------
        pathlib.Path
            ``<output.root>/<name>``.
        """
        return Path(self.output.root) / self.name

    def to_yaml(self) -> str:
        """The resolved config as YAML text (what is embedded in every results file).

        Returns
        -------
        str
            YAML document, keys in schema order.
        """
        return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)


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
        Dotted ``key=value`` edits (:mod:`acmm_qpp.overrides`), applied before validation.

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
