"""Schema of a sweep config (pydantic v2, ``extra="forbid"``), read from YAML.

A sweep file names one or more *base* configs (ordinary acmm configs) and says how to vary
them::

    name: inertia30                # results go to <output.root>/<name>/sweep.h5
    description: "..."
    sweep:
      bases: [mb3, ac]             # paths (relative to this file, then the working directory)
                                   # or packaged config names; or `base: mb3`
      monte_carlo:                 # or `grid: {parameter: [values...]}`
        inertia: {percent: 30}     # each of I11..I23 × (1 + U(−0.30, +0.30))
      n_runs: 200                  # Monte Carlo draws per base
      seed: 185644
      design: fixed                # fixed nominal gain schedule | redesign per case
      tea_estimate: nominal        # controller's TEA estimate with a fixed design
      orbits: 10                   # per run (default: the base config's simulation.orbits)
      margin: {low: 0.1, high: 10} # bisection on a uniform inertia scaling, per base
    output: {root: runs, figures: true}

Alternatively the ``sweep`` section may sit inside an ordinary config (no ``base``/``bases``):
the rest of that file is then the single base config and the sweep takes its ``name``.

Parameters (see :data:`PARAMETERS`): relative inertia-element changes ``dI11 … dI23``
(shorthand ``inertia``), a uniform inertia scale ``inertia_scale``, additive bias torques
``bias_roll|pitch|yaw`` (ft·lbf, shorthand ``bias``), a factor on the harmonic amplitudes
``harmonic_scale`` and initial attitude offsets ``offset_roll|pitch|yaw`` (deg, shorthand
``offset``).  Distributions: ``{uniform: [low, high]}``, ``{normal: [mean, std]}`` or
``{percent: p}`` (relative and scale parameters only: neutral value ± p/100, uniform).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal, Optional

import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from acmm.config import Config, Output, load_config, parse_config, require_mapping, validate_model
from common.errors import ConfigError
from common.results import RUN_NAME_MAX, RUN_NAME_PATTERN


@dataclass(frozen=True)
class Parameter:
    """A sweepable quantity: unit, neutral value, kind (relative | scale | absolute)."""

    name: str
    unit: str
    neutral: float
    kind: str
    description: str


_AX = ("roll", "pitch", "yaw")
_ELEMENTS = ("I11", "I22", "I33", "I12", "I13", "I23")

#: Every sweepable parameter, in canonical (column) order.
PARAMETERS: dict[str, Parameter] = {}
for _e in _ELEMENTS:
    PARAMETERS[f"d{_e}"] = Parameter(f"d{_e}", "1", 0.0, "relative",
                                     f"relative change of {_e}: {_e} → {_e}·(1 + d{_e})")
PARAMETERS["inertia_scale"] = Parameter("inertia_scale", "1", 1.0, "scale",
                                        "uniform inertia scaling: I → s·I (applied after the element changes)")
for _a in _AX:
    PARAMETERS[f"bias_{_a}"] = Parameter(f"bias_{_a}", "ft*lbf", 0.0, "absolute",
                                         f"torque added to the {_a} bias (eq 3.9)")
PARAMETERS["harmonic_scale"] = Parameter("harmonic_scale", "1", 1.0, "scale",
                                         "factor on the harmonic amplitudes A and B (eq 3.9)")
for _a in _AX:
    PARAMETERS[f"offset_{_a}"] = Parameter(f"offset_{_a}", "deg", 0.0, "absolute",
                                           f"initial {_a} attitude minus the plant's TEA, added to "
                                           "simulation.initial_offset")

#: Shorthands expanding to several parameters (each drawn independently).
SHORTHANDS = {"inertia": [f"d{e}" for e in _ELEMENTS],
              "bias": [f"bias_{a}" for a in _AX],
              "offset": [f"offset_{a}" for a in _AX]}

#: Derived columns that may also be used as stability-map axes.
MAP_EXTRAS = ("tea_shift_roll", "tea_shift_pitch", "tea_shift_yaw")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Dist(_Model):
    """One distribution: exactly one of ``uniform``, ``normal`` or ``percent``."""

    uniform: Optional[tuple[float, float]] = Field(None, description="[low, high], parameter units")
    normal: Optional[tuple[float, float]] = Field(None, description="[mean, std], parameter units")
    percent: Optional[float] = Field(None, gt=0, lt=100,
                                     description="neutral ± percent/100, uniform (relative/scale parameters)")

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("uniform", "normal", "percent") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'uniform: [low, high]', 'normal: [mean, std]', 'percent: p'")
        if self.uniform is not None and not self.uniform[0] <= self.uniform[1]:
            raise ValueError("uniform: low must be ≤ high")
        if self.normal is not None and self.normal[1] < 0:
            raise ValueError("normal: std must be ≥ 0")
        return self


class Margin(_Model):
    """Search for the range of a uniform inertia scaling s (I → s·I) the design tolerates.

    From s = 1, s is stepped geometrically towards ``high`` (and towards ``low``) in
    ``scan_points`` steps; the first failing step is refined by bisection (in log s) to a
    relative width ``rel_tol``.  The result is the largest (smallest) s such that every
    evaluated point between 1 and s is bounded.
    """

    low: float = Field(0.2, gt=0, lt=1, description="smallest scaling searched")
    high: float = Field(10.0, gt=1, le=1000, description="largest scaling searched")
    scan_points: int = Field(8, ge=1, le=100, description="geometric scan steps each way before bisection")
    rel_tol: float = Field(0.01, ge=1e-6, lt=0.5, description="relative width of the final bracket")


def _param_unit_value(v, unit: str, where: str):
    from acmm.units import to_canonical, DIMENSIONS

    if not isinstance(v, str):
        return v
    kind = next((k for k, u in DIMENSIONS.items() if u == unit), None)
    try:
        return to_canonical(v, kind) if kind else to_canonical(v, "dimensionless")
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _param_value(name: str, v, where: str):
    """A grid or distribution value of parameter ``name``, converted to its unit."""
    p = PARAMETERS.get(name)
    return v if p is None else _param_unit_value(v, p.unit, where)


class SweepSpec(_Model):
    """The ``sweep`` section."""

    base: Optional[str] = Field(None, description="base config: path or packaged name")
    bases: Optional[list[str]] = Field(None, min_length=1, description="several base configs (same cases each)")
    monte_carlo: Optional[dict[str, Dist]] = Field(None, description="parameter → distribution")
    grid: Optional[dict[str, list[float]]] = Field(None, description="parameter → values (Cartesian product)")
    n_runs: Optional[int] = Field(None, ge=1, le=1_000_000, description="Monte Carlo draws per base")
    seed: int = Field(0, ge=0, description="root seed; case i uses SeedSequence([seed, i])")
    design: Literal["fixed", "redesign"] = Field(
        "fixed", description="fixed: the nominal design for every case; redesign: TEA, LQR and schedule per case")
    tea_estimate: Annotated[Literal["nominal", "true"], BeforeValidator(
        lambda v: {True: "true", False: "nominal"}.get(v, v) if isinstance(v, bool) else v)] = Field(
        "nominal", description="fixed design only: the controller's TEA estimate is the nominal design's TEA "
                               "(nominal) or the perturbed plant's own TEA (true: exact mass properties)")
    orbits: Optional[float] = Field(None, gt=0, le=10000, description="orbits per run (default: base config's)")
    unphysical: Literal["resample", "reject"] = Field(
        "resample", description="perturbed inertia not positive definite or violating the triangle inequality: "
                                "draw again (resample) or record the case as 'unphysical' (reject)")
    max_draws: int = Field(10000, ge=1, description="resample: give up (verdict 'unphysical') after this many draws")
    settle_deg: float = Field(
        10.0, gt=0, le=180, description="a run that stays within the divergence bound but whose steady attitude "
                                        "error from the plant's true TEA exceeds this (deg) gets the verdict "
                                        "'not_settled' instead of 'bounded'")
    workers: Optional[int] = Field(None, ge=1, le=1024, description="worker processes (default: CPU count)")
    margin: Optional[Margin] = Field(None, description="uniform-inertia-scaling margin search per base")
    map: Optional[list[str]] = Field(None, min_length=2, max_length=2,
                                     description="two parameters (or tea_shift_*) for the stability-map axes")

    @model_validator(mode="before")
    @classmethod
    def _units(cls, data):
        """Grid values and distribution parameters may carry units (``"2 N*m"``, ``"5 deg"``):
        converted (pint) to the parameter's unit, a wrong dimension is an error."""
        if not isinstance(data, dict):
            return data
        data = dict(data)
        if isinstance(data.get("grid"), dict):
            data["grid"] = {k: [_param_value(k, x, f"grid.{k}") for x in v] if isinstance(v, list) else v
                            for k, v in data["grid"].items()}
        if isinstance(data.get("monte_carlo"), dict):
            mc = {}
            for k, dist in data["monte_carlo"].items():
                if isinstance(dist, dict):
                    dist = dict(dist)
                    for kind in ("uniform", "normal"):
                        if isinstance(dist.get(kind), (list, tuple)):
                            dist[kind] = [_param_value(k, x, f"monte_carlo.{k}.{kind}") for x in dist[kind]]
                mc[k] = dist
            data["monte_carlo"] = mc
        if "settle_deg" in data:
            data["settle_deg"] = _param_unit_value(data["settle_deg"], "deg", "settle_deg")
        return data

    @model_validator(mode="after")
    def _consistent(self):
        if self.base is not None and self.bases is not None:
            raise ValueError("give either 'base' or 'bases', not both")
        if (self.monte_carlo is None) == (self.grid is None):
            raise ValueError("give exactly one of 'monte_carlo' or 'grid'")
        if self.monte_carlo is not None:
            if not self.monte_carlo:
                raise ValueError("monte_carlo: give at least one parameter")
            if self.n_runs is None:
                raise ValueError("monte_carlo needs n_runs")
            for name, dist in self.monte_carlo.items():
                _check_name(name)
                if dist.percent is not None:
                    for p in SHORTHANDS.get(name, [name]):
                        if PARAMETERS[p].kind == "absolute":
                            raise ValueError(f"monte_carlo.{name}: 'percent' applies only to relative or "
                                             f"scale parameters ({PARAMETERS[p].name} is in {PARAMETERS[p].unit})")
        if self.grid is not None:
            if not self.grid:
                raise ValueError("grid: give at least one parameter")
            size = 1
            for name, values in self.grid.items():
                if name in SHORTHANDS:
                    raise ValueError(f"grid.{name}: shorthands are for monte_carlo; name the parameters "
                                     f"({', '.join(SHORTHANDS[name])})")
                _check_name(name)
                if not values:
                    raise ValueError(f"grid.{name}: give at least one value")
                size *= len(values)
            if self.n_runs is not None and self.n_runs != size:
                raise ValueError(f"n_runs ({self.n_runs}) must equal the grid size ({size}) or be omitted")
        names = swept_parameters(self)
        if len(set(names)) != len(names):
            raise ValueError("a parameter is given twice (directly and through a shorthand?)")
        for name in names:
            if name == "inertia_scale" and any(v <= 0 for v in _support(self, name)):
                raise ValueError("inertia_scale must stay > 0")
            if name.startswith("offset_"):
                for v in _support(self, name):
                    if abs(v) >= 89:
                        raise ValueError(f"{name} must stay within ±89 deg")
        if self.map is not None:
            for m in self.map:
                if m not in names and m not in MAP_EXTRAS:
                    raise ValueError(f"map: {m!r} is neither a swept parameter ({', '.join(names)}) nor one of "
                                     f"{', '.join(MAP_EXTRAS)}")
        return self

    def base_names(self) -> list[str]:
        return list(self.bases) if self.bases is not None else ([self.base] if self.base is not None else [])

    def n_cases(self) -> int:
        """Cases per base."""
        if self.grid is not None:
            return math.prod(len(v) for v in self.grid.values())
        return int(self.n_runs)


