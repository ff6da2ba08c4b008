"""Section Table 1: inertias and torque-equilibrium attitudes, printed vs computed."""
from __future__ import annotations

import numpy as np

from acmm.report.context import SectionWriter
from acmm.report.numbers import fmt_value
from acmm.report.ledger import status_text
from acmm.model import tea as tea_mod

TABLE1_PRINTED = {
    "mb3": {"I11": "23.22", "I22": "1.30", "I33": "23.23", "I12": "-0.023", "I13": "0.477", "I23": "-0.011",
            "tea": ("1.3", "-44.7", "2.1")},
    "ac": {"I11": "50.28", "I22": "10.80", "I33": "58.57", "I12": "-0.39", "I13": "0.16", "I23": "0.16",
           "tea": ("0.19", "-5.0", "0.56")},
}


#: the status of a Table 1 row that is an input of the configs (the inertias), not a computed number
INPUT_STATUS = "input (the config's value; not counted as matched)"


def table1_teas(cfg) -> tuple:
    """A station's TEA with its config's bias and with zero bias (eqs 4.1–4.3), the numbers Table 1
    and the README's Table 1 bullet show.

    Parameters
    ----------
    cfg : acmm.io.config.Config
        The station's config (MB3 or AC).

    Returns
    -------
    tuple
        (:class:`acmm.model.tea.TEA` with the config's bias, TEA with zero bias, (3,) array bias
        torque in ft·lbf); θ* in rad.
    """
    I = cfg.inertia.matrix()
    bias = tea_mod.resolve_bias(cfg.disturbance, I, cfg.orbit_rate)
    return (tea_mod.solve_tea(I, cfg.orbit_rate, bias, expected=cfg.disturbance.requested_tea()),
            tea_mod.solve_tea(I, cfg.orbit_rate, np.zeros(3)), bias)


def _build(ctx: SectionWriter) -> dict:
    """Part: Table 1 printed vs computed; returns ``{"mb3"/"ac": (TEA with the config's bias, zero-bias
    TEA, (3,) bias torque ft·lbf)}``, eqs 4.1–4.3, θ* in rad."""
    ctx.section("table1")
    ctx.doc.p("Table 1 of CR-185644 next to this run. The bias torque is not printed in the report: each "
              "config uses the bias back-solved from eq 4.1 at the printed attitude (bias_from_tea), and the "
              "TEA is then recomputed by continuation from LVLH (docs/ERRATA.md), so the computed TEA is an "
              "independent solve of eqs 4.1–4.3, not a copy. The zero-bias TEA shows how much of each "
              "attitude the inertia alone explains.")
    rows, teas = [], {}
    for name in ("mb3", "ac"):
        cfg = ctx.g.configs[name]
        pr = TABLE1_PRINTED[name]
        I = cfg.inertia.matrix()
        for key, (i, j) in zip(("I11", "I22", "I33", "I12", "I13", "I23"),
                               [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
            # an input (the config's value echoed back): shown, not counted among the printed
            # numbers this run computes and matches
            rows.append([name.upper(), f"{key} (10⁶ slug·ft²)", pr[key], f"{I[i, j] / 1e6:.4g}", "—",
                         INPUT_STATUS])
        teas[name] = table1_teas(cfg)
        t, t0, _ = teas[name]
        for a in range(3):
            pn = ctx.ledger_add("Table 1", f"{name.upper()} θ{a + 1}*", pr["tea"][a], t.theta_deg[a], "deg")
            rows.append([name.upper(), f"θ{a + 1}* (deg)", pr["tea"][a], f"{t.theta_deg[a]:+.4f}",
                         f"{t0.theta_deg[a]:+.3f}", status_text(pn)])
    ctx.doc.table(["config", "quantity", "printed", "computed", "zero-bias TEA", "status"], rows,
                  "Table 1: printed vs computed (TEA residual of eq 4.1 below 1e-12 ft·lbf)")
    brow = [[name.upper(), fmt_value(bias, "{:+.5f}"), f"{t.residual:.1e}",
             fmt_value(np.degrees(t.omega) * 3600, "{:+.4f}")] for name, (t, _, bias) in teas.items()]
    ctx.doc.table(["config", "bias used [roll, pitch, yaw] (ft·lbf)", "residual (ft·lbf)", "ω* (deg/h)"], brow,
                  "Bias torques used (back-solved from eq 4.1 at the printed TEA; not printed in the report)")
    return teas


#: this section's parts, rows of :data:`acmm.report.plan.PARTS`
PARTS = [("table1", "table1", _build, (), (), 0.1)]
