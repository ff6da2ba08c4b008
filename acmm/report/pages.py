"""The numbers README.md and the guide (docs/) quote about the packaged configs of Parts II and
III: the stages they come from (the designs and simulations of ch. 5–6, the ±30 % inertia sweep of
ch. 7, the qpp examples of ch. 13–14 and the shipped ones, the design routes and stair-case
schedules the guide compares, the search over procedure 12.1's family), run into a results root
through the report's own functions (:func:`run_stages`), and the text of each generated block
(:data:`BLOCKS`, the text between ``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->`` that
``scripts/readme_numbers.py`` rewrites or checks), written with the report's own formatting
(:mod:`acmm.report.numbers`): rounded to the digits that mean something (3 significant digits for
momenta and attitude errors, 3 decimals for margins in units of n, 2 significant digits for
condition numbers and robustness radii), so the text does not change between machines.
"""
from __future__ import annotations

import itertools
import math
import os
from pathlib import Path

import numpy as np
import yaml

from acmm import PACKAGED_CONFIGS
from acmm.design.regional_lmi import random_gain_radius
from acmm.io.config import load_config
from acmm.model import tea
from acmm.model.tea import NoEquilibriumError
from acmm.report.gather import (REPORT_VARIANTS, acmm_config, ensure_acmm_design, ensure_acmm_simulation, ensure_qpp,
                                qpp_config, qpp_scenarios, robustness_result)
from acmm.report.numbers import fixed, markdown_table, sci, sig
from acmm.report.sections.claim1 import peak_errors
from acmm.report.sections.robustness import bounded_count, case_column
from acmm.report.sections.schedule import point_energy, route_numbers
from acmm.report.sections.table1 import table1_teas
from acmm.sweep.config import parse_sweep
from acmm.sweep.run import run_sweep
from acmm_qpp.configio import packaged_config_path
from acmm_qpp.errors import AcmmError
from acmm_qpp.results import h5_text, read_h5
from qpp.design import spheres
from qpp.design.family import (REPORT_CERTIFIED, REPORT_GRIDS, family_bounds, peak_exclusion, refine, resettle, search,
                               settle_exclusion)

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
        ``"design:<name>"`` (mb3, mb3_decoupled, ac, staircase and :data:`STAIRCASE_VARIANTS`),
        ``"simulate:<name>"`` (the same but ac), ``"sweep"`` (``sweep_inertia30``) → the file as read by
        :func:`acmm_qpp.results.read_h5`; ``"config:<name>"`` → the acmm config;
        ``"qpp_design:<name>"`` (:data:`QPP_CONFIGS`) → ``qpp_design.h5`` as read by ``read_h5``,
        ``"qpp_sim:<name>"`` → :func:`qpp_scenarios` of ``qpp_sim.h5``, ``"qpp_config:<name>"`` →
        the qpp config; ``"qpp_family:<name>"`` (:data:`qpp.design.family.REPORT_GRIDS`) →
        :func:`_family_search`.

    Raises
    ------
    acmm_qpp.errors.AcmmError
        The ±30 % sweep could not run (the report's robustness section names why).
    """
    out: dict = {}
    acmm = [(name, acmm_config(name, root)) for name in ("mb3", "mb3_decoupled", "ac", "staircase")]
    acmm += [(name, _variant_config(root, "staircase", name, patch)[1]) for name, patch in STAIRCASE_VARIANTS.items()]
    for name, cfg in acmm:
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
        out[f"qpp_family:{name}"] = _family_search(out[f"qpp_config:{name}"], grid, REPORT_CERTIFIED.get(name))
    res, note = robustness_result(root, workers=workers)
    if res is None:
        raise AcmmError(f"the sweep for the README did not run: {note}")
    out["sweep"] = res["data"]
    out.update(_route_variants(root, workers))
    return out


def _family_search(cfg, grid: dict, beyond: tuple | None = None) -> dict:
    """Procedure 12.1's family of ``cfg`` searched on ``grid`` (``rho``, ``w`` dimensionless, ``a`` in
    1/s, as :data:`qpp.design.family.REPORT_GRIDS`), then locally from its best point (largest m − β1)
    and, with ``beyond`` (ρ, w, a as :data:`qpp.design.family.REPORT_CERTIFIED`), at that design off
    the grid and on the certificate's own samples: ``{"candidates", "best", "refined", "designs"[,
    "beyond", "resettled"]}``; minutes on one core for ch. 13's grid."""
    cands = search(cfg, grid["rho"], grid["w"], grid["a"])
    best = max(cands, key=lambda c: c.m - c.beta1)
    refined, designs = refine(cfg, best)
    out = {"candidates": cands, "best": best, "refined": refined, "designs": designs}
    if beyond is not None:
        out["beyond"] = search(cfg, *[[x] for x in beyond])[0]
        out["resettled"] = resettle(cfg, out["beyond"])
    return out


def _variant_config(root: Path, base: str, name: str, patch: dict):
    """The packaged acmm config ``base`` renamed ``name``, its sections updated by ``patch``
    (``{section: {key: value}}``), written to ``root/<name>.yaml`` and loaded with results under
    ``root``, figures off: (path of the file, the config)."""
    data = yaml.safe_load(packaged_config_path(f"{base}.yaml", PACKAGED_CONFIGS).read_text())
    data["name"] = name
    for section, values in patch.items():
        data.setdefault(section, {}).update(values)
    path = root / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path, load_config(str(path), [f"output.root={root}", "output.figures=false"])


#: the station routes beside the packaged sector LQR (``_block_design_routes``): the regional LMI
#: point design, and the robust gain for the ±30 % family started from it (``design.robust``)
ROUTE_VARIANTS = {
    "lmi": {"design": {"pole_method": "lmi"}},
    "robust": {"design": {"pole_method": "lmi", "robust": {"inertia_percent": 30}}},
}

#: the stair-case variants of the routes table (``_block_staircase_routes``) beside the packaged one
#: (regional LMI points, table look-up, judged on a 1 001-TEA path): the report's own two
#: (:data:`acmm.report.gather.REPORT_VARIANTS`, the report's route with the same table and the
#: quadratic converged on the path from the LMI points: the same names and designs, so a report on
#: this root reuses them), and the report's route with its own quadratic (least squares, ch. 5.3)
STAIRCASE_VARIANTS = {
    **{key: patch for key, (_, patch) in REPORT_VARIANTS.items()},
    "staircase_lqr_quadratic": {"design": {"pole_method": "shift"},
                                "schedule": {"form": "polynomial", "fit": "least_squares", "refine_points": 0}},
}


