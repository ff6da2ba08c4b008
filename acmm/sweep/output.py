"""Sweep results: ``sweep.h5`` (atomic), ``sweep.csv`` and the figures."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from acmm_qpp.errors import AcmmError, FigureError
from acmm_qpp.outputs import write_text
from acmm_qpp.results import Dataset, h5_text, write_h5
from acmm.io.dimensions import with_coordinates
from acmm.sweep.cases import VERDICTS
from acmm.sweep.spec import AXES, MAP_EXTRAS, PARAMETERS, swept_parameters
from acmm.sweep.config import Sweep, parse_sweep
import h5py
import yaml
from acmm.design.schedule_points import point_specs
from acmm.model.tea import solve_tea
from acmm.stages.common import define_units, stored_in
from dataclasses import replace
from acmm.io.units import convert_items
from acmm.model.unit_systems import display_unit, shown
from functools import partial


def split_records(sweep: Sweep, records: list[dict]):
    """The case rows and the margin records of a sweep, each in the bases' order.

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    records : list of dict
        Its journal records.

    Returns
    -------
    rows : list of dict
        The case records, by base then index.
    margins : list of dict
        The margin records, by base, ``up`` first.
    """
    order = {b.label: k for k, b in enumerate(sweep.bases)}
    rows = sorted((r for r in records if r["kind"] == "case"), key=lambda r: (order[r["base"]], r["index"]))
    margins = sorted((r for r in records if r["kind"] == "margin"),
                     key=lambda r: (order[r["base"]], r["direction"] != "up"))
    return rows, margins


#: The dimension of the per-case arrays: one row per case.
CASE = ("case",)
#: The metric columns of the case table, in order: row field → (unit, description, shape of a row's value)
METRICS = {
    "time_to_divergence": ("orbit", "stop time of a diverged run (NaN if not)", ()),
    "peak_attitude_error": ("deg", "max |θ − θ*_true| over the run (θ*_true: the plant's TEA)", (3,)),
    "steady_attitude_error": ("deg", "max |θ − θ*_true| over the second half of the run", (3,)),
    "peak_momentum": ("ft*lbf*s", "max |h_i| over the run", (3,)),
    "torque_saturation_time": ("orbit", "time with any axis torque-limited (every integrator step)", ()),
    "momentum_saturation_time": ("orbit", "time with any CMG axis at its momentum limit (every integrator step)",
                                 ()),
    "tea_true": ("deg", "TEA of the perturbed plant (first level)", (3,)),
    "tea_estimate": ("deg", "TEA estimate used by the controller (first level)", (3,)),
    "inertia": ("slug*ft^2", "perturbed inertia (first level)", (3, 3)),
    "bias": ("ft*lbf", "bias torque (first level)", (3,)),
}


def _table_arrays(sweep: Sweep, rows: list[dict]) -> dict:
    """Column name → array (N rows) of the case rows (:func:`acmm.sweep.case.run_case`, sorted by
    base then index) in the rows' units: attitude errors and TEAs deg, momentum ft·lbf·s, times
    orbits, inertia slug·ft², bias ft·lbf; ``parameters`` a dict of the swept parameters;
    ``verdict`` and ``reason`` lists of str."""
    labels = [b.label for b in sweep.bases]
    return {
        "base": np.array([labels.index(r["base"]) for r in rows], np.int64),
        "index": np.array([r["index"] for r in rows], np.int64),
        "case": np.array([labels.index(r["base"]) * sweep.spec.n_cases() + r["index"] for r in rows], np.int64),
        "parameters": {k: np.array([r["values"].get(k, PARAMETERS[k].neutral) for r in rows], float)
                       for k in swept_parameters(sweep.spec)},
        "verdict": [r["verdict"] for r in rows],
        "verdict_code": np.array([VERDICTS.index(r["verdict"]) for r in rows], np.int64),
        "reason": [r["reason"] for r in rows],
        "stable": np.array([r["verdict"] == "bounded" for r in rows], bool),
        **{k: np.array([r[k] for r in rows], float).reshape((len(rows),) + shape)
           for k, (_, _, shape) in METRICS.items()},
        "n_draws": np.array([r["n_draws"] for r in rows], np.int64),
    }


def _nominal_tea_deg(sweep: Sweep) -> dict:
    out = {}
    for b in sweep.bases:
        s = point_specs(b.config)[0]
        try:
            out[b.label] = np.degrees(solve_tea(s.inertia, b.config.orbit_rate, s.bias, expected=s.expected).theta)
        except AcmmError:
            out[b.label] = np.full(3, np.nan)
    return out


def _margin_items(margins: list, S) -> dict:
    """Datasets of the margin searches: one group ``<base>_<direction>`` per search."""
    return {
        m["base"] + "_" + m["direction"]: {
            "limit": Dataset(m["limit"], "1", "tolerated uniform inertia scaling (bounded up to here)"),
            "first_failure": Dataset(m["first_failure"], "1", "first failing scaling (NaN: none up to search_end)"),
            "search_end": Dataset(m["search_end"], "1", "end of the searched range"),
            "evaluated_s": Dataset(np.array(m["evaluated_s"]), "1", "scalings evaluated, in order",
                                   dims=("evaluation",)),
            "evaluated_verdict": Dataset(S(m["evaluated_verdict"]), "1", "verdict at each", dims=("evaluation",)),
            # fixed-length UTF-8 like every other text variable (a scalar str became variable-length)
            "failure_reason": Dataset(np.array((m["failure_reason"] or "-").encode(), dtype="S"), "1",
                                      "why the first failure failed"),
        } for m in margins}


def _root_attrs(sweep: Sweep, a: dict, labels: list, n_done: int, complete: bool,
                wall_time: float | None) -> dict:
    """Root attributes of ``sweep.h5``: what was run, how far, and the verdict counts per base."""
    spec = sweep.spec
    summary = {lab: {v: int(np.sum((a["base"] == k) & (a["verdict_code"] == j))) for j, v in enumerate(VERDICTS)}
               for k, lab in enumerate(labels)}
    attrs = {"stage": "sweep", "sweep_name": sweep.name, "complete": bool(complete),
             "n_cases_expected": spec.n_cases() * len(labels), "n_cases_done": n_done,
             "design": spec.design, "tea_estimate": spec.tea_estimate, "seed": spec.seed,
             "method": "grid" if spec.grid is not None else "monte_carlo",
             "verdicts": json.dumps(list(VERDICTS)), "summary": json.dumps(summary),
             "results_key": sweep.results_key()}
    if wall_time is not None:
        attrs["wall_time_s"] = float(wall_time)
    return attrs


def _orbit_defined(items: dict, sweep) -> dict:
    """``items`` with the unit ``orbit`` defined (:func:`acmm.stages.common.define_units`) when
    every base config has the same orbit rate; else an orbit's length differs between cases and
    each dataset in orbits says that its case's orbit is ``orbit_period[case]`` s."""

    rates = {b.config.orbit_rate for b in sweep.bases}
    if len(rates) == 1:
        return define_units(items, rates.pop())
    # bases of different orbit rates: no one definition; each case's orbit is its orbit_period
    return {k: replace(v, attrs={**v.attrs, "units_per_case": "orbit = orbit_period[case] * s"})
            if getattr(v, "units", None) == "orbit" else v for k, v in items.items()}


