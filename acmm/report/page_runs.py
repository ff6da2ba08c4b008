"""The stages whose numbers README.md and the guide quote (:mod:`acmm.report.page_blocks`), run
into a results root through the report's own functions (:mod:`acmm.report.gather`), figures off.

The packaged designs and simulations of ch. 5–6 (MB3, AC, the stair-case), the ±30 % inertia
sweep of ch. 7, the qpp examples of ch. 13–14 and the shipped ones, and the variants the guide
compares them with: the regional LMI and robust routes (:data:`ROUTE_VARIANTS`) and the
stair-case's other schedules (:data:`STAIRCASE_VARIANTS`); and the search over procedure 12.1's
family of the report's two qpp examples that docs/qpp-certificates.md quotes
(:func:`family_search`).
"""
from __future__ import annotations

import os
from pathlib import Path

import yaml

from acmm import PACKAGED_CONFIGS
from acmm.io.config import load_config
from acmm.report.gather import (REPORT_VARIANTS, acmm_config, ensure_acmm_design, ensure_acmm_simulation, ensure_qpp,
                                qpp_config, qpp_scenarios, robustness_result)
from acmm.sweep.config import parse_sweep
from acmm.sweep.run import run_sweep
from acmm_qpp.configio import packaged_config_path
from acmm_qpp.errors import AcmmError
from acmm_qpp.results import read_h5
from qpp.design.family import REPORT_CERTIFIED, REPORT_GRIDS, refine, resettle, search

#: the qpp configs the pages quote: the report's two chapters and the three shipped examples
QPP_CONFIGS = ("qpp_siso", "qpp_manipulator", "qpp_unstable", "qpp_saturation", "qpp_cubic2", "qpp_siso_certified")


def run_stages(root: Path, workers: int | None = None) -> dict:
    """Run the stages the README quotes into ``root`` and read their results back.

    Parameters
    ----------
    root : pathlib.Path
        Results root (``<root>/<name>/``): an empty temporary folder.
    workers : int, optional
        Worker processes of the sweep (default: min(2, CPUs)).

    Returns
    -------
    dict
        ``"design:<name>"`` (mb3, mb3_decoupled, ac, staircase), ``"simulate:<name>"`` (mb3,
        mb3_decoupled, staircase), ``"sweep"`` (``sweep_inertia30``) → the file as read by
        :func:`acmm_qpp.results.read_h5`; ``"config:<name>"`` → the acmm config;
        ``"qpp_design:<name>"`` (:data:`QPP_CONFIGS`) → ``qpp_design.h5`` as read by ``read_h5``,
        ``"qpp_sim:<name>"`` → :func:`qpp_scenarios` of ``qpp_sim.h5``, ``"qpp_config:<name>"`` →
        the qpp config; ``"qpp_family:<name>"`` (:data:`qpp.design.family.REPORT_GRIDS`) →
        :func:`family_search`.

    Raises
    ------
    acmm_qpp.errors.AcmmError
        The ±30 % sweep could not run (the report's robustness section names why).
    """
    out: dict = {}
    for name in ("mb3", "mb3_decoupled", "ac", "staircase"):
        cfg = acmm_config(name, root)
        out[f"config:{name}"] = cfg
        out[f"design:{name}"] = read_h5(ensure_acmm_design(cfg).path)
        if name != "ac":
            out[f"simulate:{name}"] = read_h5(ensure_acmm_simulation(cfg).path)
    for name in QPP_CONFIGS:
        qcfg = qpp_config(name, root)
        out[f"qpp_config:{name}"] = qcfg
        out[f"qpp_design:{name}"] = read_h5(ensure_qpp(qcfg, "design").path)
        out[f"qpp_sim:{name}"] = qpp_scenarios(ensure_qpp(qcfg, "simulate").path)
    for name, grid in REPORT_GRIDS.items():
        out[f"qpp_family:{name}"] = family_search(out[f"qpp_config:{name}"], grid, REPORT_CERTIFIED.get(name))
    res, note = robustness_result(root, workers=workers)
    if res is None:
        raise AcmmError(f"the sweep for the README did not run: {note}")
    out["sweep"] = res["data"]
    out.update(route_variants(root, workers))
    return out