def _route_variants(root: Path, workers: int | None) -> dict:
    """MB3 and AC designed by each route of :data:`ROUTE_VARIANTS` with the packaged ±30 % sweep of
    those gains (``"design:<name>_<route>"``, ``"sweep_<route>"``), as :func:`run_stages`."""
    out = {}
    for route, patch in ROUTE_VARIANTS.items():
        bases = []
        for name in ("mb3", "ac"):
            path, cfg = _variant_config(root, name, f"{name}_{route}", patch)
            bases.append(str(path))
            out[f"design:{name}_{route}"] = read_h5(ensure_acmm_design(cfg).path)
        p = packaged_config_path("sweep_inertia30.yaml", PACKAGED_CONFIGS)
        data = yaml.safe_load(p.read_text())
        data["name"], data["sweep"]["bases"] = f"sweep_inertia30_{route}", bases
        data["output"] = {"root": str(root), "figures": False}
        sweep = parse_sweep(data, source=str(p), directory=p.parent)
        out[f"sweep_{route}"] = read_h5(run_sweep(sweep, workers=workers or max(1, min(2, os.cpu_count() or 1)),
                                                  figures=False).path)
    return out


def _decimals(p: float) -> int:
    """Decimals of a printed value (the fewest that give it back)."""
    return next(d for d in range(12) if abs(round(p, d) - p) <= 1e-12 * max(1.0, abs(p)))


def _gains(printed, computed, extra: int) -> tuple[str, bool]:
    """Computed gains at the printed decimals + ``extra`` (non-zero printed entries, rows by " / "),
    and whether every one rounds to its printed value."""
    rows, ok = [], True
    for pr, co in zip(np.atleast_2d(printed), np.atleast_2d(computed)):
        cells = []
        for p, c in zip(pr, co):
            if p != 0.0:
                d = _decimals(p)
                ok &= bool(abs(c - p) <= 0.5 * 10.0 ** -d * (1 + 1e-9))
                cells.append(fixed(c, d + extra))
        rows.append(", ".join(cells))
    return " / ".join(rows), ok


def _printed(printed) -> str:
    return " / ".join(", ".join(fixed(p, _decimals(p)) for p in row if p != 0.0)
                      for row in np.atleast_2d(printed))


def _qpp_summary(r: dict, name: str) -> dict:
    """What the README says about one report chapter's design (``qpp_design.h5``, ``qpp_sim.h5``)."""
    d, cfg, sims = r[f"qpp_design:{name}"], r[f"qpp_config:{name}"], r[f"qpp_sim:{name}"]
    pub, pc = d["published"], d["published_certificate"]
    k = np.concatenate([np.ravel(pub["K1"]), np.ravel(pub["Kc"])])
    kc = np.concatenate([np.ravel(d["K1"]), np.ravel(d["Kc"])])
    _, k_ok = _gains(k[None, :], kc[None, :], 0)
    rel = np.ravel(pub["H_rel_diff"])[np.ravel(pub["H"]) != 0]
    m = float(np.atleast_2d(d["thresholds"])[0, 3])          # printed β3, β4 (row 0: printed bookkeeping)
    return {"d": d, "cfg": cfg, "sims": sims, "k_ok": k_ok, "h_rel": rel, "m": m,
            "b1": (float(pc["beta1_eq10_7"]), float(pc["beta1_printed"]))}


def _block_qpp_bullet(r: dict) -> str:
    """The QPP bullet of "What the tool reproduces": gains, H, m, β1 and the spheres of ch. 13, 14."""
    s = [_qpp_summary(r, n) for n in ("qpp_siso", "qpp_manipulator")]
    k = ("published K reproduced to the printed digits" if all(x["k_ok"] for x in s)
         else "published K **not** reproduced to the printed digits")
    rel = np.concatenate([x["h_rel"] for x in s]) * 100
    holds = [[b <= x["m"] for b in x["b1"]] for x in s]
    which = {(True, True): "both readings", (True, False): "the eq 10.7 reading only",
             (False, True): "the printed reading only", (False, False): "neither reading"}
    in_spheres = all(v["passed"] for x in s for v in x["sims"].values())
    cert = tuple(bool(int(x["d"]["attrs"]["certified"])) for x in s)
    consistent = {(False, False): "neither example is certified", (True, True): "both examples are certified",
                  (True, False): "only the SISO example is certified",
                  (False, True): "only the manipulator is certified"}[cert]
    return (f"* **QPP** (ch. 13, 14): {k}, H within {sig(rel.min(), 2)}–{sig(rel.max(), 2)} %, "
            f"m = {fixed(s[0]['m'], 5)}\n  and {fixed(s[1]['m'], 5)}, β1 exact for both B_z readings; the report's "
            f"own bookkeeping reproduces\n  β1 ≤ m for the SISO example with {which[tuple(holds[0])]} and for the "
            f"manipulator with {which[tuple(holds[1])]},\n  a reproduction, not a certificate: in the consistent "
            f"reading (one sector, one norm) {consistent}\n  ([QPP certificates](../qpp-certificates.md)); simulated "
            f"errors {'within' if in_spheres else '**not** all within'} the output spheres (see [QPP results](qpp.md)).\n")


def _block_qpp_certificates(r: dict) -> str:
    """docs/qpp-certificates.md: per packaged qpp config, the report's bookkeeping (a reproduction)
    beside the consistent certificate (one sector, the Euclidean norm) and its verdict (a table)."""
    rows = []
    for name in QPP_CONFIGS:
        d = r[f"qpp_design:{name}"]
        a, c = d["attrs"], d["certificate"]
        bk = str(a["bookkeeping"])
        if bk == "consistent":
            rep = "— (iterates against the consistent m)"
        else:
            rep = f"{bk}: m = {fixed(float(c['m_bookkeeping']), 5)}, {'holds' if float(c['beta1']) <= float(c['m_bookkeeping']) else 'fails'}"
        ok = bool(int(a["certified"]))
        failed = [k[8:-1] for k in a if k.startswith("premise[") and not int(a[k])]
        rows.append([f"`{name}`", rep, fixed(float(c["beta1"]), 4),
                     f"{fixed(float(c['m']), 4)} ({fixed(float(c['beta_i']), 4)}, {fixed(float(c['beta3']), 4)}, "
                     f"{fixed(float(c['beta4']), 4)})", fixed(float(c["peak_ratio"]), 3),
                     f"{sig(float(d['T']))}, {sig(float(c['T_settle']))}",
                     "**certified** (0)" if ok else f"no certified design: {', '.join(failed)} fail (3)"])
    return markdown_table(["config", "report's bookkeeping (reproduction, not a certificate): m, β1 ≤ m",
                           "consistent: β1", "m (β_i, β3, β4)", "γ∞·max E/m",
                           "T, nominal settling time (s)", "verdict (exit of `qpp design`)"], rows)


