"""The sweepable parameters (:data:`PARAMETERS`, CR-185644 Table 1 inertias, eq 3.9 disturbance,
listed in :mod:`acmm.sweep.config`; a value given with a unit is converted to the parameter's
unit) and the schema of the ``sweep`` section of a sweep config (pydantic v2, ``extra="forbid"``):
grid or Monte Carlo distributions, the margin search, the sweep file.  Cross-field rules: one of
grid/Monte Carlo, known parameter names, ranges that keep the plant physical.
"""
from __future__ import annotations

import copy

import math
from dataclasses import dataclass
from typing import Annotated, Literal, Optional

from pydantic import BeforeValidator, Field, model_validator

from acmm.io.config import Config, Output
from acmm_qpp.config_model import StrictModel, closest, header
from acmm_qpp.units import to_canonical
from acmm.io.schema import AcmmGenerator, fix_alternatives
from acmm_qpp.results import RUN_NAME_MAX, RUN_NAME_PATTERN
from pydantic.json_schema import models_json_schema


@dataclass(frozen=True)
class Parameter:
    """A sweepable quantity: unit, neutral value, kind (relative | scale | absolute).

    Attributes
    ----------
    name : str
        Parameter name (a column of ``sweep.csv``).
    unit : str
        Its unit: ``"1"`` (dimensionless), ``"ft*lbf"`` or ``"deg"``.
    neutral : float
        The value that leaves the base config unchanged, in ``unit``.
    kind : str
        ``relative`` (x → x·(1 + p)), ``scale`` (x → p·x) or ``absolute`` (added).
    description : str
        What it changes.
    """

    name: str
    unit: str
    neutral: float
    kind: str
    description: str


AXES = ("roll", "pitch", "yaw")
_ELEMENTS = ("I11", "I22", "I33", "I12", "I13", "I23")

#: Every sweepable parameter, in canonical (column) order.
PARAMETERS: dict[str, Parameter] = {p.name: p for p in (
    *(Parameter(f"d{e}", "1", 0.0, "relative", f"relative change of {e}: {e} → {e}·(1 + d{e})") for e in _ELEMENTS),
    Parameter("inertia_scale", "1", 1.0, "scale",
              "uniform inertia scaling: I → s·I (applied after the element changes)"),
    *(Parameter(f"bias_{a}", "ft*lbf", 0.0, "absolute", f"torque added to the {a} bias (eq 3.9)") for a in AXES),
    Parameter("harmonic_scale", "1", 1.0, "scale", "factor on the harmonic amplitudes A and B (eq 3.9)"),
    *(Parameter(f"offset_{a}", "deg", 0.0, "absolute",
                f"initial {a} attitude minus the plant's TEA, added to simulation.initial_offset") for a in AXES))}

#: Shorthands expanding to several parameters (each drawn independently).
SHORTHANDS = {"inertia": [f"d{e}" for e in _ELEMENTS],
              "bias": [f"bias_{a}" for a in AXES],
              "offset": [f"offset_{a}" for a in AXES]}

#: Derived columns that may also be used as stability-map axes.
MAP_EXTRAS = ("tea_shift_roll", "tea_shift_pitch", "tea_shift_yaw")


def _in_unit(v, unit: Optional[str], where: str):
    """``v`` converted (pint) to ``unit`` when it carries a unit (``"2 N*m"``, ``"5 deg"``); a bare
    number (already in ``unit``), or any value when ``unit`` is None (an unknown parameter: the
    schema reports it), as it is.  A malformed unit or one of the wrong dimension is a ValueError
    naming ``where``, the config field (pydantic turns it into a field error)."""
    if unit is None or not isinstance(v, str):
        return v
    try:
        return to_canonical(v, unit)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


class Dist(StrictModel):
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
        if self.uniform is not None and not math.isfinite(self.uniform[1] - self.uniform[0]):
            raise ValueError("uniform: high − low overflows a float (numpy cannot draw from that range)")
        if self.normal is not None and self.normal[1] < 0:
            raise ValueError("normal: std must be ≥ 0")
        return self


