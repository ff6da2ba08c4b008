"""Schema of a sweep config (pydantic v2, ``extra="forbid"``), read from YAML.

A sweep file names one or more *base* configs (ordinary acmm configs: paths relative to the file,
then the working directory, or packaged names) and says how to vary them (``monte_carlo`` with
``n_runs`` and ``seed``, or ``grid``; ``design``, ``tea_estimate``, ``orbits``, ``margin``):
docs/howto/sweeps.md shows a full file.  Alternatively the ``sweep`` section may sit inside an
ordinary config (no ``base``/``bases``): the rest of that file is then the single base config
and the sweep takes its ``name``.

Parameters (see :data:`acmm.sweep.spec.PARAMETERS`): relative inertia-element changes
``dI11 … dI23`` (shorthand ``inertia``), a uniform inertia scale ``inertia_scale``, additive bias
torques ``bias_roll|pitch|yaw`` (ft·lbf, shorthand ``bias``), a factor on the harmonic amplitudes
of eq 3.9 ``harmonic_scale`` and initial attitude offsets ``offset_roll|pitch|yaw`` (deg, shorthand
``offset``).  Distributions: ``{uniform: [low, high]}``, ``{normal: [mean, std]}`` or
``{percent: p}`` (relative and scale parameters only: neutral value ± p/100, uniform).

The parameters and the schema of the ``sweep`` section live in :mod:`acmm.sweep.spec`; this
module resolves the base configs and reads the file.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import yaml

from acmm.io.config import Config, load_config, parse_config
from acmm_qpp.configio import apply_overrides, read_yaml, remember_origin, require_mapping, validate_model
from acmm.sweep.spec import SweepFile, SweepSpec
from acmm_qpp.errors import ConfigError
import json
from acmm.sweep.limits import check_sweep_work
from acmm import PACKAGED_CONFIGS
from acmm_qpp.provenance import config_hash
import difflib

#: Version of how a ``design: fixed`` case is computed, part of :meth:`Sweep.results_key` so that
#: ``--resume`` never mixes rows of two versions: 2 (2026-11-30): a case starts at the equilibrium
#: connected to the design TEA (:mod:`acmm.sweep.case`); 1: at the root continued
#: from LVLH.  (A redesigned case is designed about its own plant's TEA, as before.)
CASE_MODEL = 2

#: Version of a case's metrics, part of :meth:`Sweep.results_key` for every sweep: 2 (2026-11-30):
#: peaks, steady errors and saturation times over every accepted integrator step
#: (:class:`acmm.simulate.scenario.RunExtremes`); 1: over the output samples.
METRICS_MODEL = 2


@dataclass(frozen=True)
class Base:
    """A resolved base config.

    Attributes
    ----------
    label : str
        The config's name.
    config : acmm.io.config.Config
        The validated config.
    source : str
        Where it was read from (a path or a packaged name).
    """

    label: str        # the config's name
    config: Config
    source: str       # where it was read from


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: the file's model plus its resolved base configs.

    Attributes
    ----------
    file : SweepFile
        The validated sweep file.
    bases : tuple of Base
        The resolved base configs.
    source : str
        Where the sweep was read from.
    """

    file: SweepFile
    bases: tuple[Base, ...]
    source: str

    @property
    def spec(self) -> SweepSpec:
        """The ``sweep`` section."""
        return self.file.sweep

    @property
    def name(self) -> str:
        """The sweep's name."""
        return self.file.name

    def run_dir(self) -> Path:
        """The results folder ``<output.root>/<name>``.

        Returns
        -------
        Path
            The folder.
        """
        return Path(self.file.output.root) / self.file.name

    def to_yaml(self) -> str:
        """The resolved sweep config plus every resolved base config, as YAML.

        Returns
        -------
        str
            The YAML text.
        """
        d = {"sweep_file": self.file.model_dump(mode="json", exclude_none=True),
             "bases": {b.label: b.config.model_dump(mode="json") for b in self.bases}}
        return yaml.safe_dump(d, sort_keys=False)

    def changed_since(self, config_yaml: Path) -> list[str]:
        """The settings that differ from an earlier run's ``config.yaml`` (``key: old → new``),
        leaving out those that do not change the cases (workers, description, output).

        Parameters
        ----------
        config_yaml : Path
            The run folder's ``config.yaml`` of the earlier run.

        Returns
        -------
        list of str
            The differences, in the order of the config (empty: the file is unreadable, or the
            same settings).
        """
        try:
            old = yaml.safe_load(Path(config_yaml).read_text(encoding="utf-8"))
        except (OSError, ValueError, yaml.YAMLError):
            return []
        if not isinstance(old, dict):
            return []
        flat_old = _flatten(_case_settings(old.get("sweep_file"), old.get("bases")))
        flat_new = _flatten(self._case_settings())
        keys = list(dict.fromkeys([*flat_new, *flat_old]))
        return [f"{k.removeprefix('file.')}: {flat_old.get(k, '(unset)')!s} → {flat_new.get(k, '(unset)')!s}"
                for k in keys if flat_old.get(k) != flat_new.get(k)]

    def _case_settings(self) -> dict:
        """The resolved sweep file and base configs without what does not change the cases."""
        return _case_settings(self.file.model_dump(mode="json", exclude_none=True),
                              {b.label: b.config.model_dump(mode="json") for b in self.bases})

    def results_key(self) -> str:
        """Hash of everything that determines the case results (not workers, figures, description).

        Returns
        -------
        str
            16 hex digits (:func:`acmm_qpp.provenance.config_hash`).
        """
        key = {**self._case_settings(), "metrics": METRICS_MODEL}
        # the order of the grid's and the Monte Carlo's parameters decides which values case i
        # gets (product order, draw order), and sort_keys below would lose it
        key["parameter_order"] = {k: list(key["file"]["sweep"].get(k) or {}) for k in ("grid", "monte_carlo")}
        if self.spec.design == "fixed":        # a redesigned case is computed as before
            key["case_model"] = CASE_MODEL
        return config_hash(json.dumps(key, sort_keys=True))


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

    Parameters
    ----------
    data : object
        The parsed YAML (a mapping with a ``sweep`` section).
    source : str
        Where it was read from, for error messages.
    directory : Path, optional
        Directory against which base paths resolve (default: the working directory).

    Returns
    -------
    Sweep
        The validated sweep with its resolved base configs.

    Raises
    ------
    ConfigError
        One line naming the offending field.
    """
    require_mapping(data, source)
    if "sweep" not in data and "sweep_file" in data:
        return _parse_resolved(data, source)
    if "sweep" not in data:
        raise ConfigError(f"{source}: sweep: missing (a sweep config needs a 'sweep' section)")
    directory = Path(".") if directory is None else directory
    raw = data["sweep"]
    if not isinstance(raw, dict):
        raise ConfigError(f"{source}: sweep: expected a mapping (base or bases, then monte_carlo or grid), "
                          f"got {type(raw).__name__}")
    inline = "base" not in raw and "bases" not in raw
    if inline and "inertia" not in data:     # neither a base nor an inline acmm config around it
        unknown = [k for k in raw if k not in SweepSpec.model_fields]
        close = [m for k in unknown for m in difflib.get_close_matches(str(k), ["base", "bases"], n=1)]
        hint = (f" (sweep.{unknown[0]}: unknown key" + (f"; did you mean {close[0]!r}?)" if close else ")")
                if unknown else "")
        raise ConfigError(f"{source}: sweep.base: missing: give the base config (sweep.base: NAME or "
                          f"sweep.bases: [...]), or write the sweep inside a full acmm config{hint}")
    if inline:
        base_cfg = parse_config({k: v for k, v in data.items() if k != "sweep"}, source=source)
        sf = validate_model(SweepFile, {"name": base_cfg.name, "description": base_cfg.description, "sweep": raw,
                                        "output": base_cfg.output.model_dump(mode="json")}, source)
        bases = (Base(base_cfg.name, base_cfg, source),)
    else:
        sf = validate_model(SweepFile, data, source)
        bases = tuple(_resolve_base(r, directory) for r in sf.sweep.base_names())
    labels = [b.label for b in bases]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"{source}: sweep.bases: two base configs share the name "
                          f"{next(x for x in labels if labels.count(x) > 1)!r}")
    sweep = Sweep(sf, bases, source)

    check_sweep_work(sweep, source)
    return sweep


def _parse_resolved(data: dict, source: str) -> Sweep:
    """The resolved form a sweep writes next to its results (:meth:`Sweep.to_yaml`, ``config.yaml``
    and the ``config`` attribute of ``sweep.h5``): ``sweep_file`` (the sweep file) and ``bases``
    (every base config, by name, in order), parsed as they are: the same sweep, the same
    :meth:`Sweep.results_key`, without the files it was first read from."""
    extra = sorted(set(data) - {"sweep_file", "bases"})
    if extra:
        raise ConfigError(f"{source}: {extra[0]}: not a key of a resolved sweep (sweep_file, bases)")
    bases_data = data.get("bases")
    if not isinstance(bases_data, dict) or not bases_data:
        raise ConfigError(f"{source}: bases: missing or empty (the resolved base configs, by name)")
    sf = validate_model(SweepFile, data["sweep_file"], f"{source}: sweep_file")
    bases = tuple(Base(str(label), parse_config(cfg, source=f"{source}: bases.{label}"), source)
                  for label, cfg in bases_data.items())
    for b in bases:
        if b.label != b.config.name:
            raise ConfigError(f"{source}: bases.{b.label}: its name is {b.config.name!r}")
    expected = len(sf.sweep.base_names()) or 1            # an inline sweep: its one config
    if len(bases) != expected:
        raise ConfigError(f"{source}: bases: {len(bases)} config(s) for the {expected} base(s) of "
                          "sweep_file.sweep")
    sweep = Sweep(sf, bases, source)

    check_sweep_work(sweep, source)
    return sweep


def load_sweep(path: str | Path, overrides: list[str] | None = None) -> Sweep:
    """Read and validate a sweep config file (a bare name is looked up among the packaged configs).

    Parameters
    ----------
    path : path-like
        The sweep file, or a packaged config name.
    overrides : list of str, optional
        Dotted ``key=value`` overrides (:mod:`acmm_qpp.configio`), applied before validation,
        e.g. ``sweep.n_runs=20``.

    Returns
    -------
    Sweep
        The validated sweep.
    """
    data, p = read_yaml(path, PACKAGED_CONFIGS)
    sw = parse_sweep(apply_overrides(data, overrides), source=str(p), directory=p.parent)
    return remember_origin(sw, str(p), overrides)


def _case_settings(file: object, bases: object) -> dict:
    """``{"file": …, "bases": {label: …}}``: a sweep file and its base configs as mappings (dumped,
    or read back from a run's ``config.yaml``) without the settings that do not change the cases
    (the sweep's workers; descriptions and outputs)."""
    f = {k: v for k, v in (file if isinstance(file, dict) else {}).items() if k not in ("description", "output")}
    if isinstance(f.get("sweep"), dict):
        f["sweep"] = {k: v for k, v in f["sweep"].items() if k != "workers"}
    bases = {label: {k: v for k, v in c.items() if k not in ("output", "description")} if isinstance(c, dict) else c
             for label, c in (bases if isinstance(bases, dict) else {}).items()}
    return {"file": f, "bases": bases}


def _flatten(tree, prefix: str = "") -> dict:
    """``{"a.b.c": value}`` of a nested mapping (lists are values)."""
    if not isinstance(tree, dict):
        return {prefix: tree} if prefix else {}
    return {key: value for k, v in tree.items()
            for key, value in _flatten(v, f"{prefix}.{k}" if prefix else str(k)).items()}