def _block_qpp_search(r: dict) -> str:
    """docs/qpp-certificates.md: the report's two examples searched over procedure 12.1's family
    (:mod:`qpp.design.family`): the bounds that hold for every design, then the grid of
    :data:`qpp.design.family.REPORT_GRIDS` and a local search from its best point
    (:func:`_family_search`, run with the stages): a table and one sentence per example."""
    rows, notes = [], []
    for name in REPORT_GRIDS:
        cfg = r[f"qpp_config:{name}"]
        b = family_bounds(cfg)
        fam = r[f"qpp_family:{name}"]
        cands, best, ref, n_ref = fam["candidates"], fam["best"], fam["refined"], fam["designs"]
        n_cert = sum(c.certified for c in cands) + int(ref.certified)
        ws = ", ".join(fixed(w, 3) for w in b.servo_frequencies)
        sin = "—" if b.m_upper_sin is None else f"{fixed(b.m_upper_sin, 4)} (T ≥ {fixed(b.T_sin, 4)} s)"
        rows.append([f"`{name}`", f"{fixed(b.beta1_lower, 1)} (ω_k = {ws} rad/s; on the grid "
                     f"σ̄(T(jω_k)) ≥ {fixed(min(c.servo_gain for c in cands), 6)})",
                     f"{fixed(b.m_upper, 4)} (β_o = {sig(cfg.spheres.beta_o)}, β_i = {fixed(b.beta_i, 4)}, "
                     f"‖k ∘ C x0‖₂ = {fixed(b.y0_term, 4)})", sin, str(len(cands)), str(n_cert),
                     fixed(max(c.m for c in cands), 4), fixed(min(c.beta1 for c in cands), 4),
                     f"{fixed(best.m - best.beta1, 4)} (ρ = {sci(best.rho)}, w = {sig(best.ws[0])}, a = {sci(best.a)}, "
                     f"T = {fixed(best.T, 3)} s)",
                     f"{fixed(ref.m - ref.beta1, 4)} after {n_ref} designs (ρ = {sci(ref.rho)}, w = {sig(ref.ws[0])}, "
                     f"a = {sci(ref.a)}, T = {fixed(ref.T, 3)} s; β1 = {fixed(ref.beta1, 4)}, m = {fixed(ref.m, 4)})"])
        if b.excluded:
            notes.append(f"* `{name}`: **no design of the family is certified**, by the bounds alone: β1 ≥ "
                         f"{fixed(b.beta1_lower, 1)} > {fixed(b.m_upper, 4)} ≥ m for every ρ, w, a and T.")
        elif b.m_upper_sin is not None and b.m_upper_sin <= b.beta1_lower:
            pe = peak_exclusion(cfg)
            peak_note = ""
            if pe is not None and np.any(pe.excluded & (pe.times < b.T_sin)):
                first = float(np.min(pe.times[pe.excluded & (pe.times < b.T_sin)]))
                j = int(np.argmin(np.abs(pe.times - first)))
                gaps = [x for x in pe.open_below(b.T_sin) if x > first]
                below = pe.open_below(b.T_sin)
                below = below[below < first]
                peak_note = (f"; below it, the premise peak excludes every settling time from {fixed(first, 4)} s on"
                             + (f" but {', '.join(fixed(x, 4) for x in gaps)} s" if gaps else "")
                             + f" (the first pass's samples, {fixed(pe.times[1] - pe.times[0], 4)} s apart: γ∞ ≥ L(T) "
                             f"of every design settling at T against m(T) ≤ U(T), √T·L = "
                             f"{fixed(np.sqrt(first) * pe.gamma_lower[j], 4)} > U = {fixed(pe.m_upper[j], 4)} at "
                             f"T = {fixed(first, 4)} s), which leaves {below.size + len(gaps)} settling times "
                             f"(T ≤ {fixed(float(below.max()), 4)} s" + (" and the exceptions" if gaps else "") + ")")
                se = settle_exclusion(cfg, pe)
                if se is not None and np.any(se.excluded):
                    ex = se.excluded
                    k = int(np.argmin(np.where(ex, np.sqrt(se.times) * se.gamma_lower, np.inf)))
                    rest = se.open_times()
                    peak_note += (f"; of these, the premises contraction and peak together exclude {int(ex.sum())}, "
                                  f"from {fixed(float(se.times[ex].min()), 4)} s to {fixed(float(se.times[ex].max()), 4)} s "
                                  f"(β1 ≥ 1 < m keeps ‖y_o‖_{{L2[0, T]}} below ν_max(T) = "
                                  f"{fixed(float(se.nu_max[ex].min()), 4)} … {fixed(float(se.nu_max[ex].max()), 4)}, and "
                                  f"settling right after T then needs γ∞ ≥ L(T, ν): √T·L(T, ν_max) ≥ "
                                  f"{fixed(float(np.sqrt(se.times[k]) * se.gamma_lower[k]), 4)} (T = "
                                  f"{fixed(float(se.times[k]), 4)} s) > U(T, ν_max) = 1, every smaller ν covered by at "
                                  f"most {int(se.splits[ex].max())} intervals), which leaves {rest.size} settling times "
                                  f"open" + (f" ({', '.join(fixed(float(x), 4) for x in rest)} s)" if rest.size else ""))
                else:
                    peak_note += " open"
            notes.append(f"* `{name}`: no design with T ≥ {fixed(b.T_sin, 4)} s is certified (β1 ≥ "
                         f"{fixed(b.beta1_lower, 1)} ≥ {fixed(b.m_upper_sin, 4)} ≥ m){peak_note}; there, m ≤ "
                         f"{fixed(b.m_upper, 4)} leaves room, and the grid finds "
                         + ("**no** certified design" if n_cert == 0 else f"{n_cert} certified designs")
                         + f": m ≤ {fixed(max(c.m for c in cands), 4)} against β1 ≥ "
                         f"{fixed(min(c.beta1 for c in cands), 4)} on its {len(cands)} designs, and the local search "
                         f"from its best point ends at m − β1 = {fixed(ref.m - ref.beta1, 4)} (a search, not a proof).")
        if "beyond" in fam:
            c, rs = fam["beyond"], fam["resettled"]
            cmp_b, cmp_p = ("<" if c.beta1 < c.m else "≥"), ("≤" if c.peak <= 1.0 else ">")
            notes.append(f"* `{name}`, beyond the grid (`qpp.design.family.REPORT_CERTIFIED`): ρ = {sci(c.rho)}, w = "
                         f"{sig(c.ws[0])}, a = {sci(c.a)} settles at T = {fixed(c.T, 4)} s on the first pass's samples "
                         f"and is " + ("**certified** there" if c.certified else "**not** certified there")
                         + f": β1 = {fixed(c.beta1, 4)} {cmp_b} m = {fixed(c.m, 4)}, γ∞·max E/m = {fixed(c.peak, 3)} "
                         f"{cmp_p} 1" + (f", so no bound excludes the settling time {fixed(c.T, 4)} s" if c.certified else
                                         f" ({', '.join(c.failed)} fail)")
                         + f". The certificate's own samples at that T (up to 20 001 on [0, t_final]) put the same "
                         f"loop's settling time at {fixed(rs.T, 4)} s, where it is "
                         + ("certified too." if rs.certified else
                            f"not certified ({', '.join(rs.failed)} fail; β1 = {fixed(rs.beta1, 4)}, m = "
                            f"{fixed(rs.m, 4)}): the certificate covers [0, T], a horizon shorter than the loop's "
                            f"settling."))
    table = markdown_table(["example", "β1 ≥ (every design: T_ry = I at ω_k)", "m ≤ (every design, every T)",
                            "m ≤ for T ≥ π/(2ω)", "grid: designs (ρ, w, a; T = settling time)", "certified",
                            "largest m", "smallest β1", "largest m − β1", "refined from there (Nelder–Mead)"], rows)
    return table + "\n" + "\n".join(notes) + "\n"