def write_results(sweep: Sweep, records: list[dict], complete: bool, figures: bool = False,
                  wall_time: float | None = None) -> tuple[Path, list]:
    """Build ``sweep.h5`` (atomically, via :func:`acmm_qpp.results.write_h5`) and ``sweep.csv`` from
    the records; with ``figures`` also the stability map and the peak-error distributions.

    Parameters
    ----------
    sweep : acmm.sweep.config.Sweep
        The sweep.
    records : list of dict
        Journal records (cases and margin searches).
    complete : bool
        Every task is done (root attribute ``complete``; False for a snapshot).
    figures : bool, optional
        Also write the figures.
    wall_time : float, optional
        Wall time of the sweep so far, s (root attribute ``wall_time_s``).

    Returns
    -------
    tuple
        (pathlib.Path of ``sweep.h5``, list of the figure paths).
    """
    rows, margins = split_records(sweep, records)
    a = _table_arrays(sweep, rows)
    labels = [b.label for b in sweep.bases]
    nominal = _nominal_tea_deg(sweep)
    S = lambda xs: np.array([x.encode() for x in xs], dtype="S") if len(xs) else np.zeros(0, "S1")  # noqa: E731
    items = {
        "case": Dataset(a["case"], "1", "global case index = base_index·n_cases + index", dims=CASE),
        "base": Dataset(a["base"], "1", "index into base_names", dims=CASE),
        "base_names": Dataset(S(labels), "1", "base config names", dims=("base_name",)),
        "index": Dataset(a["index"], "1", "case index within its base (seeds SeedSequence([seed, index]))", dims=CASE),
        "parameters": {k: Dataset(v, PARAMETERS[k].unit, PARAMETERS[k].description, dims=CASE)
                       for k, v in a["parameters"].items()},
        "verdict": Dataset(S(a["verdict"]), "1", "bounded | not_settled | diverged | no_equilibrium | unphysical | "
                                                 "design_failed | tea_failed", dims=CASE),
        "verdict_code": Dataset(a["verdict_code"], "1", "index into the root attribute 'verdicts'", dims=CASE),
        "reason": Dataset(S(a["reason"]), "1", "why the run stopped or was not run", dims=CASE),
        "stable": Dataset(a["stable"], "1", "verdict == bounded", dims=CASE),
        **{k: Dataset(a[k], unit, text, list(AXES) if shape == (3,) else None,
                      dims=CASE + ("axis", "axis_col")[:len(shape)]) for k, (unit, text, shape) in METRICS.items()},
        "n_draws": Dataset(a["n_draws"], "1", "Monte Carlo draws used (resampling of unphysical inertia)", dims=CASE),
        "nominal_tea": Dataset(np.array([nominal[lab] for lab in labels]).reshape(len(labels), 3), "deg",
                               "TEA of each base config's nominal plant (NaN: none found)", list(AXES),
                               dims=("base_name", "axis")),
        "orbit_period": Dataset(np.array([2 * np.pi / sweep.bases[int(k)].config.orbit_rate for k in a["base"]]),
                                "s", "orbital period of the case's base: the length of its 'orbit'", dims=CASE),
    }
    if margins:
        items["margin"] = _margin_items(margins, S)
    run_dir = sweep.run_dir()
    system = sweep.file.output.units
    path = write_h5(run_dir / "sweep.h5", with_coordinates(convert_items(_orbit_defined(items, sweep), system)),
                    sweep.to_yaml(), {**_root_attrs(sweep, a, labels, len(rows), complete, wall_time),
                                      "unit_system": system})
    _write_csv(run_dir / "sweep.csv", labels, a, system)
    figs = []
    if figures and rows:
        try:
            figs = _plot_sweep(sweep, a, run_dir, nominal)
        except OSError as exc:        # the tables are written: only a figure failed (exit 4)
            err = FigureError.of(exc)
            raise err from (None if err is exc else exc)
    return path, figs