def _check_name(name: str) -> None:
    if name not in PARAMETERS and name not in SHORTHANDS:
        from common.hints import closest

        known = list(SHORTHANDS) + list(PARAMETERS)
        best = closest(name, known)
        raise ValueError(f"unknown parameter {name!r}" + (f" (did you mean `{best}`?)" if best else "")
                         + f"; known: {', '.join(known)}")


def _support(spec: SweepSpec, name: str) -> list[float]:
    """Extreme values a parameter can take (for range checks)."""
    if spec.grid is not None:
        return list(spec.grid.get(name, []))
    for key, dist in (spec.monte_carlo or {}).items():
        if name in SHORTHANDS.get(key, [key]):
            p = PARAMETERS[name]
            if dist.uniform is not None:
                return list(dist.uniform)
            if dist.percent is not None:
                return [p.neutral - dist.percent / 100, p.neutral + dist.percent / 100]
            m, s = dist.normal
            return [m - 8 * s, m + 8 * s] if name != "inertia_scale" else [m]
    return []


def swept_parameters(spec: SweepSpec) -> list[str]:
    """Names of the swept parameters, shorthands expanded, in canonical order."""
    keys = list(spec.grid or {}) + list(spec.monte_carlo or {})
    out = []
    for k in keys:
        out.extend(SHORTHANDS.get(k, [k]))
    return [p for p in PARAMETERS if p in out] + [p for p in out if p not in PARAMETERS]


