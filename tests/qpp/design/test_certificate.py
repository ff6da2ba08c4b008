"""What the certificate covers (qpp.design.certificate): the horizon T of a loop with nothing to
track or that never settles, a nonlinearity stiffer after T, a slow mode beyond the horizon."""
import numpy as np
import pytest
import yaml

from qpp.io.config import load_config


def _mass_on_integrator(name, f1, *, beta_o, step, delta_r=None):
    """A review's plant: a damped mass tracking a step of ``step`` through an integrator servo,
    φ = ``f1`` with k ∈ [−0.8, 0.8], β_ri = 0.004, simulated 8 s, one scenario at k = 0.8."""
    scenario = {"name": "kmax", "parameters": {"k": 0.8}, **({"delta_r": delta_r} if delta_r else {})}
    return {"name": name,
            "plant": {"A": [[0, 1], [0, -0.5]], "B": [[0], [1]], "C": [[1, 0]], "G": [[0], [1]],
                      "Ac": [[0]], "Bc": [[1]], "Cc": [[1]]},
            "nonlinearity": {"kind": "expression", "f1": [f1],
                             "parameters": {"k": {"min": -0.8, "max": 0.8, "nominal": 0}}, "y_range": [[-3, 3]]},
            "hinf": {"rho": 0.1, "a": 1.0e-4}, "spheres": {"beta_o": beta_o, "beta_ri": 0.004, "T": 1.0},
            "design": {"a_max": 1.0e-2, "rho_min": 0.05, "wider_search": False},
            "simulation": {"t_final": 8.0, "n_samples": 401, "r_o": [[{"kind": "step", "amplitude": step}]],
                           "scenarios": [scenario]},
            "output": {"root": "runs", "figures": False}}