class Margin(StrictModel):
    """Search for the range of a uniform inertia scaling s (I → s·I) the design tolerates.

    From s = 1, s is stepped geometrically towards ``high`` (and towards ``low``) in
    ``scan_points`` steps; the first failing step is refined by bisection (in log s) to a
    relative width ``rel_tol``.  The result is the largest (smallest) s such that every
    evaluated point between 1 and s is bounded.
    """

    low: float = Field(0.2, gt=0, lt=1, description="smallest scaling searched")
    high: float = Field(10.0, gt=1, le=1000, description="largest scaling searched")
    scan_points: int = Field(8, strict=True, ge=1, le=100, description="geometric scan steps each way before bisection")
    rel_tol: float = Field(0.01, ge=1e-6, lt=0.5, description="relative width of the final bracket")


class SweepSpec(StrictModel):
    """The ``sweep`` section."""

    base: Optional[str] = Field(None, description="base config: path or packaged name")
    bases: Optional[list[str]] = Field(None, min_length=1, description="several base configs (same cases each)")
    monte_carlo: Optional[dict[str, Dist]] = Field(None, description="parameter → distribution")
    grid: Optional[dict[str, list[float]]] = Field(None, description="parameter → values (Cartesian product)")
    n_runs: Optional[int] = Field(None, strict=True, ge=1, le=1_000_000, description="Monte Carlo draws per base")
    seed: int = Field(0, strict=True, ge=0, le=2**63 - 1, description="root seed (< 2⁶³: stored as an HDF5 int64); case i "
                                                      "uses SeedSequence([seed, i])")
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
    max_draws: int = Field(10000, strict=True, ge=1, description="resample: give up (verdict 'unphysical') after this many draws")
    settle_deg: float = Field(
        10.0, gt=0, le=180, description="a run that stays within the divergence bound but whose steady attitude "
                                        "error from the plant's true TEA exceeds this (deg) gets the verdict "
                                        "'not_settled' instead of 'bounded'")
    workers: Optional[int] = Field(None, strict=True, ge=1, le=1024, description="worker processes (default: CPU count)")
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
            data["grid"] = {k: [_in_unit(x, getattr(PARAMETERS.get(k), "unit", None), f"grid.{k}") for x in v]
                            if isinstance(v, list) else v for k, v in data["grid"].items()}
        if isinstance(data.get("monte_carlo"), dict):
            mc = {k: dict(d) if isinstance(d, dict) else d for k, d in data["monte_carlo"].items()}
            for k, dist in mc.items():
                for kind in ("uniform", "normal"):
                    if isinstance(dist, dict) and isinstance(dist.get(kind), (list, tuple)):
                        dist[kind] = [_in_unit(x, getattr(PARAMETERS.get(k), "unit", None), f"monte_carlo.{k}.{kind}")
                                      for x in dist[kind]]
            data["monte_carlo"] = mc
        if "settle_deg" in data:
            data["settle_deg"] = _in_unit(data["settle_deg"], "deg", "settle_deg")
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
            for name, values in self.grid.items():
                if name in SHORTHANDS:
                    raise ValueError(f"grid.{name}: shorthands are for monte_carlo; name the parameters "
                                     f"({', '.join(SHORTHANDS[name])})")
                _check_name(name)
                if not values:
                    raise ValueError(f"grid.{name}: give at least one value")
            if self.n_runs is not None and self.n_runs != self.n_cases():
                raise ValueError(f"n_runs ({self.n_runs}) must equal the grid size ({self.n_cases()}) or be omitted")
        names = swept_parameters(self)
        given = _expanded(self)
        twice = sorted({p for p in given if given.count(p) > 1})
        if twice:
            raise ValueError(f"parameter {', '.join(twice)} is given twice (directly and through a shorthand: "
                             f"{', '.join(k for k in SHORTHANDS if set(SHORTHANDS[k]) & set(twice))})")
        for name in names:
            if name == "inertia_scale" and any(v <= 0 for v in _support(self, name)):
                raise ValueError("inertia_scale must stay > 0")
            if name.startswith("offset_") and any(abs(v) >= 89 for v in _support(self, name)):
                raise ValueError(f"{name} must stay within ±89 deg")
        if self.map is not None:
            if self.map[0] == self.map[1]:
                raise ValueError(f"map: the two axes are both {self.map[0]!r}; give two different parameters")
            for m in self.map:
                if m not in names and m not in MAP_EXTRAS:
                    raise ValueError(f"map: {m!r} is neither a swept parameter ({', '.join(names)}) nor one of "
                                     f"{', '.join(MAP_EXTRAS)}")
        return self

    def base_names(self) -> list[str]:
        """The base configs named by ``base`` or ``bases``.

        Returns
        -------
        list of str
            Paths or packaged names; empty for an inline sweep section.
        """
        return list(self.bases) if self.bases is not None else ([self.base] if self.base is not None else [])

    def n_cases(self) -> int:
        """Cases per base.

        Returns
        -------
        int
            The grid size or ``n_runs``.
        """
        if self.grid is not None:
            return math.prod(len(v) for v in self.grid.values())
        return int(self.n_runs)