def _block_qpp_reproduced(r: dict) -> str:
    """The qpp section's "Reproduced vs printed" table (ch. 13 SISO, ch. 14 manipulator)."""
    so, ma = _qpp_summary(r, "qpp_siso"), _qpp_summary(r, "qpp_manipulator")
    rows = [["SISO A_z (13.6), Table 14.1 A_z/B_z", "—", "rebuilt from printed gains, equal at printed precision"]]
    for lab, x, two in (("SISO K1, Kc", so, "[{}], [{}]"), ("manip. K1 / Kc", ma, "{} / {}")):
        d, pub, h = x["d"], x["d"]["published"], x["cfg"].hinf
        (k1, c1), (kc, cc), (hp, hc) = ((np.ravel(pub[k])[None, :], np.ravel(d[k])[None, :]) for k in ("K1", "Kc", "H"))
        rows.append([f"{lab} (ρ={sci(h.rho, 1)}, a={sci(h.a, 1)})", two.format(_printed(k1), _printed(kc)),
                     two.format(_gains(k1, c1, 2)[0], _gains(kc, cc, 2)[0])])
        rel = ", ".join(f"{sig(100 * v, 2)} %" for v in x["h_rel"])
        rows.append([f"{lab.split()[0]} H", _printed(hp), f"{_gains(hp, hc, 1)[0]} (rel. diff {rel})"])
    cfg_s, cfg_m = so["cfg"], ma["cfg"]
    rows.append(["m SISO / manip. (printed β3, β4)", f"{cfg_s.published.m:g} / {cfg_m.published.m:g}",
                 f"{fixed(so['m'], 5)} / {fixed(ma['m'], 5)}"])
    for lab, x, cfg in (("SISO", so, cfg_s), ("manip.", ma, cfg_m)):
        e, p = x["b1"]
        mark = ["(< m ✓)" if v <= x["m"] else "(> m ✗)" for v in (e, p)]
        rows.append([f"β1 {lab} (printed gains)", f"{cfg.published.beta1:g}",
                     f"eq 10.7: {fixed(e, 6)} {mark[0]}; printed B_z: {fixed(p, 6)} {mark[1]}"])
    T = cfg_s.spheres.T
    rows.append(["SISO β3", f"{cfg_s.published.beta3:g}",
                 f"0.05‖(sin 5t)_{T:g}‖₂ = {fixed(spheres.beta3_sinusoidal(0.05, 5.0, T), 6)}; with sin t (10.54): "
                 f"{fixed(spheres.beta3_sinusoidal(0.05, cfg_s.nonlinearity.omega, T), 6)}"])
    th = np.atleast_2d(so["d"]["thresholds"])
    rows.append(["SISO ‖(y_o)_T‖₂", "0.363", f"{fixed(th[1, 2] / 0.05, 4)} (designed gains)"])
    circ = []
    for x in (so, ma):
        c, sec = x["d"]["circle"], np.atleast_2d(x["d"]["sector"])
        hw = float(np.max(np.abs(sec)))
        circ.append(("pass" if int(x["d"]["attrs"]["circle_passed"]) else "FAIL", hw, hw * float(c["max_scale"])))
    rows.append(["circle criterion", "satisfied",
                 f"SISO {circ[0][0]}, sector [{fixed(-circ[0][1], 1)}, {fixed(circ[0][1], 1)}], largest half-width "
                 f"{sig(circ[0][2])}; manip. {circ[1][0]} for ±{circ[1][1]:g} (largest ±{sig(circ[1][2])})"])
    ss = so["sims"]
    rows.append(["SISO ‖y − y_o‖∞ (Δm = 0.05)", "< 0.094, < 0.16",
                 ", ".join(sig(ss[k]["error_inf"]) for k in ("step_offset", "sin10"))
                 + f" (sphere {cfg_s.spheres.beta_o:g} {'✓' if all(v['passed'] for v in ss.values()) else '✗'})"])
    ms = ma["sims"]
    rows.append(["manip. ‖y − y_o‖∞, M = " + "/".join(k[1:] for k in ms) + " kg", "0.006 m, 0.0015 rad (M = 45)",
                 " / ".join(sig(v["error_inf"], 2) for v in ms.values())
                 + f" (sphere {cfg_m.spheres.beta_o:g} {'✓' if all(v['passed'] for v in ms.values()) else '✗'})"])
    return markdown_table(["quantity", "printed", "reproduced"], rows)


#: plant / nonlinearity of the shipped examples (their configs' inputs, not results)
QPP_EXAMPLES = {
    "qpp_unstable": "poles +1, −2, r_o = sin 3t; f1 = 2y + (1.5 + dm) y sin t, \\|dm\\| ≤ 0.05, G = B",
    "qpp_saturation": "mass, damping 0.5, step r_o; f1 = −k sat(y, 0.5), k ∈ [3.8, 4.2]",
    "qpp_cubic2": "two coupled masses, 2 inputs/outputs, step + sin 2t; f1 = [−c y1³, 0], c ∈ [0.9, 1.1], "
                  "\\|y\\| ≤ 1",
}