class SweepFile(_Model):
    """A sweep config file: name, description, the ``sweep`` section and ``output``."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX, description="sweep name; results in <root>/<name>/")
    description: str = Field("", description="free text")
    sweep: SweepSpec
    output: Output = Output()


@dataclass(frozen=True)
class Base:
    """A resolved base config."""

    label: str        # the config's name
    config: Config
    source: str       # where it was read from


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: the file's model plus its resolved base configs."""

    file: SweepFile
    bases: tuple[Base, ...]
    source: str

    @property
    def spec(self) -> SweepSpec:
        return self.file.sweep

    @property
    def name(self) -> str:
        return self.file.name

    def run_dir(self) -> Path:
        return Path(self.file.output.root) / self.file.name

    def to_yaml(self) -> str:
        """The resolved sweep config plus every resolved base config, as YAML."""
        d = {"sweep_file": self.file.model_dump(mode="json", exclude_none=True),
             "bases": {b.label: b.config.model_dump(mode="json") for b in self.bases}}
        return yaml.safe_dump(d, sort_keys=False)

    def results_key(self) -> str:
        """Hash of everything that determines the case results (not workers, figures, description)."""
        import json

        from common.results import config_hash

        f = self.file.model_dump(mode="json", exclude_none=True)
        f["sweep"].pop("workers", None)
        f.pop("description", None)
        f.pop("output", None)
        bases = {}
        for b in self.bases:
            c = b.config.model_dump(mode="json")
            c.pop("output", None)
            c.pop("description", None)
            bases[b.label] = c
        return config_hash(json.dumps({"file": f, "bases": bases}, sort_keys=True))


