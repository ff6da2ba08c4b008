"""One case of a sweep (acmm.sweep.case): the unperturbed case is the plain simulation, a failed
redesign and a missing equilibrium are verdicts, a case starts at the equilibrium connected to the
design TEA, the margin searches stay within their work bound."""
from __future__ import annotations

import itertools

import numpy as np
import yaml

from acmm_qpp.results import read_h5
from acmm.model.inertia import perturb_inertia
from acmm.sweep.cases import case_values
from acmm.sweep.run import run_sweep
from acmm.sweep.case import prepare_base, simulate_values
from acmm.sweep.config import load_sweep

from tests.conftest import CONFIGS
from tests.acmm.conftest import _sweep_yaml


def test_grid_order_and_unperturbed_case_equals_plain_simulation(tmp_path):
    from acmm.simulate import kernel as sm
    from acmm.simulate import scenario as scen
    from acmm.io.config import load_config
    from acmm.stages.design import compute_design

    sw = load_sweep(_sweep_yaml(tmp_path, "grid", monte_carlo=None, n_runs=None,
                                grid={"inertia_scale": [1.0, 0.9], "offset_pitch": [0.0, 1.0, -1.0]}))
    assert sw.spec.n_cases() == 6
    inertias = sw.bases[0].config.inertia.matrix()[None]
    got = [case_values(sw.spec, i, inertias)[0] for i in range(6)]
    want = [{"inertia_scale": s, "offset_pitch": o} for s, o in itertools.product([1.0, 0.9], [0.0, 1.0, -1.0])]
    assert got == want
    # case 0 perturbs nothing: it must reproduce the ordinary simulation of the base config
    cfg = load_config(CONFIGS / "ac.yaml")
    r = sm.simulate(scen.scenario_from_config(cfg, compute_design(cfg).table, orbits=1.0))
    ctx = prepare_base(sw.bases[0], sw.spec)
    row = simulate_values(ctx, got[0])
    assert row["verdict"] == r.verdict == "bounded"
    # the same run, so the same extremes over every step; the samples see no more than the steps
    sampled_err = np.degrees(np.abs(scen.attitude_error(scen.scenario_from_config(cfg, ctx.table, orbits=1.0), r)))
    np.testing.assert_allclose(row["peak_attitude_error"], np.degrees(r.run_extremes.peak_error), rtol=0, atol=1e-9)
    np.testing.assert_allclose(row["peak_momentum"], r.run_extremes.peak_momentum, rtol=1e-12)
    assert np.all(np.array(row["peak_attitude_error"]) >= sampled_err.max(axis=0) - 1e-12)
    assert np.all(np.array(row["peak_momentum"]) >= np.abs(r.state[:, 6:9]).max(axis=0))


def test_a_redesign_that_fails_is_design_failed_and_an_impossible_scale_unphysical(tmp_path, monkeypatch):
    """A review: a case whose TEA is found but whose Riccati solve is refused was labelled
    tea_failed (then inertia_scale 1e5; since Riccati solutions are accepted on their backward
    error that station designs, so the refusal is injected here); 1e200 overflowed in the sector
    LQR and ended the whole sweep (exit 3)."""
    import acmm.design.riccati as ric
    from acmm_qpp.errors import ConvergenceError

    sw = load_sweep(_sweep_yaml(tmp_path, "rd", base=str(CONFIGS / "mb3.yaml"), monte_carlo=None, n_runs=None,
                                design="redesign", grid={"inertia_scale": [1e5, 1e200]}, orbits=0.1))
    base = prepare_base(sw.bases[0], sw.spec)

    def refused(*args, **kwargs):
        raise ConvergenceError("Riccati solve (method='scipy') failed: refused for the test")

    monkeypatch.setattr(ric, "solve_unverified", refused)
    rows = [simulate_values(base, v) for v in
            (case_values(sw.spec, i, sw.bases[0].config.inertia.matrix()[None])[0] for i in range(2))]
    assert rows[0]["verdict"] == "design_failed" and "Riccati" in rows[0]["reason"], rows[0]["reason"]
    assert rows[1]["verdict"] == "unphysical" and "physical range" in rows[1]["reason"]


def test_the_margin_searches_stay_within_the_runs_counted_for_them(tmp_path):
    """The work bound counts the margin searches (acmm.sweep.limits._margin_evaluations): the searches
    actually run no more simulations than that."""
    from acmm.sweep.case import margin_search
    from acmm.sweep.limits import _margin_evaluations

    for margin in ({"low": 0.5, "high": 2.0, "scan_points": 3, "rel_tol": 0.01},
                   {"low": 0.05, "high": 50.0, "scan_points": 1, "rel_tol": 1e-4}):
        sw = load_sweep(_sweep_yaml(tmp_path, "mw", n_runs=1, margin=margin, orbits=0.3))
        ctx = prepare_base(sw.bases[0], sw.spec)
        done = sum(len(margin_search(ctx, d)["evaluated_s"]) for d in ("up", "down"))
        assert 4 <= done <= _margin_evaluations(sw.spec.margin)