def _check_name(name: str) -> None:
    if name not in PARAMETERS and name not in SHORTHANDS:
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
    """Names of the swept parameters, shorthands expanded, in canonical order.

    Parameters
    ----------
    spec : SweepSpec
        The ``sweep`` section.

    Returns
    -------
    list of str
        Parameter names (:data:`PARAMETERS` order first).
    """
    out = _expanded(spec)
    return [p for p in PARAMETERS if p in out] + [p for p in out if p not in PARAMETERS]


def _expanded(spec: SweepSpec) -> list[str]:
    """The parameters the grid's and the Monte Carlo's keys name, in order, shorthands expanded."""
    return [p for k in [*(spec.grid or {}), *(spec.monte_carlo or {})] for p in SHORTHANDS.get(k, [k])]


class SweepFile(StrictModel):
    """A sweep config file: name, description, the ``sweep`` section and ``output``."""

    name: str = Field(pattern=RUN_NAME_PATTERN, max_length=RUN_NAME_MAX, description="sweep name; results in <root>/<name>/")
    description: str = Field("", description="free text")
    sweep: SweepSpec
    output: Output = Output()


def sweep_schema() -> dict:
    """Schema of a sweep config: a sweep file, or an acmm config with an inline ``sweep`` section.

    Returns
    -------
    dict
        JSON schema (draft 2020-12) with ``anyOf`` the two forms.
    """

    keys, top = models_json_schema([(SweepFile, "validation"), (Config, "validation"),
                                    (SweepSpec, "validation")], schema_generator=AcmmGenerator)
    defs = fix_alternatives(top)["$defs"]
    ref_file, ref_cfg, ref_spec = (keys[(model, "validation")]["$ref"] for model in (SweepFile, Config, SweepSpec))
    inline = copy.deepcopy(defs[ref_cfg.split("/")[-1]])
    inline["title"] = "Config with an inline sweep section"
    inline["properties"]["sweep"] = {
        "allOf": [{"$ref": ref_spec},
                  {"not": {"anyOf": [{"required": ["base"]}, {"required": ["bases"]}]}}],
        "description": "sweep over this very config (no base/bases)"}
    inline["required"] = sorted(set(inline.get("required", [])) | {"sweep"})
    defs["InlineSweepConfig"] = inline
    file_def = defs[ref_file.split("/")[-1]]
    # the file form needs a base: the loader reads a `sweep` without base/bases as inline
    file_def["properties"]["sweep"] = {"allOf": [file_def["properties"]["sweep"],
                                                 {"anyOf": [{"required": ["base"]}, {"required": ["bases"]}]}]}
    schema = {"anyOf": [{"$ref": ref_file}, {"$ref": "#/$defs/InlineSweepConfig"}], "$defs": defs}
    return header(schema, "acmm sweep config")