def _path(values, fmt) -> str:
    """``a → b → c`` of the successive distinct values (first and last kept)."""
    return " → ".join(t for t, _ in itertools.groupby(map(fmt, values)))


def _block_qpp_examples(r: dict) -> str:
    """The worked example's table of the three shipped qpp examples (design path, certificate,
    simulated errors)."""
    rows = []
    for name, plant in QPP_EXAMPLES.items():
        d, sims = r[f"qpp_design:{name}"], r[f"qpp_sim:{name}"]
        it = np.atleast_2d(d["iterations"])          # rho, nu, a, T, delta, beta1, m, circle, certified
        cert = d["certificate"]
        ws = np.atleast_1d(cert["ws_scale"])
        final = it[np.flatnonzero(it[:, 8] == 1)[-1]] if np.any(it[:, 8] == 1) else it[-1]
        design = []
        for lab, col, fmt, unit in (("ρ", 0, lambda v: sig(v, 2), ""), ("T", 3, lambda v: sig(v, 3), " s"),
                                    ("a", 2, lambda v: sci(v, 1), "")):
            path = _path(it[:, col], fmt)
            kept = "" if path.endswith(fmt(final[col])) else f" (kept {fmt(final[col])})"
            design.append(f"{lab} {path}{unit}{kept}")
        if np.any(ws != 1.0):
            design.append("W_s = " + ("·".join(sorted({f"{w:g}" for w in ws})) + "·S_c"))
        ok = int(cert["certified"])
        b1, m = float(cert["beta1"]), float(cert["m"])
        beta_o = next(iter(sims.values()))["beta_o"]
        rows.append([f"`{name}`", plant, "; ".join(design),
                     f"{fixed(b1, 4)} {'≤' if b1 <= m else '>'} {fixed(m, 4)}" + ("" if ok else " (not certified)"),
                     ", ".join(sig(v["error_inf"], 2) for v in sims.values()) + f" ({beta_o:g})"])
    return markdown_table(["config", "plant / nonlinearity", "design (12.1): ρ, T, a along the iterations",
                           "β1 ≤ m", "‖y − y_o‖∞ per scenario (β_o)"], rows)


def _block_table1_tea(r: dict) -> str:
    """The Table 1 TEA bullet: MB3 and AC TEAs, their residuals, MB3's zero-bias roots and the
    largest pitch bias with an MB3 equilibrium."""
    def angles(t):
        return "(" + ", ".join(fixed(v, 2) for v in t.theta_deg) + ")°"

    teas = {k: table1_teas(r[f"config:{k}"]) for k in ("mb3", "ac")}       # the report's Table 1 numbers
    t, zero = {k: v[0] for k, v in teas.items()}, teas["mb3"][1]
    cfg = r["config:mb3"]
    inertia, n, wie = cfg.inertia.matrix(), cfg.orbit_rate, np.array([0.0, 4.0, 0.0])      # ft·lbf
    roots = tea.all_equilibria(inertia, n, np.zeros(3))
    other = [x for x in roots if np.max(np.abs(x.theta - zero.theta)) > 1e-6]
    try:        # no equilibrium: the largest pitch bias on the branch the continuation follows from LVLH
        tea.solve_tea(inertia, n, wie)
        fold = None
    except NoEquilibriumError:
        lam = tea.bias_fold(inertia, n, wie)
        fold = None if lam is None else lam * 4.0

    def bound(x):
        return "≤ " + sci(10.0 ** math.ceil(math.log10(max(x, 1e-16))), 1)     # 0: round-off level
    text = ("* **Table 1 TEA** (bias back-solved from eq 4.1 at the printed attitude, continuation branch):\n"
            f"  MB3 {angles(t['mb3'])}, residual {bound(t['mb3'].residual)} ft·lbf; "
            f"AC {angles(t['ac'])}, residual {bound(t['ac'].residual)} ft·lbf.\n"
            f"  MB3 with zero bias: {fixed(zero.theta_deg[1], 2)}° pitch")
    if other:
        text += (f" ({fixed(other[0].theta_deg[1], 2, sign=True)}° is the other principal-axis root, "
                 "`acmm tea mb3 --all`)")
    text += ".\n"
    text += ("  The 4 ft·lbf pitch bias of Wie et al. has " + (
        f"no MB3 equilibrium: largest pitch bias {sig(fold, 4)} ft·lbf.\n" if fold is not None
        else "an MB3 equilibrium.\n"))
    return text


