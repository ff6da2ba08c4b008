"""The report's errata evidence (issue 12): pure functions of explicit inputs that call the
library itself (TEA solver, linearization, Riccati solvers, the pipeline's sector design)."""
from __future__ import annotations

import re

import numpy as np
import pytest

from acmm.model import linearize as lin
from acmm.design import schedule
from acmm.design.settings import design_settings
from acmm.model import tea
from acmm.io.config import load_config
from acmm.report.sections import errata


@pytest.fixture(scope="module")
def mb3():
    cfg = load_config("mb3")
    I, n = cfg.inertia.matrix(), cfg.orbit_rate
    bias = tea.resolve_bias(cfg.disturbance, I, n)
    t = tea.solve_tea(I, n, bias)
    m = lin.design_point(I, t.theta, n, model="coupled", drf_mode=cfg.design.drf_mode)
    return cfg, I, n, t, bias, m


def _num(pattern, text):
    return float(re.search(pattern, text).group(1))


def test_kinematics_printed_f_violates_eq42_corrected_does_not(mb3):
    _, _, n, t, _, _ = mb3
    row = errata._kinematics_rows(t.theta, n)[0]
    assert row[0] == "eq 3.6 (1,1) entry"
    assert _num(r"rad/s at the MB3 TEA and (\S+) rad/s", row[3]) > 1e-5      # at (10°, −30°, 25°)
    assert _num(r"corrected f: (\S+) rad/s", row[3]) < 1e-12


def test_tea_rows_report_the_missing_equilibrium_of_the_4_ftlbf_bias(mb3):
    _, I, n, t, bias, _ = mb3
    rows = errata._tea_rows(I, n, tea.solve_tea(I, n, np.zeros(3)), bias)
    assert [r[0] for r in rows] == ["TEA roots (eqs 4.1–4.3)", "4 ft·lbf pitch bias (Wie et al. 1989)"]
    assert "no equilibrium" in rows[1][3] and _num(r"MB3 = (\S+) ft·lbf < 4", rows[1][3]) < 4


def test_design_on_is_the_pipelines_sector_design(mb3, monkeypatch):
    cfg, _, n, _, _, m = mb3
    seen = []
    real = schedule.sector_design

    def spy(A, B, scales, s):
        seen.append(s)
        return real(A, B, scales, s)

    assert errata.sector_design is real                # the pipeline's own function, imported
    monkeypatch.setattr(errata, "sector_design", spy)
    settings = design_settings(cfg)
    assert settings.orbit_rate == n
    text = errata._design_on(m.A, m.B, m, settings)
    assert seen == [settings]                         # R, Q0, sector and solver settings of the config
    margin = real(m.A, m.B, m.scales, settings).margin
    assert f"margin {margin:+.3f} n" in text and "stable on the true model" in text
    assert "UNSTABLE" in errata._design_on(m.A, -m.B, m, settings)


def test_riccati_rows_printed_sign_iteration_fails_corrected_converges(mb3):
    cfg, _, n, _, _, m = mb3
    rows = errata._riccati_rows(m, cfg.design, n)
    assert rows[0][0] == "eq 5.6 sign iteration" and "corrected form converges" in rows[0][3]
    assert "converged (unexpected)" not in rows[0][3]
    assert rows[1][0] == "state scaling"
