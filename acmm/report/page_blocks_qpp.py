"""The qpp numbers README.md and the guide quote (ch. 13–14 and the shipped examples): the
reproduced-vs-printed table, the bullet of "What the tool reproduces", the examples, the
certificates and the search over procedure 12.1's family, each a block of text from the stages'
results (:mod:`acmm.report.page_runs`) with the report's formatting (:mod:`acmm.report.numbers`).
"""
from __future__ import annotations

import numpy as np

from acmm.report.numbers import fixed, markdown_table, sci, sig
from acmm.report.page_runs import QPP_CONFIGS
from qpp.design import spheres
from qpp.design.family import REPORT_GRIDS, family_bounds, peak_exclusion, settle_exclusion


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
    hp = np.ravel(pub["H"])
    rel = np.ravel(pub["H_rel_diff"])[hp != 0]
    m = float(np.atleast_2d(d["thresholds"])[0, 3])          # printed β3, β4 (row 0: printed bookkeeping)
    return {"d": d, "cfg": cfg, "sims": sims, "k_ok": k_ok, "h_rel": rel, "m": m,
            "b1": (float(pc["beta1_eq10_7"]), float(pc["beta1_printed"]))}


def block_qpp_bullet(r: dict) -> str:
    """The QPP bullet of "What the tool reproduces": gains, H, m, β1 and the spheres of ch. 13, 14.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        One Markdown bullet.
    """
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


def block_qpp_certificates(r: dict) -> str:
    """docs/qpp-certificates.md: per packaged qpp config, the report's bookkeeping (a reproduction)
    beside the consistent certificate (one sector, the Euclidean norm) and its verdict.

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
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


def block_qpp_search(r: dict) -> str:
    """docs/qpp-certificates.md: the report's two examples searched over procedure 12.1's family
    (:mod:`qpp.design.family`): the bounds that hold for every design, then the grid of
    :data:`qpp.design.family.REPORT_GRIDS` and a local search from its best point
    (:func:`acmm.report.page_runs.family_search`, run with the stages).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages` (the qpp configs ``"qpp_config:<name>"`` and
        their searches ``"qpp_family:<name>"``).

    Returns
    -------
    str
        A Markdown table and one sentence per example.
    """
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


def block_qpp_reproduced(r: dict) -> str:
    """The qpp section's "Reproduced vs printed" table (ch. 13 SISO, ch. 14 manipulator).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
    so, ma = _qpp_summary(r, "qpp_siso"), _qpp_summary(r, "qpp_manipulator")
    rows = [["SISO A_z (13.6), Table 14.1 A_z/B_z", "—", "rebuilt from printed gains, equal at printed precision"]]
    for lab, x in (("SISO K1, Kc", so), ("manip. K1 / Kc", ma)):
        d, pub, h = x["d"], x["d"]["published"], x["cfg"].hinf
        if lab.startswith("SISO"):
            pr = f"[{_printed(pub['K1'])}], [{_printed(pub['Kc'])}]"
            co = f"[{_gains(pub['K1'], d['K1'], 2)[0]}], [{_gains(pub['Kc'], d['Kc'], 2)[0]}]"
        else:
            pr = f"{_printed(np.ravel(pub['K1'])[None, :])} / {_printed(np.ravel(pub['Kc'])[None, :])}"
            co = (f"{_gains(np.ravel(pub['K1'])[None, :], np.ravel(d['K1'])[None, :], 2)[0]} / "
                  f"{_gains(np.ravel(pub['Kc'])[None, :], np.ravel(d['Kc'])[None, :], 2)[0]}")
        rows.append([f"{lab} (ρ={sci(h.rho, 1)}, a={sci(h.a, 1)})", pr, co])
        hp, hc = np.ravel(pub["H"])[None, :], np.ravel(d["H"])[None, :]
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
    out = []
    for v in values:
        t = fmt(v)
        if not out or out[-1] != t:
            out.append(t)
    return " → ".join(out)


def block_qpp_examples(r: dict) -> str:
    """The worked example's table of the three shipped qpp examples (design path, certificate,
    simulated errors).

    Parameters
    ----------
    r : dict
        :func:`acmm.report.page_runs.run_stages`.

    Returns
    -------
    str
        A Markdown table.
    """
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