def test_an_si_sweeps_no_equilibrium_reason_gives_the_bias_in_n_m(tmp_path):
    """The reason of a no_equilibrium case printed the bias in ft·lbf only, next to a bias
    dataset in N·m (a review); it now gives both, and the N·m agree with the stored bias."""
    import re

    _sweep_yaml(tmp_path, "si", base=str(CONFIGS / "ac.yaml"), monte_carlo=None, n_runs=None,
                grid={"bias_pitch": [0.0, 40.0]}, orbits=0.2)
    text = (tmp_path / "si.yaml").read_text().replace("figures: false", "figures: false\n  units: SI")
    (tmp_path / "si.yaml").write_text(text)
    r = run_sweep(load_sweep(tmp_path / "si.yaml"), workers=1)
    h = read_h5(r.path)
    assert h["attrs"]["unit_system"] == "SI"
    k = [v.decode() for v in h["verdict"]].index("no_equilibrium")
    m = re.search(r"\(= \[([^]]*)\] N·m\)", h["reason"][k].decode())
    np.testing.assert_allclose([float(x) for x in m.group(1).split(",")], h["bias"][k], rtol=1e-3)


def test_no_equilibrium_is_a_verdict_not_a_crash(tmp_path):
    # docs/ERRATA.md § TEA: MB3's gravity-gradient pitch capacity is ≈ 1.73 ft·lbf, so +4 ft·lbf pitch bias has no TEA
    sw = load_sweep(_sweep_yaml(tmp_path, "noeq", base=str(CONFIGS / "mb3.yaml")))
    ctx = prepare_base(sw.bases[0], sw.spec)
    assert simulate_values(ctx, {"bias_pitch": 4.0})["verdict"] == "no_equilibrium"
    assert simulate_values(ctx, {"bias_pitch": 1.0})["verdict"] != "no_equilibrium"


def test_base_with_an_asked_tea_off_the_continuation_branch_stays_on_it(tmp_path):
    # MB3 asked to sit at +20° pitch (bias_from_tea): the continuation from LVLH ends at −19.4°;
    # the design is made about +20°, so the unperturbed case's plant is there too (not 39° from
    # the controller's estimate), a 1 % change of I22 stays within a degree of it, and the sweep's
    # nominal TEA says +20°
    base = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
    base["disturbance"]["bias_from_tea"] = [0.0, 20.0, 0.0]
    (tmp_path / "mb3_20.yaml").write_text(yaml.safe_dump(base))
    sw = load_sweep(_sweep_yaml(tmp_path, "asked", base=str(tmp_path / "mb3_20.yaml")))
    ctx = prepare_base(sw.bases[0], sw.spec)
    row = simulate_values(ctx, {})
    np.testing.assert_allclose(row["tea_true"], [0.0, 20.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(row["tea_estimate"], [0.0, 20.0, 0.0], atol=1e-9)
    near = simulate_values(ctx, {"dI22": 0.01})
    assert abs(near["tea_true"][1] - 20.0) < 1.0
    from acmm.sweep.output import _nominal_tea_deg

    np.testing.assert_allclose(_nominal_tea_deg(sw)[sw.bases[0].label], [0.0, 20.0, 0.0], atol=1e-9)


def test_a_case_starts_at_the_equilibrium_connected_to_the_design_tea(tmp_path):
    # MB3 (I11 ≈ I33) with I33 0.5 % smaller: the root continued from LVLH flips to +41.8° pitch,
    # 86° from the controller's estimate, and such a case used to diverge at once; the station
    # follows the design TEA's own equilibrium to −48.2° and the fixed design holds it
    sw = load_sweep(_sweep_yaml(tmp_path, "connected", base=str(CONFIGS / "mb3.yaml"), orbits=2.0))
    ctx = prepare_base(sw.bases[0], sw.spec)
    from acmm.model import tea      # solve_tea_connected: checked against an independent path
                                    # in tests/acmm/model/test_tea.py
    sc0 = ctx.scenario
    rows = [simulate_values(ctx, {"dI33": d}) for d in (-0.005, 0.0, 0.005)]
    assert [r["verdict"] for r in rows] == ["bounded"] * 3
    for d, r in zip((-0.005, 0.0, 0.005), rows):
        inertia = perturb_inertia(sc0.inertia[0], {"dI33": d})
        ref = tea.solve_tea_connected(sc0.theta_est[0], sc0.inertia[0], sc0.bias[0], inertia, sc0.n, sc0.bias[0])
        np.testing.assert_allclose(r["tea_true"], np.degrees(ref.theta), atol=1e-9)
        assert "LVLH" not in r["reason"]
    assert round(rows[1]["tea_true"][1], 1) == -44.7                     # MB3's TEA (report, Table 1)
    assert abs(rows[0]["tea_true"][1] - rows[1]["tea_true"][1]) < 5      # not the flipped +41.8°
    # AC with I11 20 % larger: the design TEA's branch folds before the perturbed plant, another
    # equilibrium exists (+24.5° pitch); the case starts there and its reason says why
    sw = load_sweep(_sweep_yaml(tmp_path, "folded", orbits=2.0))
    ctx = prepare_base(sw.bases[0], sw.spec)
    row = simulate_values(ctx, {"dI11": 0.2})
    lvlh = tea.solve_tea(perturb_inertia(ctx.scenario.inertia[0], {"dI11": 0.2}), ctx.scenario.n,
                         ctx.scenario.bias[0]).theta                     # the continuation from LVLH
    assert "design TEA's equilibrium folds" in row["reason"]
    np.testing.assert_allclose(row["tea_true"], np.degrees(lvlh), atol=1e-9)
    # I11 15 % larger: no equilibrium on either branch; the reason says the design's folded first
    row = simulate_values(ctx, {"dI11": 0.15})
    assert row["verdict"] == "no_equilibrium"
    assert row["reason"].startswith("the design TEA's equilibrium folds") and "continued from LVLH" in row["reason"]
