"""Errata evidence of Part III (ch. 10–14): the signs of 13.6 / Table 14.1, B_z, the ch. 11
weights, β3 (eq 10.54) and m, and the unknowns of ch. 14, as rows of the errata section
(:mod:`acmm.report.sections.errata`).
"""
from __future__ import annotations

import numpy as np

from acmm.report.numbers import fmt_value


def qpp_rows(s13, d13, a, beta3) -> list[list[str]]:
    """Part III: signs, B_z, ch. 11 weights, β3 and ch. 14 unknowns.

    Parameters
    ----------
    s13 : qpp.io.config.QppConfig
        The ch. 13 config.
    d13 : dict
        Its ``qpp_design.h5`` (read_h5 dict).
    a : qpp.io.config.QppConfig
        The ch. 14 config.
    beta3 : tuple of float
        Ch. 13 β3 with sin 5t and at the nonlinearity's frequency, output units.

    Returns
    -------
    list of list of str
        Table rows: item, printed / claim, correction used, evidence, confirming tests.
    """
    rows = []
    # Part III
    rows.append(["signs of 13.6 / Table 14.1", "u = +K x̂, L = −H; plant f sign differs (13.1/14.2 vs 10.1)",
                 "as docs/ERRATA.md", "A_z rebuilt from the printed gains equals 13.6 / Table 14.1",
                 "tests/qpp/model/test_lure.py"])
    b = {rd: float(d13[f"beta1_{rd.replace('.', '_')}"]) for rd in ("eq10.7", "printed")}
    rows.append(["B_z of 13.6 / Table 14.1", "H in the r-columns of the observer rows", "eq 10.7 (zeros); β1 "
                 "reported for both", f"ch. 13 β1 = {b['eq10.7']:.5f} (eq 10.7), {b['printed']:.5f} (printed B_z); "
                 f"printed 1.61454", "tests/qpp/design/test_spheres.py"])
    rows.append(["ch. 11 weights", "state weight [C 0]ᵀ[C 0]; Lyapunov 11.2 for the observer",
                 "servo weight [0 C_c]ᵀ[0 C_c]; filter Riccati H = −h Cᵀ",
                 f"ch. 13 K1 = {fmt_value(d13['K1'], '{:.1f}')}, Kc = {fmt_value(d13['Kc'], '{:.1f}')} (printed "
                 f"{fmt_value(s13.published.K1, '{:.1f}')}, {fmt_value(s13.published.Kc, '{:.1f}')})",
                 "tests/qpp/design/test_hinf.py"])
    b3_5, b3_1 = beta3
    th13 = np.atleast_2d(d13["thresholds"])
    rows.append(["β3 (10.54) and m", "β3 = 0.02727; half-width 0.05 in m, [−0.5, 0.5] in the circle check",
                 "β3 = 0.05‖(sin 5t)_T‖₂; both bookkeepings reported",
                 f"0.05‖(sin 5t)_T‖₂ = {b3_5:.5f} at T = 0.5 s; with sin t: {b3_1:.5f}; m = "
                 + ", ".join(f"{v[3]:.4f}" for v in th13) + " (printed, report, circle bookkeepings)",
                 "tests/qpp/design/test_spheres.py"])
    rows.append(["ch. 14 target and unknowns", "Y_A1, Y_A2 ambiguous; μ, impulse not printed",
                 "Y_A1 = (x1 + a) sin x2, Y_A2 = (x1 + a) cos x2; μ and impulse are config parameters",
                 f"μ = {a.nonlinearity.mu:g} kg, impulse {a.simulation.scenarios[0].impulse} at "
                 f"t = {a.simulation.scenarios[0].impulse_time} s", "tests/qpp/simulate/test_closed_loop.py"])
    return rows