def test_nothing_to_track_is_no_reason_for_a_vanishing_T(tmp_runs):
    """r_o ≡ 0: the nominal loop 'settles' at t = 0, T fell to 1e-3·t_final, β3 = k‖(1)_T‖₂ to ~0
    and a design was certified whose simulation leaves the output sphere (a review's case: k at
    the end of its range, ‖δr‖∞ = β_ri, ‖y − y_o‖∞ = 0.0072 > β_o = 0.006).  T is now the
    settling time of the loop's slowest mode: no certificate, and the simulation agrees."""
    import h5py
    from typer.testing import CliRunner

    from qpp.cli import app

    cfg = _mass_on_integrator("regulate", "k*y1", beta_o=0.006, step=0.0,
                              delta_r=[[{"kind": "sin", "amplitude": 0.004, "omega": 1.0}]])
    (tmp_runs / "reg.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "reg.yaml"])
    assert r.exit_code == 3 and "hint: no tracking loop meets these spheres" in r.output, r.output
    CliRunner().invoke(app, ["simulate", "reg.yaml"])
    with h5py.File(tmp_runs / "runs" / "regulate" / "qpp_design.h5") as f:
        certified, T = int(f.attrs["certified"]), float(f["certificate/T_settle"][()])
    with h5py.File(tmp_runs / "runs" / "regulate" / "qpp_sim.h5") as f:
        err = float(f["kmax/error_inf"][()])
    assert err > 0.006                        # the simulation leaves the sphere ...
    assert certified == 0, r.output           # ... so no certificate may claim it
    assert T > 1.0                            # the slowest mode's settling time, not 0.008 s


def test_a_nominal_loop_that_never_settles_is_named(tmp_runs):
    """A servo-compensator that does not model the step r_o (Ac = −1): the nominal loop never
    settles, T took the horizon and the certificate silently depended on t_final (review)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    plant = {"A": [[0, 1], [2, -1]], "B": [[0], [1]], "C": [[1, 0]], "G": [[0], [1]], "Ac": [[-1]],
             "Bc": [[1]], "Cc": [[1]]}
    cfg = {"name": "nosettle", "plant": plant,
           "nonlinearity": {"kind": "expression", "f1": ["-k*sat(y1, 0.5)"],
                            "parameters": {"k": {"min": 0.8, "max": 1.2}}, "y_range": [[-3, 3]]},
           "hinf": {"rho": 0.1, "a": 1.0e-4, "search": True},
           "spheres": {"beta_o": 0.3, "beta_ri": 0.05, "T": 1.0}, "design": {"a_max": 1.0e-2},
           "simulation": {"t_final": 5.0, "n_samples": 201, "r_o": [[{"kind": "step", "amplitude": 1.0}]],
                          "scenarios": [{"name": "kmin", "parameters": {"k": 0.8}}]},
           "output": {"root": "runs", "figures": False}}
    (tmp_runs / "ns.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "ns.yaml"])
    assert "warning: the nominal loop does not settle within 5 s" in r.output, r.output
    cfg["plant"]["Ac"] = [[0]]                        # an integrator models the step: it settles
    (tmp_runs / "ns.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "ns.yaml"])
    assert "does not settle" not in r.output, r.output


def test_a_nonlinearity_that_switches_on_after_T_is_named(tmp_runs):
    """φ = k·y·(sat(10(t − 3)) + 1)/2 is off on [0, T] and on after 3 s: β3 = β4 = 0 and a
    certificate that the simulation beyond T contradicted (26 β_o; review).  The design now warns
    that the certificate (on [0, T], eqs 10.53–10.54) does not reach beyond T; the ch. 13 form
    k·y·sin t warns only while [0, T] has not come near |sin t|'s peak (closed form)."""
    from typer.testing import CliRunner

    from qpp.cli import app
    from qpp.design.certificate import late_slope
    from qpp.io.config import load_config

    cfg = _mass_on_integrator("late", "k*y1*(sat(10*(t-3), 1) + 1)/2", beta_o=0.02, step=1.0)
    (tmp_runs / "late.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "late.yaml"])
    assert "warning: the nonlinearity is stiffer after T" in r.output, r.output
    before, after = late_slope(load_config(str(tmp_runs / "late.yaml")), 2.0, 8.0)
    assert before == pytest.approx(0.0, abs=1e-9) and after == pytest.approx(0.8, rel=1e-6)
    assert late_slope(load_config("qpp_unstable"), 2.0, 10.0) is None
    # ch. 13's k·|sin t| (k = 0.5): small on a short [0, T], 0.5 after it; on [0, 2 s] it has peaked
    siso = load_config("qpp_siso")
    assert late_slope(siso, 0.25, 10.0) == pytest.approx((0.5 * np.sin(0.25), 0.5), rel=1e-12)
    assert late_slope(siso, 0.25, 1.0) == pytest.approx((0.5 * np.sin(0.25), 0.5 * np.sin(1.0)), rel=1e-12)
    assert late_slope(siso, 1.0, 1.2) is None          # sin rises by less than half on (1, 1.2]
    assert late_slope(siso, 2.0, 10.0) is None


def test_a_slow_mode_beyond_the_horizon_is_named_with_nothing_to_track(tmp_runs):
    """r_o ≡ 0 on the ch. 13 loop: T is its slowest mode's settling time, ln 20/0.1005 = 29.8 s,
    beyond the 10 s horizon; the warning blamed the servo-compensator (review)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    import re

    import h5py

    r = CliRunner().invoke(app, ["design", "qpp_siso", "spheres.adapt_T=true",
                                 "simulation.r_o=[[{kind: step, amplitude: 0.0}]]"])
    said = re.search(r"the loop's slowest mode settles in ([0-9.]+) s", r.output)
    assert said and "plant.Ac" not in r.output, r.output
    # independent: ln(1/band)/min(−Re λ) of the stored closed loop, eigenvalues by numpy
    with h5py.File(tmp_runs / "runs" / "qpp_siso" / "qpp_design.h5") as f:
        decay = float(np.min(-np.linalg.eigvals(f["Az"][()]).real))
    assert float(said.group(1)) == pytest.approx(np.log(20.0) / decay, rel=1e-3)
    assert float(said.group(1)) > 10.0                        # beyond the 10 s horizon


# ----------------------------------------------------------------- the independent verifier (issue 33 item 3)
def _verified(tmp_path, cfg_dict):
    """Design through the CLI, then recompute the certificate with tests/qpp/independent_verifier.py."""
    from typer.testing import CliRunner

    from acmm_qpp.results import read_h5
    from qpp.cli import app
    from tests.qpp.independent_verifier import verify

    cfg_dict = {**cfg_dict, "output": {"root": str(tmp_path / "runs"), "figures": False}}
    path = tmp_path / f"{cfg_dict['name']}.yaml"
    path.write_text(yaml.safe_dump(cfg_dict))
    r = CliRunner().invoke(app, ["design", str(path), "--no-figures"])
    d = read_h5(tmp_path / "runs" / cfg_dict["name"] / "qpp_design.h5")
    v = verify(cfg_dict, d)
    tool = bool(d["attrs"]["certified"])
    assert r.exit_code == (0 if tool else 3), r.output
    assert tool == v["certified"], (r.output, v.get("premises"))
    if np.isfinite(v["beta1"]):
        assert d["certificate"]["beta1"] == pytest.approx(v["beta1"], rel=1e-6)
        # (on a sector narrower than φ's own the tool's m means nothing; the polar arm's sector is
        # the config's in both)
        if v["premises"]["sector"] or cfg_dict["nonlinearity"]["kind"] == "polar_arm":
            c = d["certificate"]
            # both m are proved lower bounds for every T' ∈ (0, T] (the tool's from its Picard
            # enclosure and cell sums, the verifier's from Van Loan's integrals and a series
            # remainder), each at most the trapezoid estimate of the verifier's LSODA samples
            assert v["m"] <= v["m_sampled"] * (1 + 1e-9)
            assert c["m"] <= v["m_sampled"] * (1 + 1e-5)
            assert c["m"] == pytest.approx(v["m"], rel=5e-4)      # (the gap of the tool's enclosure)
            assert c["beta3"] == pytest.approx(v["beta3"], rel=1e-3)
            assert c["beta4"] == pytest.approx(v["beta4"], rel=1e-3)
            assert c["peak_ratio"] == pytest.approx(v["peak"], rel=5e-4)
            if "rho_v" in v:                # the arm's rates' sphere, and its β3 over the sphere
                assert c["rho_v"] == pytest.approx(v["rho_v"], rel=1e-9)
        assert d["certificate"]["gamma_inf"] == pytest.approx(v["gamma_inf"], rel=1e-6)
    if cfg_dict["nonlinearity"]["kind"] == "expression":      # the verifier's own interval proofs ran
        assert "slope" in v["premises"] and "slope_proved" in v
    stored = {k[len("premise["):-1]: bool(int(x)) for k, x in d["attrs"].items() if k.startswith("premise[")}
    for k, ok in v.get("premises", {}).items():             # premise by premise, not only the verdict
        assert stored.get(k) == ok, (k, stored, v["premises"])
    for name, err in v.get("errors", {}).items():           # a certified design stays in its sphere
        assert err <= cfg_dict["spheres"]["beta_o"], (name, err)
    return tool, d, v


def _packaged(name):
    from configs import __file__ as cfgdir
    from pathlib import Path

    return yaml.safe_load((Path(cfgdir).parent / f"{name}.yaml").read_text())


@pytest.mark.parametrize("name", [
    "qpp_siso", pytest.param("qpp_saturation", marks=pytest.mark.slow),
    pytest.param("qpp_unstable", marks=pytest.mark.slow), pytest.param("qpp_cubic2", marks=pytest.mark.slow),
    pytest.param("qpp_manipulator", marks=pytest.mark.slow), pytest.param("qpp_siso_certified", marks=pytest.mark.slow)])
def test_independent_verifier_agrees_on_every_packaged_config(tmp_path, name):
    """The tool's verdict and premises, β1 (1e-6), the proved m (5e-4), β3, β4 (1e-3: the arm's over
    its sphere too), γ∞·max E/m (5e-4) and γ∞ equal the independent verifier's; every scenario of a
    certified design stays inside its output sphere on [0, T]."""
    tool, _, _ = _verified(tmp_path, _packaged(name))
    assert tool == (name in ("qpp_unstable", "qpp_saturation", "qpp_cubic2", "qpp_siso_certified"))


def test_a_stated_sector_narrower_than_phis_own_is_no_certificate(tmp_path):
    """design.sector = ±0.001 for ch. 13's φ = 10·Δm·y·sin t (|Δm| ≤ 0.05, so ±0.5): the circle
    criterion and β4 on that sector would prove nothing; the premise ``sector`` fails in the tool
    and in the verifier, which finds φ's sector itself."""
    cfg = _packaged("qpp_siso")
    cfg["name"] = "narrow"
    cfg["design"] = {**cfg.get("design", {}), "sector": [[-0.001, 0.001]]}
    tool, d, v = _verified(tmp_path, cfg)
    assert not tool and not v["premises"]["sector"]
    assert int(d["attrs"]["premise[sector]"]) == 0


def _issue_scalar():
    """The issue's scalar plant, G = B/10 (φ = N·γ·y·sin t, N = 10), report's bookkeeping."""
    return {"name": "issue_scalar",
            "plant": {"A": [[0, 1], [2, -1]], "B": [[0], [1]], "C": [[1, 0]], "G": [[0], [0.1]],
                      "Ac": [[0, 1], [-9, 0]], "Bc": [[0], [1]], "Cc": [[1, 0]]},
            "nonlinearity": {"kind": "sinusoidal", "F0": [[2.0]], "F1": [[1.5]], "F_unc": [[1.0]],
                             "omega": 1.0, "gamma_max": 0.05},
            "hinf": {"rho": 1.0e-4, "a": 1.0e-8},
            "spheres": {"beta_o": 0.2, "beta_ri": 0.1, "T": 0.5},
            "design": {"bookkeeping": "report", "sector": [[-0.5, 0.5]]},
            "simulation": {"t_final": 10.0, "n_samples": 1001, "r_o": [[{"kind": "sin", "amplitude": 1.0, "omega": 3.0}]],
                           "scenarios": [{"name": "s", "gamma": 0.05,
                                          "delta_r": [[{"kind": "step", "amplitude": -0.1}]]}]}}


def _issue_mimo():
    """The issue's 2×2 plant: an unstable pole (+0.5 on mass 1) and a saturation."""
    cfg = _packaged("qpp_cubic2")
    cfg["name"] = "issue_mimo"
    cfg["plant"]["A"] = [[0, 0, 1, 0], [0, 0, 0, 1], [0.5, 0.0, -0.2, 0], [0.0, -1, 0, -0.2]]
    cfg["nonlinearity"] = {"kind": "expression",
                           "f1": [{"form": "saturation", "output": 1, "gain": "-k", "level": 0.2}, "0"],
                           "parameters": {"k": {"min": 0.5, "max": 1.5, "nominal": 1.0}},
                           "y_range": [[-2.0, 2.0], [-2.0, 2.0]]}
    cfg["spheres"] = {"beta_o": 0.1, "beta_ri": 0.05, "T": 1.0}
    for sc, k in zip(cfg["simulation"]["scenarios"], (0.5, 1.5, 0.5)):
        sc["parameters"] = {"k": k}
    return cfg


@pytest.mark.slow
@pytest.mark.parametrize("make", [_issue_scalar, _issue_mimo])
def test_the_issues_two_cases_are_not_certified(tmp_path, make):
    """Issue 33: the scalar plant with G = B/10 under the report's bookkeeping, and a 2×2 plant with
    an unstable pole and a saturation: no certificate (exit 3), and the verifier agrees."""
    tool, _, _ = _verified(tmp_path, make())
    assert not tool


@pytest.mark.slow
def test_verifier_agrees_on_a_lightly_damped_and_an_impossible_plant(tmp_path):
    """A lightly damped mass (ζ = 0.02) with a saturating spring is certified with wide spheres;
    the same plant with β_o = β_ri/2 cannot be (β1 ≥ 1 for a loop that tracks), and the verifier
    agrees with both verdicts."""
    cfg = _packaged("qpp_saturation")
    cfg["name"] = "light"
    cfg["plant"]["A"] = [[0, 1], [-1, -0.04]]
    cfg["spheres"] = {"beta_o": 0.6, "beta_ri": 0.05, "T": 1.0}
    tool, _, _ = _verified(tmp_path, cfg)
    assert tool
    # (t_final 6 s: the 12 s of qpp_saturation met the design-work limit on this plant, its 26th
    # candidate at 5.2e4 of 5e4 — how many candidates the search tries moves with rounding)
    cfg = {**cfg, "name": "impossible", "spheres": {"beta_o": 0.025, "beta_ri": 0.05, "T": 1.0},
           "simulation": {**cfg["simulation"], "t_final": 6.0}}
    tool, _, _ = _verified(tmp_path, cfg)
    assert not tool


@pytest.mark.parametrize("feature", [pytest.param("WINDOW", marks=pytest.mark.slow), "SPIKE"])
def test_the_verifier_proves_premises_itself_on_features_narrower_than_its_grid(tmp_path, feature):
    """tests/qpp/model/test_sector_proof.py's features, which both samplings miss: φ/y doubles in a
    window of width 1e-7 (WINDOW: the sector and the slope refuted, ~20 s), the slope rises to 1.5×
    on 1e-9 while the sector stays intact (SPIKE: the sector proved — the verifier splits off the
    terms y divides, (k − 1)·y, and bounds the rest's ratio alone — and the slope refuted).  The
    tool's interval proofs and the verifier's own (mpmath iv in sympy's lambdify, its own bisection)
    agree premise by premise; contraction and peak are read, in both, with the sampled slopes the
    premise slope could not prove."""
    import tests.qpp.model.test_sector_proof as features

    cfg = _packaged("qpp_unstable")
    cfg["name"] = feature.lower()
    cfg["nonlinearity"]["f1"] = [getattr(features, feature)]
    cfg["nonlinearity"]["parameters"] = {"k": {"min": 0.95, "max": 1.05, "nominal": 1.0}}
    for s in cfg["simulation"]["scenarios"]:
        s["parameters"] = {"k": 1.05}
    tool, d, v = _verified(tmp_path, cfg)
    assert not tool and not v["premises"]["slope"]
    assert v["premises"]["sector"] == (feature == "SPIKE")