def _write_csv(path: Path, labels, a, units: str = "imperial") -> None:
    per_axis = {"peak_attitude_error": "deg", "steady_attitude_error": "deg",
                "peak_momentum": display_unit("ft*lbf*s", units), "tea_true": "deg"}
    cols = ["case", "base", "index"] + [f"{k}[{display_unit(PARAMETERS[k].unit, units)}]" for k in a["parameters"]] + [
        "verdict", "time_to_divergence[orbit]"]
    for what, unit in per_axis.items():
        cols += [f"{what}_{ax}[{unit}]" for ax in AXES]
    a = dict(a)
    a["parameters"] = {k: shown(np.asarray(v, float), PARAMETERS[k].unit, units)[0] for k, v in a["parameters"].items()}
    a["peak_momentum"] = shown(np.asarray(a["peak_momentum"], float), "ft*lbf*s", units)[0]
    cols += ["torque_saturation_time[orbit]", "momentum_saturation_time[orbit]", "n_draws", "reason"]
    lines = [",".join(cols)]
    for i in range(len(a["case"])):
        vals = [str(a["case"][i]), labels[a["base"][i]], str(a["index"][i])]
        vals += [repr(float(v[i])) for v in a["parameters"].values()]
        vals += [a["verdict"][i], repr(float(a["time_to_divergence"][i]))]
        for what in per_axis:
            vals += [repr(float(x)) for x in a[what][i]]
        vals += [repr(float(a["torque_saturation_time"][i])), repr(float(a["momentum_saturation_time"][i])),
                 str(a["n_draws"][i]), '"' + a["reason"][i].replace('"', "'") + '"']
        lines.append(",".join(vals))
    write_text(path, "\n".join(lines) + "\n")