def family_search(cfg, grid: dict, beyond: tuple | None = None) -> dict:
    """Procedure 12.1's family of ``cfg`` searched on ``grid`` (:func:`qpp.design.family.search`),
    locally from the grid's best point (:func:`qpp.design.family.refine`) and at one design
    ``beyond`` the grid, on the first pass's samples and on the certificate's own
    (:func:`qpp.design.family.resettle`); minutes on one core for ch. 13's grid.

    Parameters
    ----------
    cfg : qpp.io.config.QppConfig
        The qpp config.
    grid : dict
        ``"rho"``, ``"w"``, ``"a"``: the grid's control weights ρ (dimensionless), output weights
        w (dimensionless) and exponential weightings a (1/s), as in
        :data:`qpp.design.family.REPORT_GRIDS`.
    beyond : tuple, optional
        (ρ, w, a) of a design off the grid, as in :data:`qpp.design.family.REPORT_CERTIFIED`.

    Returns
    -------
    dict
        ``"candidates"`` (list of :class:`qpp.design.family.Candidate`, one per grid design),
        ``"best"`` (the one with the largest m − β1), ``"refined"`` (the local search's end, a
        Candidate), ``"designs"`` (the designs the local search evaluated), and with ``beyond``
        ``"beyond"`` (its Candidate) and ``"resettled"`` (its :class:`qpp.design.family.Resettled`).
    """
    cands = search(cfg, grid["rho"], grid["w"], grid["a"])
    best = max(cands, key=lambda c: c.m - c.beta1)
    refined, designs = refine(cfg, best)
    out = {"candidates": cands, "best": best, "refined": refined, "designs": designs}
    if beyond is not None:
        out["beyond"] = search(cfg, *[[x] for x in beyond])[0]
        out["resettled"] = resettle(cfg, out["beyond"])
    return out


def variant_config(root: Path, base: str, name: str, patch: dict):
    """A packaged acmm config ``base`` renamed ``name``, its sections updated by ``patch``,
    written into ``root`` and loaded with results under ``root`` (figures off).

    Parameters
    ----------
    root : pathlib.Path
        Results root; the config file is written there as ``<name>.yaml``.
    base : str
        Packaged config name (``mb3``, ``staircase``, ...).
    name : str
        The variant's name.
    patch : dict
        ``{section: {key: value}}`` merged into the base's sections.

    Returns
    -------
    tuple
        (path of the written config file, the loaded config).
    """
    data = yaml.safe_load(packaged_config_path(f"{base}.yaml", PACKAGED_CONFIGS).read_text())
    data["name"] = name
    for section, values in patch.items():
        data.setdefault(section, {}).update(values)
    path = root / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path, load_config(str(path), [f"output.root={root}", "output.figures=false"])


#: the station routes beside the packaged sector LQR (``block_design_routes``): the regional LMI
#: point design, and the robust gain for the ±30 % family started from it (``design.robust``)
ROUTE_VARIANTS = {
    "lmi": {"design": {"pole_method": "lmi"}},
    "robust": {"design": {"pole_method": "lmi", "robust": {"inertia_percent": 30}}},
}

#: the stair-case variants of the routes table (``block_staircase_routes``) beside the packaged one
#: (regional LMI points, table look-up, judged on a 1 001-TEA path): the report's own two
#: (:data:`acmm.report.gather.REPORT_VARIANTS`, the report's route with the same table and the
#: quadratic converged on the path from the LMI points: the same names and designs, so a report on
#: this root reuses them), and the report's route with its own quadratic (least squares, ch. 5.3)
STAIRCASE_VARIANTS = {
    **{key: patch for key, (_, patch) in REPORT_VARIANTS.items()},
    "staircase_lqr_quadratic": {"design": {"pole_method": "shift"},
                                "schedule": {"form": "polynomial", "fit": "least_squares", "refine_points": 0}},
}


def route_variants(root: Path, workers: int | None) -> dict:
    """MB3 and AC designed by each route of :data:`ROUTE_VARIANTS` (regional LMI, robust) and the
    packaged ±30 % sweep of those fixed gains on the same draws (``"design:<name>_<route>"``,
    ``"sweep_<route>"``), and the stair-case variants of :data:`STAIRCASE_VARIANTS`, designed and simulated
    (``"design:<variant>"``, ``"simulate:<variant>"``, ``"config:<variant>"``).

    Parameters
    ----------
    root : pathlib.Path
        Results root.
    workers : int or None
        Worker processes of the sweeps (default: min(2, CPUs)).

    Returns
    -------
    dict
        Those results files as read by :func:`acmm_qpp.results.read_h5`, and the variants' configs.
    """
    out = {}
    for route, patch in ROUTE_VARIANTS.items():
        bases = []
        for name in ("mb3", "ac"):
            path, cfg = variant_config(root, name, f"{name}_{route}", patch)
            bases.append(str(path))
            out[f"design:{name}_{route}"] = read_h5(ensure_acmm_design(cfg).path)
        p = packaged_config_path("sweep_inertia30.yaml", PACKAGED_CONFIGS)
        data = yaml.safe_load(p.read_text())
        data["name"], data["sweep"]["bases"] = f"sweep_inertia30_{route}", bases
        data["output"] = {"root": str(root), "figures": False}
        sweep = parse_sweep(data, source=str(p), directory=p.parent)
        out[f"sweep_{route}"] = read_h5(run_sweep(sweep, workers=workers or max(1, min(2, os.cpu_count() or 1)),
                                                  figures=False).path)
    for name, patch in STAIRCASE_VARIANTS.items():
        _, cfg = variant_config(root, "staircase", name, patch)
        out[f"config:{name}"] = cfg
        out[f"design:{name}"] = read_h5(ensure_acmm_design(cfg).path)
        out[f"simulate:{name}"] = read_h5(ensure_acmm_simulation(cfg).path)
    return out