def _block_claims(r: dict) -> str:
    """Claims 1 and 2 of ch. 6, the sector designs, the schedule along the path, the ±30 % sweep (a table)."""
    s_c, s_d = r["simulate:mb3"], r["simulate:mb3_decoupled"]
    first, late = peak_errors(s_c)
    rows = [
        ["1", "cross-inertia-free MB3 design (`mb3_decoupled`) on the nonlinear model",
         f"{h5_text(s_d['attrs']['verdict'])} at **{sig(s_d['attrs']['stop_time_orbits'], 2)} orbit**"],
        ["1", "fully coupled MB3 design (`mb3`)",
         f"{h5_text(s_c['attrs']['verdict'])} over {sig(s_c['orbits'][-1], 2)} orbits"],
        ["1", "its peak attitude error in the first orbit, roll / pitch / yaw",
         " / ".join(sig(v) for v in first) + "°"],
        ["1", "its peak attitude error after orbit 2, roll / pitch / yaw",
         " / ".join(sig(v) for v in late) + "°"],
    ]
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    dwell = np.diff(np.append(lv["start"], st["t"][-1])) / orbit
    pitch = np.degrees(lv["tea_estimate"][:, 1])
    steady = np.degrees(lv["steady_error"]).max(axis=0)
    pk = np.asarray(lv["peak_momentum"])
    rows += [
        ["2", f"stair-case MB3 → AC (`staircase`): {len(pk)} levels, pitch TEA "
              f"{sig(pitch[0])}° … {sig(pitch[-1], 2)}°, dwell {sig(dwell.mean())} orbits",
         f"{h5_text(st['attrs']['verdict'])} over {sig(st['orbits'][-1])} orbits"],
        ["2", "largest steady attitude error of a level, roll / pitch / yaw",
         " / ".join(sig(v, 2) for v in steady) + "°"],
        ["2", "peak CMG momentum per level (every integrator step)",
         f"{sig(pk.min())} … {sig(pk.max())} ft·lbf·s (AC level {sig(pk[-1])}; "
         f"limit {sig(cfg.actuators.momentum_limit)})"],
    ]
    d = r["design:staircase"]
    pa = d["schedule"]["path"]
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    margins = [float(np.min(r[f"design:{k}"]["sector_margin"])) for k in ("mb3", "ac", "staircase")]
    conds = [float(np.max(r[f"design:{k}"]["max_eig_condition"])) for k in ("mb3", "ac", "staircase")]
    rows += [
        ["sector", f"smallest sector margin of the MB3, AC and {len(d['sector_margin'])} stair-case design points "
                   f"({int(np.sum(d['level']))} levels and the table's nodes)",
         f"{fixed(min(margins))}n"],
        ["sector", "relative Riccati residual of the sector LQRs (scaled; MB3, AC and the stair-case's "
                   "pre-conditioning designs), decade above the largest",
         "≤ " + sci(10.0 ** math.ceil(math.log10(max(float(p["riccati_residual"]) for k in ("mb3", "ac", "staircase")
                                                      for p in r[f"design:{k}"]["points"].values()))), 1)],
        ["sector", "largest eigenvalue condition of A − BK (scaled): AC / MB3 / any stair-case point",
         f"{sci(conds[1])} / {sci(conds[0])} / {sci(conds[2])}"],
        ["schedule", f"largest Re λ of the scheduled loop over {mr.size} path TEAs", f"**{fixed(mr.max())}n**"],
        ["schedule", "worst sector margin along the path", f"{fixed(mg.min(), 2)}n"],
        ["schedule", "smallest disk margin α at the plant input", fixed(dm.min())],
    ]
    w = r["sweep"]
    counts = [(lab.upper(), *bounded_count(w, lab)) for lab in (h5_text(x) for x in np.atleast_1d(w["base_names"]))]
    rows.append(["ch. 7", "±30 % inertia element draws bounded with the fixed nominal gain "
                          "(`sweep_inertia30`)", ", ".join(f"{lab} **{ok}/{n}**" for lab, ok, n in counts)])
    return markdown_table(["claim", "quantity", "computed"], rows)


def _block_staircase_levels(r: dict) -> str:
    """Per-level statistics of the 130-orbit stair-case (``sim.h5: levels/*``), one row per level."""
    st, cfg = r["simulate:staircase"], r["config:staircase"]
    lv = st["levels"]
    orbit = 2 * np.pi / cfg.orbit_rate
    rows = [[str(k), sig(lv["start"][k] / orbit), fixed(np.degrees(lv["tea_estimate"][k, 1]), 1),
             " / ".join(sig(v, 2) for v in np.degrees(lv["steady_error"][k])), sig(lv["peak_momentum"][k])]
            for k in range(len(lv["start"]))]
    return markdown_table(["level", "start (orbit)", "θ2* (deg)", "steady \\|θ − θ̂*\\| roll / pitch / yaw (deg)",
                           "peak \\|h\\| (ft·lbf·s)"], rows, "rrrrr")


def _block_design_points(r: dict) -> str:
    """Per design point of the stair-case: sector margin, conditioning, robustness radius."""
    d = r["design:staircase"]
    n = r["config:staircase"].orbit_rate
    keys = sorted(d["points"])
    lmi = all("lmi" in d["points"][key] for key in keys)
    rows = []
    for k, name in enumerate(d["names"]):
        p = d["points"][keys[k]]
        row = [h5_text(name), fixed(np.degrees(d["tea"][k, 1]), 1), fixed(d["sector_margin"][k]),
               sci(d["max_eig_condition"][k]), sci(d["robustness_radius"][k]),
               sci(d["robustness_radius_elementwise"][k])]
        if lmi:
            row += [fixed(float(p["lmi"]["certified_margin"])), sci(float(p["lmi"]["random_radius"])),
                    sig(point_energy(p, n), 3)]
        rows.append(row + [sci(d["riccati_condition"][k])])
    head = ["point", "θ2* (deg)", "sector margin (n)", "eigenvalue condition (scaled)",
            "robustness radius ‖δK̃‖/‖K̃‖", "same, max \\|δK_ij/K_ij\\|"]
    if lmi:
        head += ["margin certified by X (n)", "radius (random re-check)", "energy"]
    head.append("κ_CARE of the pre-conditioning LQR" if lmi else "κ_CARE")
    return markdown_table(head, rows, "l" + "r" * (len(head) - 1))


def _block_schedule_path(r: dict) -> str:
    """The scheduled gain on the local loop along the path (``design.h5: schedule/path/*``)."""
    d = r["design:staircase"]
    sc, pa = d["schedule"], d["schedule"]["path"]
    th = np.degrees(np.asarray(pa["theta2"]))
    mr, mg, dm = (np.asarray(pa[k]) for k in ("max_real", "sector_margin", "disk_margin"))
    i = int(np.argmin(dm))
    form = h5_text(d["attrs"]["schedule_form"])             # (every scheduled design.h5 states it)
    rows = [["schedule form", "table look-up, K linear in θ2* between the design points" if form == "table"
             else "2nd-order polynomial in θ2*"]]
    if "refit_converged" in sc:
        rows += [
            ["least-squares fit before the refit: largest Re λ over the refit's "
             f"{int(sc['refit_n_tea'])} TEAs", f"{fixed(sc['refit_max_real_before'], 2, sign=True)}n"],
            ["converged quadratic (homotopy stages, Newton steps to the step tolerance)",
             f"{int(sc['refit_homotopy_stages'])}, {int(sc['refit_iterations'])}"]]
    rows += [
        ["largest Re λ of the scheduled local loop", f"**{fixed(mr.max())}n**"],
        ["worst sector margin", f"{fixed(mg.min(), 2)}n"],
        ["fraction of the path with every pole in the sector", fixed(np.mean(mg >= 0))],
        ["smallest disk margin α at the plant input (skew 0)",
         f"{fixed(dm[i])} at θ2* = {fixed(th[i], 1)}° (±{sig(pa['disk_gain_margin'][i], 2)} dB, "
         f"±{sig(np.degrees(pa['disk_phase_margin'][i]), 2)}°)"],
    ]
    if "refit_converged" in sc:
        rows.append(["largest RMS deviation of a refined polynomial from the LQR gains, / max\\|K_ij\\| "
                     "(`schedule/rel_residual`)", sig(np.max(sc["rel_residual"]), 2)])
    return markdown_table([f"along the path ({th.size} TEAs, {fixed(th[0], 1)}° … {fixed(th[-1], 1)}°)", "value"], rows)