def _resolve_base(ref: str, directory: Path) -> Base:
    p = Path(ref)
    local = p if p.is_absolute() else directory / p
    try:
        is_file = local.is_file()
    except (OSError, ValueError) as exc:       # name too long, NUL byte
        raise ConfigError(f"sweep.base: cannot read {ref[:200]!r}: {getattr(exc, 'strerror', None) or exc}") from None
    cfg = load_config(local if is_file else ref)
    return Base(cfg.name, cfg, str(local if is_file else ref))


def parse_sweep(data: object, source: str = "sweep config", directory: Path | None = None) -> Sweep:
    """Validate a mapping (parsed YAML) into a :class:`Sweep`; base paths resolve against ``directory``.
    Raises :class:`ConfigError` (one line naming the offending field)."""
    require_mapping(data, source)
    if "sweep" not in data:
        raise ConfigError(f"{source}: sweep: missing (a sweep config needs a 'sweep' section)")
    directory = Path(".") if directory is None else directory
    raw = data["sweep"]
    inline = not (isinstance(raw, dict) and ("base" in raw or "bases" in raw))
    if inline:
        rest = {k: v for k, v in data.items() if k != "sweep"}
        base_cfg = parse_config(rest, source=source)
        file_data = {"name": base_cfg.name, "description": base_cfg.description, "sweep": raw,
                     "output": base_cfg.output.model_dump(mode="json")}
    else:
        file_data = data
    sf = validate_model(SweepFile, file_data, source)
    if inline:
        bases = (Base(base_cfg.name, base_cfg, source),)
    else:
        bases = tuple(_resolve_base(r, directory) for r in sf.sweep.base_names())
    labels = [b.label for b in bases]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{source}: sweep.bases: two base configs share the name "
                          f"{next(x for x in labels if labels.count(x) > 1)!r}")
    sweep = Sweep(sf, bases, source)
    from acmm.sweep_limits import check_sweep_work

    check_sweep_work(sweep, source)
    return sweep


def load_sweep(path: str | Path, overrides: list[str] | None = None) -> Sweep:
    """Read and validate a sweep config file (a bare name is looked up among the packaged configs).
    ``overrides`` (dotted ``key=value``, :mod:`acmm.overrides`) apply before validation, e.g.
    ``sweep.n_runs=20``."""
    from acmm.config import read_yaml
    from common.overrides import apply_overrides, remember_origin

    data, p = read_yaml(path)
    sw = parse_sweep(apply_overrides(data, overrides), source=str(p), directory=p.parent)
    return remember_origin(sw, str(p), overrides)