def _plot_sweep(sweep: Sweep, a: dict, run_dir: Path, nominal: dict | None = None) -> list[Path]:
    """The figures written in ``run_dir``: the stability map over two swept quantities and the
    distributions of the peak attitude error, from the column arrays ``a`` of
    :func:`_table_arrays` (their units); ``nominal``: base label → nominal TEA (3,), deg
    (default: solved for each base)."""
    from matplotlib.ticker import MaxNLocator  # deferred: matplotlib start-up

    from acmm.plots.base import stage_pyplot, write_figure  # deferred: matplotlib start-up

    plt = stage_pyplot()
    labels = [b.label for b in sweep.bases]
    axes_names = list(sweep.spec.map) if sweep.spec.map else list(a["parameters"])[:2]
    nominal = _nominal_tea_deg(sweep) if nominal is None else nominal

    system = sweep.file.output.units

    def values(name, sel, lab):
        if name in a["parameters"]:
            return shown(np.asarray(a["parameters"][name][sel], float), PARAMETERS[name].unit, system)[0]
        ax = MAP_EXTRAS.index(name)
        return a["tea_true"][sel, ax] - nominal[lab][ax]

    colors = {"bounded": "tab:green", "not_settled": "gold", "diverged": "tab:red", "no_equilibrium": "tab:purple",
              "unphysical": "tab:gray", "design_failed": "tab:orange", "tea_failed": "tab:brown"}
    B = len(labels)
    fig, axs = plt.subplots(1, B, figsize=(4.6 * B, 4.0), squeeze=False)
    for k, lab in enumerate(labels):
        ax = axs[0, k]
        sel = a["base"] == k
        x = values(axes_names[0], sel, lab)
        y = (values(axes_names[1], sel, lab) if len(axes_names) > 1
             else np.nanmax(a["peak_attitude_error"][sel], axis=1))
        verdicts = np.array(a["verdict"], dtype=object)[sel]
        for v in VERDICTS:
            m = verdicts == v
            if m.any():
                ax.scatter(x[m], y[m], s=14, c=colors[v], label=f"{v} ({int(m.sum())})", alpha=0.8)
        ax.set_xlabel(_label(axes_names[0], system))
        ax.set_ylabel(_label(axes_names[1], system) if len(axes_names) > 1 else "peak attitude error (deg)")
        ax.set_title(f"{lab}: {int(np.sum(verdicts == 'bounded'))}/{int(sel.sum())} bounded")

        ax.xaxis.set_major_locator(MaxNLocator(5))       # fewer ticks, turned: they do not crowd
        ax.yaxis.set_major_locator(MaxNLocator(6))
        ax.tick_params(axis="x", labelrotation=30)
        ax.legend(fontsize=7)
    fig.suptitle(f"{sweep.name}: stability map ({sweep.spec.design} design)")
    out = write_figure(fig, run_dir / "sweep_map.png")
    fig, axs = plt.subplots(1, B, figsize=(4.6 * B, 3.6), squeeze=False)
    for k, lab in enumerate(labels):
        ax = axs[0, k]
        sel = (a["base"] == k) & (np.array(a["verdict"], dtype=object) == "bounded")
        err = a["peak_attitude_error"][sel]
        if len(err):
            hi = max(float(np.nanmax(err)), 1e-3)
            bins = np.linspace(0, hi * 1.02, 25)
            for j, axn in enumerate(AXES):
                ax.hist(err[:, j], bins=bins, histtype="step", label=axn)
            ax.legend(fontsize=7)
        ax.set_xlabel("peak attitude error |θ − θ*_true| of bounded cases (deg)")
        ax.set_ylabel("number of cases (count)")
        ax.set_title(f"{lab}: {int(sel.sum())} bounded of {int(np.sum(a['base'] == k))}")
    fig.suptitle(f"{sweep.name}: peak attitude error")
    out += write_figure(fig, run_dir / "sweep_peak_error.png")
    return out


def _label(name: str, units: str = "imperial") -> str:
    """Axis label: quantity and unit in the output system ``units`` (a relative change is
    dimensionless: 0.1 = +10 %)."""
    if name in PARAMETERS:
        p = PARAMETERS[name]
        if p.kind == "relative":
            return f"{name}: relative change of {name[1:]} (1, 0.1 = +10 %)"
        if p.kind == "scale":
            return f"{name}: {p.description.split(':')[0].split('(')[0].strip()} (1, × nominal)"

        unit = display_unit(p.unit, units).replace("*", "·")
        return f"{name}: {p.description.split('(')[0].split(',')[0].strip()} ({unit})"
    return f"{name}: plant's {name.rsplit('_', 1)[-1]} TEA − nominal TEA (deg)"


def sweep_figures_from_file(path: Path, out_dir: Path) -> list:
    """The figures of :func:`_plot_sweep` drawn from a ``sweep.h5`` alone (``acmm plot``): its
    stored resolved config (the sweep and its base configs), case table and nominal TEAs;
    nothing is run again.

    Parameters
    ----------
    path : pathlib.Path
        The ``sweep.h5``.
    out_dir : pathlib.Path
        Folder of the figures (``sweep_map.png``, ``sweep_peak_error.png``).

    Returns
    -------
    list of functools.partial
        One call drawing both figures (none when the file holds no case), for
        :func:`acmm_qpp.results.draw_figures`.
    """
    with h5py.File(path, "r") as f:
        sweep = parse_sweep(yaml.safe_load(h5_text(f.attrs["config"])), source=str(path))
        verdict = [h5_text(v) for v in f["verdict"][()]]
        a = {"base": np.asarray(f["base"][()], np.int64), "verdict": verdict,
             # in the order of the sweep's parameters, as drawn
             "parameters": {k: stored_in(f, f"parameters/{k}", PARAMETERS[k].unit)
                            for k in swept_parameters(sweep.spec) if k in f["parameters"]},
             "peak_attitude_error": stored_in(f, "peak_attitude_error", "deg"),
             "tea_true": stored_in(f, "tea_true", "deg")}
        nominal = (dict(zip([b.label for b in sweep.bases], stored_in(f, "nominal_tea", "deg")))
                   if "nominal_tea" in f else None)
    return [partial(_plot_sweep, sweep, a, out_dir, nominal)] if verdict else []