def _block_dwell_certificate(r: dict) -> str:
    """The stair-case's dwell-time certificate (``design.h5: dwell/*``, :mod:`acmm.design.dwell`)."""
    g = r["design:staircase"]["dwell"]
    n = r["config:staircase"].orbit_rate
    dwell, tau = np.asarray(g["dwell"]), float(g["tau_star"])
    rows = [["levels (frozen closed loops: coupled model about each TEA, scheduled gain)", str(dwell.size + 1)],
            ["decay rate λ every admissible switching sequence is proved to keep (1/64 of the slowest level's)",
             f"{sig(float(g['decay_rate']) / n, 2)}n"],
            ["certified minimum dwell τ* (Geromel–Colaneri LMIs per level, switches both ways, bisection)",
             f"**{fixed(tau, 2)} orbit**"],
            ["shortest dwell of a level in the scenario", f"{fixed(dwell.min(), 2)} orbit"],
            ["verdict", "certified: every level is held at least τ*" if np.all(dwell >= tau) else "NOT certified"],
            ["TEA-step transient bound (certified ellipsoids): \\|u\\|, \\|h − h*\\|",
             f"{sig(np.max(g['u_bound']))} ft·lbf, {sig(np.max(g['h_bound']))} ft·lbf·s"]]
    return markdown_table(["dwell-time certificate (`acmm certify staircase`)", "value"], rows)


def _block_design_routes(r: dict) -> str:
    """The LQR route (sector LQR, the report's method) and the regional LMI route side by side at
    MB3 and AC: margin, conditioning, robustness, energy, fastest pole, and the ±30 % Monte Carlo
    and inertia-scaling margin of each fixed gain on the same draws."""
    def margin_range(sw, label, decimals=3):
        lo, hi = sw["margin"][f"{label}_down"], sw["margin"][f"{label}_up"]
        return f"{fixed(lo['limit'], decimals)} … {fixed(hi['limit'], decimals)}"

    rows = []
    for name, label in (("mb3", "MB3"), ("ac", "AC")):
        n = r[f"config:{name}"].orbit_rate
        for route, d, sw, base in (("sector LQR", r[f"design:{name}"], r["sweep"], name),
                                   ("regional LMI", r[f"design:{name}_lmi"], r["sweep_lmi"], f"{name}_lmi"),
                                   ("robust gain for the ±30 % family (from the LMI gain)",
                                    r[f"design:{name}_robust"], r["sweep_robust"], f"{name}_robust")):
            p = d["points"][sorted(d["points"])[0]]
            A, B, K = (np.asarray(p[k]) for k in ("A", "B", "K"))
            fastest = float(np.max(-np.real(np.asarray(p["poles"])))) / n
            rr = (float(p["lmi"]["random_radius"]) if "lmi" in p and "robust" not in p
                  else random_gain_radius(A, B, K, n))
            ok, tot = bounded_count(sw, base)
            if "robust" in p:
                # a nonsmooth search: its gain moves with the BLAS kernel (docs/reproducibility.md),
                # so only what stays to these digits under Haswell and Prescott is printed
                loose = "— (kernel-dependent)"
                rows.append([f"{label}, {route}", fixed(float(p["sector_margin"]), 1), loose, "— (outside)",
                             "— (outside)", loose, loose, f"{ok}/{tot}", margin_range(sw, base, 1)])
                continue
            inside = float(p["sector_margin"]) > 0          # a radius is the distance to leaving the sector
            rows.append([f"{label}, {route}", fixed(float(p["sector_margin"])), sig(float(p["max_eig_condition"]), 2),
                         sci(float(p["robustness_radius_elementwise"])) if inside else "— (outside)",
                         sci(rr) if inside else "— (outside)",
                         sig(point_energy(p, n), 3), fixed(fastest, 1), f"{ok}/{tot}",
                         margin_range(sw, base)])
    return markdown_table(["station, route", "margin (n)", "κ max", "radius (first order, elementwise)",
                           "radius (random re-check)", "energy", "fastest pole (n)", "±30 % bounded and settled",
                           "tolerated inertia scaling s"], rows)


def _block_robust_family(r: dict) -> str:
    """The robust route's family and per-plant certificates at MB3 and AC (``design.robust``), and
    its gain on the packaged sweep's draws: how many of them have an equilibrium connected to the
    design TEA, and how many of those stay bounded and settled."""
    rows = []
    for name, label in (("mb3", "MB3"), ("ac", "AC")):
        p = r[f"design:{name}_robust"]["points"]
        g = p[sorted(p)[0]]["robust"]
        decay = np.asarray(g["certified_decay"], float)
        cone = np.degrees(np.asarray(g["certified_cone"], float))
        verdict = case_column(r["sweep_robust"], f"{name}_robust", "verdict")
        folded = np.array(["folds" in x for x in case_column(r["sweep_robust"], f"{name}_robust", "reason")])
        # (two digits of the decay and whole degrees: what stays under another BLAS kernel)
        rows.append([label, str(decay.size), f"{sig(float(decay.min()), 2)}n",
                     f"{fixed(float(cone.max()), 0)}°", f"{int(np.sum(np.asarray(g['sector_held'])))}/{decay.size}",
                     f"{int(np.sum(~folded))}/{folded.size}",
                     f"{int(np.sum(verdict[~folded] == 'bounded'))}/{int(np.sum(~folded))}",
                     f"{int(np.sum(verdict == 'bounded'))}/{verdict.size}"])
    return markdown_table(["station", "plants in the family", "decay every plant is certified to keep",
                           "cone every plant is certified in", "plants certified in the sector",
                           "packaged draws with an equilibrium connected to the design TEA",
                           "of those, bounded and settled", "all draws bounded and settled"], rows)


def _block_staircase_routes(r: dict) -> str:
    """The packaged stair-case and its variants (:data:`STAIRCASE_VARIANTS`), each judged on a
    1 001-TEA path: path stability and sector, disk margin, the point designs' conditioning,
    robustness and energy, the nonlinear run's peak CMG momentum and the dwell-time certificate."""
    labels = {"staircase": "regional LMI points, table (packaged)",
              "staircase_lqr": "sector LQR points (the report's route), table",
              "staircase_lqr_quadratic": "sector LQR points, the report's quadratic by least squares (ch. 5.3)",
              "staircase_quadratic": "regional LMI points, quadratic converged on the path's shifted LQR cost"}
    rows = []
    for name, label in labels.items():
        d = r[f"design:{name}"]
        x = route_numbers(d, r[f"simulate:{name}"], r[f"config:{name}"].orbit_rate)
        pa, sc = d["schedule"]["path"], d["schedule"]
        tau = "no certificate" if x["tau"] is None else f"{fixed(x['tau'], 2)} orbit" + (
            "" if np.all(np.asarray(d["dwell"]["dwell"]) > x["tau"]) else " (NOT certified)")
        refit = ""
        if "refit_converged" in sc and h5_text(sc["fit_method"]) == "shifted_lqr":
            refit = (f" (from the least-squares fit's {fixed(float(sc['refit_max_real_before']), 2, sign=True)}n; "
                     f"Re λ < −{fixed(float(sc['refit_decay']), 2)}n and the {fixed(float(sc['refit_cone_deg']), 0)}° "
                     "cone at " + f"{int(sc['refit_n_tea'])} TEAs; "
                     + ("Newton's method converged" if float(sc["refit_converged"]) else
                        "NOT converged: " + h5_text(sc["refit_message"])) + ")")
        peak = sig(x["peak"]) if x["peak"] is not None else f"diverged at orbit {fixed(x['stop'], 1)}"
        inside = int(np.sum(np.asarray(pa["sector_margin"]) >= 0))
        loop = [f"{fixed(np.max(pa['max_real']), sign=True)}n", f"{fixed(np.min(pa['sector_margin']), 2)}n ({inside})",
                fixed(np.min(pa["disk_margin"])), peak, tau]
        rows.append([label + refit, f"{np.asarray(pa['theta2']).size}", *loop[:3],
                     sig(x["kappa"], 2), sci(x["radius"]), sig(x["energy"], 3), *loop[3:]])
    return markdown_table(["stair-case (route, schedule)", "path TEAs", "largest Re λ on the path",
                           "worst sector margin on the path (TEAs with every pole in the sector)", "smallest disk margin", "κ max (points)",
                           "radius (first order, elementwise, min over points)", "energy (max over points)",
                           "peak \\|h\\| (ft·lbf·s)", "τ* (dwell 10.8 orbit)"], rows)


def _block_sweep_monte_carlo(r: dict) -> str:
    """Verdict counts of the ±30 % inertia Monte Carlo (``sweep_inertia30``, ``sweep.h5``), one row per base."""
    w = r["sweep"]
    base, draws = np.atleast_1d(w["base"]), np.atleast_1d(w["n_draws"])
    peak = np.degrees(np.atleast_2d(w["peak_attitude_error"]))
    rows = []
    for k, lab in enumerate(h5_text(x) for x in np.atleast_1d(w["base_names"])):
        sel = base == k
        v = case_column(w, lab, "verdict")
        nd = int(draws[sel].sum())
        ok = peak[sel][v == "bounded"]
        med = " / ".join(sig(x, 2) for x in np.median(ok, axis=0)) if ok.size else "—"
        rows.append([lab.upper(), str(v.size), f"**{int(np.sum(v == 'bounded'))}**",
                     *(str(int(np.sum(v == x))) for x in ("not_settled", "diverged", "no_equilibrium")),
                     f"{nd - v.size} ({100 * v.size / nd:.0f} % of draws physical)", med])
    return markdown_table(["base", "cases", "bounded", "not settled", "diverged", "no equilibrium",
                           "unphysical draws redrawn", "median peak error of the bounded, r / p / y (deg)"],
                          rows, "lrrrrrrr")


def _block_sweep_diverged(r: dict) -> str:
    """Where the diverged cases' plants have their equilibrium (``sweep.h5: tea_true``,
    ``tea_estimate``), one row per base."""
    w = r["sweep"]
    verdict = np.array([h5_text(x) for x in np.atleast_1d(w["verdict"])])
    base = np.atleast_1d(w["base"])
    rows = []
    for k, lab in enumerate(h5_text(x) for x in np.atleast_1d(w["base_names"])):
        sel = (base == k) & (verdict == "diverged")
        true = np.degrees(np.atleast_2d(w["tea_true"])[sel, 1])
        est = np.degrees(np.atleast_2d(w["tea_estimate"])[sel, 1])
        lo, hi = np.percentile(true, [5, 95])
        rows.append([lab.upper(), str(int(sel.sum())), f"{sig(lo, 2)}° … {sig(hi, 2)}°",
                     f"{sig(np.median(np.abs(true - est)), 2)}°",
                     f"{sig(np.min(np.atleast_1d(w['time_to_divergence'])[sel]), 2)}"])
    return markdown_table(["base", "diverged", "plant's pitch TEA (5–95 %)", "median \\|TEA − estimate\\| (pitch)",
                           "earliest divergence (orbit)"], rows, "lrrrr")


def _block_sweep_margin(r: dict) -> str:
    """The tolerated uniform inertia scaling of each fixed design (``sweep.h5: margin/*``)."""
    w = r["sweep"]
    mg, why = w["margin"], {"bounded": "not settled", "attitude": "diverged"}

    def reason(m):      # a failure's reason in a word or two
        text = h5_text(m["failure_reason"])
        return next((v for k, v in why.items() if text.startswith(k)), text)
    rows = []
    for lab in (h5_text(x) for x in np.atleast_1d(w["base_names"])):
        lo, hi = mg[f"{lab}_down"], mg[f"{lab}_up"]
        rows.append([lab.upper(), f"{fixed(lo['limit'])} … {fixed(hi['limit'])}",
                     f"{fixed(lo['first_failure'])} ({reason(lo)}) and {fixed(hi['first_failure'])} ({reason(hi)})"])
    return markdown_table(["design", "tolerated s", "first failure"], rows)


#: every generated block (each once, in README.md or one page of docs/), name → its function
BLOCKS = {"table1_tea": _block_table1_tea, "qpp_bullet": _block_qpp_bullet, "claims": _block_claims,
          "staircase_levels": _block_staircase_levels, "design_points": _block_design_points,
          "schedule_path": _block_schedule_path, "dwell_certificate": _block_dwell_certificate,
          "design_routes": _block_design_routes, "robust_family": _block_robust_family,
          "staircase_routes": _block_staircase_routes, "sweep_monte_carlo": _block_sweep_monte_carlo,
          "sweep_diverged": _block_sweep_diverged, "sweep_margin": _block_sweep_margin,
          "qpp_reproduced": _block_qpp_reproduced, "qpp_examples": _block_qpp_examples,
          "qpp_certificates": _block_qpp_certificates, "qpp_search": _block_qpp_search}
