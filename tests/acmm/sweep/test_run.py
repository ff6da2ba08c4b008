"""Batch sweeps (issue 7): reproducible cases, physical perturbations, kill-and-resume, Dask,
and one-line config errors."""
from __future__ import annotations

import itertools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from acmm_qpp.errors import ConfigError
from acmm_qpp.results import read_h5
from acmm.sweep.cases import case_values, perturb_inertia, unphysical_reason
from acmm.sweep.run import run_sweep
from acmm.sweep.case import simulate_values, prepare_base
from acmm.sweep.cases import physical_mask
from acmm.sweep.config import load_sweep, parse_sweep

from tests.conftest import CONFIGS

DATA_KEYS = ("case", "base", "index", "verdict", "verdict_code", "reason", "stable", "time_to_divergence",
             "peak_attitude_error", "steady_attitude_error", "peak_momentum", "torque_saturation_time",
             "momentum_saturation_time", "tea_true", "tea_estimate", "inertia", "bias", "n_draws")


def _sweep_yaml(tmp: Path, name: str, sort_keys: bool = True, **over) -> Path:
    spec = {"base": str(CONFIGS / "ac.yaml"), "monte_carlo": {"inertia": {"percent": 10}},
            "n_runs": 6, "seed": 11, "orbits": 1.0}
    spec.update(over)
    data = {"name": name, "sweep": spec, "output": {"root": str(tmp / "runs"), "figures": False}}
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=sort_keys))
    return p


def _assert_same_data(a: dict, b: dict):
    for k in DATA_KEYS:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert a["parameters"].keys() == b["parameters"].keys()
    for k in a["parameters"]:
        np.testing.assert_array_equal(a["parameters"][k], b["parameters"][k], err_msg=k)


# --------------------------------------------------------------------------------------------
# case generation
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["sweep_smoke", "sweep_inertia30", "inline"])
def test_the_resolved_sweep_it_writes_runs_again_as_the_same_sweep(tmp_path, name):
    """``runs/<name>/config.yaml`` (and sweep.h5's ``config``) of a sweep is a sweep config itself:
    the same results key and text, no base file needed; a bad one is one line."""
    from acmm_qpp.configio import detect_kind

    if name == "inline":                    # a sweep section inside a run config
        data = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
        data["sweep"] = {"monte_carlo": {"inertia": {"percent": 10}}, "n_runs": 2}
        sw = parse_sweep(data, directory=CONFIGS)
    else:
        sw = load_sweep(name)
    resolved = yaml.safe_load(sw.to_yaml())
    assert detect_kind(resolved) == "sweep"
    again = parse_sweep(resolved, directory=tmp_path)          # no file next to it
    assert again.results_key() == sw.results_key() and again.to_yaml() == sw.to_yaml()
    assert [b.label for b in again.bases] == [b.label for b in sw.bases]
    for bad, words in (({**resolved, "extra": 1}, "extra: not a key"),
                       ({"sweep_file": resolved["sweep_file"]}, "bases: missing"),
                       ({**resolved, "bases": {"x": next(iter(resolved["bases"].values()))}}, "bases.x")):
        with pytest.raises(ConfigError, match=words) as exc:
            parse_sweep(bad)
        assert "\n" not in str(exc.value)


@pytest.mark.parametrize("kind", ["fifo", "dev_zero"])
def test_a_journal_that_is_not_a_regular_file_is_one_line_not_a_hang(tmp_path, kind):
    """--resume reads the journal: a FIFO there hung for ever, a symlink to /dev/zero filled the
    memory; both are one ConfigError now, the sweep's files as they were."""
    from acmm.sweep.journal import read_journal

    journal = tmp_path / "sweep.journal"
    if kind == "fifo":
        os.mkfifo(journal)
    else:
        journal.symlink_to("/dev/zero")
    with pytest.raises(ConfigError, match="not a regular file"):
        read_journal(journal, "key")


def test_unphysical_reason_agrees_with_config_validator():
    from pydantic import ValidationError

    from acmm.io.config_station import Inertia

    rng = np.random.default_rng(0)
    base = np.array([[23.22e6, -0.023e6, 0.477e6], [-0.023e6, 1.30e6, -0.011e6], [0.477e6, -0.011e6, 23.23e6]])
    seen = set()
    for _ in range(300):
        m = perturb_inertia(base, dict(zip(["dI11", "dI22", "dI33", "dI12", "dI13", "dI23"],
                                           rng.uniform(-0.6, 0.6, 6))))
        try:
            Inertia.model_validate(m.tolist())
            ok = True
        except ValidationError:
            ok = False
        assert (unphysical_reason(m) is None) == ok == physical_mask(m[None])[0]     # the pilot's twin
        seen.add(ok)
    assert seen == {True, False}      # both outcomes were exercised
    # a scale beyond the physical range (a review: inertia_scale 1e160 overflowed the redesign)
    for scale in (1e6, 1e160, 1e200):
        m = perturb_inertia(base, {"inertia_scale": scale})
        with pytest.raises(ValidationError):
            Inertia.model_validate(m.tolist())
        assert "physical range" in unphysical_reason(m) and not physical_mask(m[None])[0]


def test_case_draws_follow_seedsequence_contract(tmp_path):
    sw = load_sweep(_sweep_yaml(tmp_path, "draws", monte_carlo={"inertia_scale": {"uniform": [0.9, 1.1]},
                                                                "offset_pitch": {"normal": [0.0, 2.0]}}))
    inertias = sw.bases[0].config.inertia.matrix()[None]
    for i in (5, 0, 3):                                 # any order
        rng = np.random.default_rng(np.random.SeedSequence([11, i]))
        want = {"inertia_scale": rng.uniform(0.9, 1.1), "offset_pitch": rng.normal(0.0, 2.0)}
        got, draws, why = case_values(sw.spec, i, inertias)
        assert got == want and draws == 1 and why is None


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


@pytest.mark.parametrize("scale", [1.0, 0.8])
def test_case_metrics_are_taken_over_every_step_not_the_output_samples(scale):
    """A review: at the default 60 s samples (300 s in the stair-case) a case's peak momentum,
    steady error and saturation times came from the samples (a stair-case's peak |h| 3 986
    against 6 645 ft·lbf·s; a CMG saturation missed).  Reference: the same case sampled every
    second, its metrics computed here from the samples.  MB3, 3 orbits: nominal (bounded), and
    inertia ×0.8 (saturates and diverges)."""
    import dataclasses

    from acmm.simulate import kernel as sm
    from acmm.simulate import scenario as scen
    from acmm.io.config import load_config
    from acmm.stages.design import compute_design

    cfg = load_config(CONFIGS / "mb3.yaml")
    sc = scen.scenario_from_config(cfg, compute_design(cfg).table, orbits=3.0)
    sc = dataclasses.replace(sc, inertia=sc.inertia * scale)
    coarse = sm.simulate(dataclasses.replace(sc, sample_times=np.arange(0.0, sc.t_end, 120.0)))
    dense = sm.simulate(dataclasses.replace(sc, sample_times=np.arange(0.0, sc.t_end + 0.5, 1.0)))
    assert coarse.verdict == dense.verdict == ("bounded" if scale == 1.0 else "diverged")
    ext = coarse.run_extremes
    err = np.abs(dense.state[:, 3:6] - sc.theta_est[dense.level])
    np.testing.assert_allclose(ext.peak_momentum, np.abs(dense.state[:, 6:9]).max(axis=0), rtol=1e-4)
    dt = np.diff(dense.t)
    assert abs(ext.torque_saturation_time - dt @ dense.torque_saturated[:-1].any(axis=1)) <= 5.0       # s
    assert abs(ext.momentum_saturation_time - dt @ dense.momentum_saturated[:-1].any(axis=1)) <= 5.0
    if scale == 1.0:
        np.testing.assert_allclose(ext.peak_error, err.max(axis=0), rtol=2e-4)   # (diverged: the overshoot)
        # the window t >= t_end/2 opens mid-step (Hermite-interpolated there; the first 1 s sample
        # is 0.02 s later): the error still decays there
        np.testing.assert_allclose(ext.steady_error, err[dense.t >= sc.t_end / 2].max(axis=0), rtol=1e-4)
        old = np.abs(coarse.state[:, 3:6] - sc.theta_est[0])[coarse.t >= sc.t_end / 2].max(axis=0)
        assert np.max(ext.steady_error / old) > 1.005            # what the 120 s samples said
    else:
        assert ext.momentum_saturation_time > 600.0               # s: ~0.13 orbit at a CMG limit


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


def test_the_per_run_sample_limit_applies_at_the_sweeps_own_orbits(tmp_path, monkeypatch):
    """Only the base's simulation.orbits was checked against SIM_SAMPLES (a review: 20 sweep
    orbits at 60 s samples ran under a limit of 1 000 that `acmm simulate` applies)."""
    monkeypatch.setenv("ACMM_LIMIT_SIM_SAMPLES", "1000")
    load_sweep(_sweep_yaml(tmp_path, "sl", orbits=5.0, margin=None))           # 476 samples per run
    with pytest.raises(ConfigError, match=r"sweep\.orbits: 20 orbits of ac .* output samples per run"):
        load_sweep(_sweep_yaml(tmp_path, "sl", orbits=20.0, margin=None))


def test_the_margin_searches_stay_within_the_runs_counted_for_them(tmp_path):
    """The work bound counts the margin searches (acmm.sweep.limits.margin_evaluations): the searches
    actually run no more simulations than that."""
    from acmm.sweep.case import margin_search
    from acmm.sweep.limits import margin_evaluations

    for margin in ({"low": 0.5, "high": 2.0, "scan_points": 3, "rel_tol": 0.01},
                   {"low": 0.05, "high": 50.0, "scan_points": 1, "rel_tol": 1e-4}):
        sw = load_sweep(_sweep_yaml(tmp_path, "mw", n_runs=1, margin=margin, orbits=0.3))
        ctx = prepare_base(sw.bases[0], sw.spec)
        done = sum(len(margin_search(ctx, d)["evaluated_s"]) for d in ("up", "down"))
        assert 4 <= done <= margin_evaluations(sw.spec.margin)


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
    from acmm.model import tea
    from acmm.model.tea_compiled import solve_tea_connected     # checked against an independent path
                                                            # in tests/test_tea_compiled.py
    sc0 = ctx.scenario
    rows = [simulate_values(ctx, {"dI33": d}) for d in (-0.005, 0.0, 0.005)]
    assert [r["verdict"] for r in rows] == ["bounded"] * 3
    for d, r in zip((-0.005, 0.0, 0.005), rows):
        inertia = perturb_inertia(sc0.inertia[0], {"dI33": d})
        ref = solve_tea_connected(sc0.theta_est[0], sc0.inertia[0], sc0.bias[0], inertia, sc0.n, sc0.bias[0])
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
                         ctx.scenario.bias[0]).theta                     # the numpy continuation
    assert "design TEA's equilibrium folds" in row["reason"]
    np.testing.assert_allclose(row["tea_true"], np.degrees(lvlh), atol=1e-9)
    # I11 15 % larger: no equilibrium on either branch; the reason says the design's folded first
    row = simulate_values(ctx, {"dI11": 0.15})
    assert row["verdict"] == "no_equilibrium"
    assert row["reason"].startswith("the design TEA's equilibrium folds") and "continued from LVLH" in row["reason"]


# --------------------------------------------------------------------------------------------
# whole sweeps
# --------------------------------------------------------------------------------------------
def test_an_interrupted_rerun_does_not_sit_beside_the_earlier_runs_config_and_figures(tmp_path):
    """Seed A ran to the end (figures, config.yaml); seed B, interrupted, left its partial results
    beside A's config.yaml and figures (a review).  A sweep started afresh now writes its own
    config.yaml first and removes the earlier run's results and figures."""
    class _Stop(Exception):
        pass

    def stop(n_new):
        if n_new == 2:
            raise _Stop

    run_sweep(_sweep_yaml(tmp_path, "rerun", seed=1, margin=None), workers=1, figures=True)
    run = tmp_path / "runs" / "rerun"
    assert list(run.glob("sweep_*.png")) and "seed: 1" in (run / "config.yaml").read_text()
    with pytest.raises(_Stop):
        run_sweep(_sweep_yaml(tmp_path, "rerun", seed=2, margin=None), workers=1, figures=True,
                  after_record=stop, snapshot_interval=0.0)
    assert not list(run.glob("sweep_*.png"))
    assert "seed: 2" in (run / "config.yaml").read_text()
    if (run / "sweep.h5").exists():
        h = read_h5(run / "sweep.h5")
        assert not h["attrs"]["complete"] and "seed: 2" in h["attrs"]["config"]


def test_same_config_and_seed_give_identical_data_serial_and_pool(tmp_path):
    cfg = _sweep_yaml(tmp_path, "same", margin={"low": 0.8, "high": 1.25, "scan_points": 1, "rel_tol": 0.1})
    r1 = run_sweep(cfg, workers=1)
    a = read_h5(r1.path)
    os.replace(r1.path, tmp_path / "first.h5")
    r2 = run_sweep(cfg, workers=2)
    b = read_h5(r2.path)
    _assert_same_data(read_h5(tmp_path / "first.h5"), b)
    assert a["attrs"]["complete"] and a["attrs"]["n_cases_done"] == 6
    assert a["parameters"]["dI11"].shape == (6,) and a["peak_attitude_error"].shape == (6, 3)
    assert a["attrs"]["results_key"] == b["attrs"]["results_key"]
    # the stored inertia is the perturbation of the base inertia by the stored parameters
    base = parse_sweep(yaml.safe_load(cfg.read_text())).bases[0].config.inertia.matrix()
    for i in range(6):
        f = {k: a["parameters"][k][i] for k in a["parameters"]}
        np.testing.assert_allclose(a["inertia"][i], perturb_inertia(base, f), rtol=1e-15)
        assert unphysical_reason(a["inertia"][i]) is None
    # margin: the reported limit is bounded and the first failure (when found) is not
    for key, m in a["margin"].items():
        v = dict(zip(m["evaluated_s"], m["evaluated_verdict"]))
        assert v[m["limit"]] == b"bounded"
        if np.isfinite(m["first_failure"]):
            assert v[m["first_failure"]] != b"bounded"


class _Kill(Exception):
    pass


def test_interrupted_then_resumed_equals_uninterrupted(tmp_path):
    cfg = _sweep_yaml(tmp_path, "resume", n_runs=8)
    ref = read_h5(run_sweep(cfg, workers=1).path)

    def boom(n):
        if n == 3:
            raise _Kill
    with pytest.raises(_Kill):
        run_sweep(cfg, workers=1, after_record=boom)
    part = read_h5(tmp_path / "runs" / "resume" / "sweep.h5")
    assert not part["attrs"]["complete"] and part["attrs"]["n_cases_done"] == 3
    # a torn line left by a killed writer is ignored on resume
    with open(tmp_path / "runs" / "resume" / "sweep.journal", "a") as f:
        f.write('{"kind": "case", "base": "ac", "ind')
    r = run_sweep(cfg, workers=1, resume=True)
    assert r.n_resumed == 3 and r.n_new == 5
    _assert_same_data(ref, read_h5(r.path))
    # resuming a complete sweep runs nothing
    assert run_sweep(cfg, workers=1, resume=True).n_new == 0


def test_sigkill_then_resume_equals_uninterrupted(tmp_path):
    cfg = _sweep_yaml(tmp_path, "killed", n_runs=16, orbits=40.0)
    journal = tmp_path / "runs" / "killed" / "sweep.journal"
    proc = subprocess.Popen([sys.executable, "-c", "from acmm.cli.app import main; main()", "sweep", str(cfg),
                             "--workers", "1"], cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "MPLBACKEND": "Agg"})
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and journal.read_text().count('"kind": "case"') >= 3:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(10) == -signal.SIGKILL, "the sweep finished before it could be killed"
    n_before = journal.read_text().count('"kind": "case"')
    assert 3 <= n_before < 16
    r = run_sweep(cfg, workers=2, resume=True)
    assert r.n_resumed == n_before and r.n_new == 16 - n_before
    resumed = read_h5(r.path)
    os.replace(r.path, tmp_path / "resumed.h5")
    _assert_same_data(read_h5(run_sweep(cfg, workers=1).path), resumed)


def test_resume_refuses_a_journal_of_another_config(tmp_path):
    run_sweep(_sweep_yaml(tmp_path, "other", n_runs=2), workers=1)
    with pytest.raises(ConfigError, match=r"different sweep configuration.*\(changed since: sweep\.seed: \d+ → 12\)$"):
        run_sweep(_sweep_yaml(tmp_path, "other", n_runs=2, seed=12), workers=1, resume=True)


@pytest.mark.parametrize("section, a, b", [
    ("grid", {"dI11": [-0.05, 0.05], "bias_pitch": [-1.0, 1.0]}, {"bias_pitch": [-1.0, 1.0], "dI11": [-0.05, 0.05]}),
    ("monte_carlo", {"inertia": {"percent": 10}, "bias_pitch": {"uniform": [-1, 1]}},
     {"bias_pitch": {"uniform": [-1, 1]}, "inertia": {"percent": 10}})])
def test_resume_refuses_a_journal_whose_parameters_came_in_another_order(tmp_path, section, a, b):
    """The order of the parameters decides which values case i gets (the grid's product, the
    draws), but the results key hashed the config with sorted keys: resuming one order's journal
    with the other mixed the cases without a word (a review: one grid point twice, one never)."""
    over = {"monte_carlo": None, "n_runs": None} if section == "grid" else {"n_runs": 2}
    sa, sb = (load_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: x})) for x in (a, b))
    values = [[case_values(sw.spec, i, sw.bases[0].config.inertia.matrix()[None])[0] for i in range(2)]
              for sw in (sa, sb)]
    assert values[0] != values[1]                     # the orders give case 0 and 1 other values
    assert sa.results_key() != sb.results_key()
    run_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: a}), workers=1)
    with pytest.raises(ConfigError, match="different sweep configuration"):
        run_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: b}), workers=1, resume=True)


def test_resume_refuses_a_journal_of_an_earlier_case_model(tmp_path, monkeypatch):
    # a journal written before cases started at the design TEA's equilibrium (case model 1) must
    # not be completed with rows of the current model
    import acmm.sweep.config as sweep_config

    cfg = _sweep_yaml(tmp_path, "model", n_runs=2)
    monkeypatch.setattr(sweep_config, "CASE_MODEL", 1)
    run_sweep(cfg, workers=1)
    monkeypatch.setattr(sweep_config, "CASE_MODEL", 2)
    with pytest.raises(ConfigError, match="computed cases differently"):
        run_sweep(cfg, workers=1, resume=True)


def test_dask_local_cluster_gives_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed", reason="optional extra acmm-qpp[dask] not installed")
    cfg = _sweep_yaml(tmp_path, "dask", n_runs=4)
    ref = read_h5(run_sweep(cfg, workers=1).path)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        r = run_sweep(cfg, scheduler=cluster.scheduler_address)
    _assert_same_data(ref, read_h5(r.path))


def test_scheduler_without_distributed_is_a_one_line_error(tmp_path, run_acmm, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)      # import distributed -> ImportError
    cfg = _sweep_yaml(tmp_path, "nosched", n_runs=1)
    r = run_acmm("sweep", cfg, "--scheduler", "tcp://127.0.0.1:8786")
    assert r.exit_code == 2 and "acmm-qpp[dask]" in r.stderr and r.stderr.count("\n") == 1


# --------------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------------
def test_cli_smoke_sweep(tmp_runs, run_acmm):
    r = run_acmm("sweep", CONFIGS / "sweep_smoke.yaml", "--workers", "2")
    assert r.exit_code == 0, r.output
    d = tmp_runs / "runs" / "sweep_smoke"
    for f in ("sweep.h5", "sweep.csv", "sweep_map.png", "sweep_peak_error.png"):
        assert (d / f).is_file(), f
    lines = (d / "sweep.csv").read_text().splitlines()
    assert len(lines) == 1 + 8
    h = read_h5(d / "sweep.h5")
    assert h["peak_momentum"].shape == (8, 3)
    assert h["attrs"]["complete"]
    counts = json.loads(h["attrs"]["summary"])["ac"]
    assert sum(counts.values()) == 8
    assert f"ac: {counts['bounded']}/8 bounded" in r.stdout


@pytest.mark.parametrize("sweep, message", [
    ({"base": "ac", "monte_carlo": {"inertia": {"percent": 10}}, "n_runs": 2, "bogus": 1}, "sweep.bogus: unknown key"),
    ({"base": "ac", "monte_carlo": {"dI44": {"percent": 10}}, "n_runs": 2}, "unknown parameter 'dI44'"),
    ({"base": "ac", "monte_carlo": {"bias": {"percent": 10}}, "n_runs": 2}, "'percent' applies only"),
    ({"base": "ac", "monte_carlo": {"inertia": {"percent": 10}}}, "monte_carlo needs n_runs"),
    ({"base": "ac", "grid": {"inertia_scale": [1.0]}, "monte_carlo": {"dI11": {"percent": 1}}, "n_runs": 1},
     "exactly one of 'monte_carlo' or 'grid'"),
    ({"base": "nonexistent_base.yaml", "grid": {"inertia_scale": [1.0]}}, "config file not found"),
    ({"base": "ac", "grid": {"inertia_scale": [1.0, -0.5]}}, "inertia_scale must stay > 0"),
    ({"base": "ac", "monte_carlo": {"dI11": {"uniform": [0.1, -0.1]}}, "n_runs": 2}, "low must be"),
    # numpy cannot draw from a range whose width overflows (it was exit 3 with a journal left)
    ({"base": "ac", "monte_carlo": {"bias_pitch": {"uniform": [-1.7e308, 1.7e308]}}, "n_runs": 2},
     "sweep.monte_carlo.bias_pitch: uniform: high − low overflows"),
    # a YAML boolean is no count (it used to run one case)
    ({"base": "ac", "monte_carlo": {"inertia": {"percent": 10}}, "n_runs": True}, "sweep.n_runs: expected a number, got a boolean"),
    ({"base": "ac", "monte_carlo": {"inertia": {"percent": 10}}, "n_runs": 2, "seed": False}, "sweep.seed: expected a number, got a boolean"),
])
def test_bad_sweep_config_exits_2_with_one_line(tmp_runs, run_acmm, sweep, message):
    p = tmp_runs / "bad.yaml"
    p.write_text(yaml.safe_dump({"name": "bad", "sweep": sweep}))
    r = run_acmm("sweep", p)
    assert r.exit_code == 2
    assert message in r.stderr and r.stderr.count("\n") == 1 and "Traceback" not in r.output
    assert not (tmp_runs / "runs").exists()


def test_journal_record_checks(tmp_path):
    # what --resume accepts: the records a sweep writes (NaN and ±inf included); a line that is
    # JSON but not such a record is named, field by field, instead of failing in the table builder
    import json

    from acmm.sweep.journal_records import record_problem

    sw = load_sweep(_sweep_yaml(tmp_path, "rec", n_runs=2, orbits=0.2))
    run_sweep(sw, workers=1)
    lines = (sw.run_dir() / "sweep.journal").read_text().splitlines()[1:]
    recs = [json.loads(x) for x in lines]
    assert recs and all(record_problem(r, {"ac"}) is None for r in recs)
    case = next(r for r in recs if r["kind"] == "case")
    assert record_problem({**case, "time_to_divergence": float("inf")}) is None
    for bad, words in (({**case, "verdict": 123}, "malformed 'verdict'"), ({**case, "verdict": "fine"}, "unknown verdict"),
                       ({k: v for k, v in case.items() if k != "bias"}, "without 'bias'"),
                       ({**case, "inertia": [[1, 2, 3]] * 2}, "malformed 'inertia'"),
                       ({**case, "index": True}, "malformed 'index'"), ({**case, "kind": "x"}, "unknown record kind"),
                       ([1, 2], "not a record")):
        assert words in record_problem(bad, {"ac"})
    assert "base 'ac'" in record_problem(case, {"mb3"})
    # a record of a case the sweep does not have (a review: --resume gave 161 rows of 160)
    with open(sw.run_dir() / "sweep.journal", "a") as f:
        f.write(json.dumps({**case, "index": 99999}) + "\n")
    with pytest.raises(ConfigError, match=r"case 99999 of ac, which this sweep does not have"):
        run_sweep(sw, workers=1, resume=True)


@pytest.mark.parametrize("section", [
    {"monte_carlo": {"inertia": {"percent": 1}, "dI11": {"uniform": [0.5, 0.6]}}},
    {"monte_carlo": {"offset": {"uniform": [-1, 1]}, "offset_pitch": {"uniform": [-2, 2]}}},
])
def test_a_parameter_given_twice_is_refused(section):
    """A parameter given directly and through a shorthand: refused naming both (the later key
    used to win silently, both drawing random numbers)."""
    with pytest.raises(ConfigError, match="given twice"):
        parse_sweep({"name": "dup", "sweep": {"base": "mb3", "n_runs": 2, "orbits": 1, **section}})


def test_a_fifo_in_place_of_design_h5_is_designed_again_not_a_hang(tmp_path, monkeypatch):
    """``acmm simulate`` reuses ``design.h5`` when it matches: a FIFO (or a device) there used to
    block it for ever; it is not a design file, so the stage designs again and replaces it."""
    from acmm.io.config import load_config
    from acmm.stages.design import design_for

    monkeypatch.chdir(tmp_path)
    cfg = load_config("mb3", ["output.figures=false"])
    run = cfg.run_dir()
    run.mkdir(parents=True)
    os.mkfifo(run / "design.h5")
    table, note = design_for(cfg)
    assert note.startswith("designed") and (run / "design.h5").is_file()
    assert design_for(cfg)[1].startswith("reused")


def test_a_full_disk_under_the_journal_names_the_journal(tmp_path):
    """A full disk gave "I/O error: No space left on device" without a file (a review, on a
    20 kB tmpfs)."""
    import errno

    from acmm.sweep.journal import GroupCommitJournal
    from acmm_qpp.errors import OutputError

    class _Full:
        closed = False

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        flush = close = lambda self: None

    j = GroupCommitJournal(tmp_path / "sweep.journal", "key", fresh=True)
    j._f.close()
    j._f = _Full()
    with pytest.raises(OutputError, match=r"cannot write the sweep journal .*sweep\.journal: No space left"):
        j.append({"kind": "case"})


def test_an_empty_scheduler_address_is_refused_not_run_locally(tmp_runs, run_acmm):
    """`--scheduler ""` ran the sweep on local processes without a word (a review)."""
    r = run_acmm("sweep", "sweep_smoke", "--scheduler", "", "sweep.n_runs=2")
    assert r.exit_code == 2 and r.output.strip().startswith("error: --scheduler: an empty address"), r.output
    assert not (tmp_runs / "runs").exists()


def test_orbits_are_defined_per_case_when_bases_differ_in_orbit_rate(tmp_path):
    """With bases of different orbit rates the unit 'orbit' had no definition in sweep.h5 (a
    review): each case's orbit is now its base's period (orbit_period, s), and the datasets in
    orbits say so; with one rate the pint definition is there as before."""
    data = yaml.safe_load((CONFIGS / "ac.yaml").read_text())
    data.update(name="ac_slow", orbit_rate=0.001)
    (tmp_path / "ac_slow.yaml").write_text(yaml.safe_dump(data))
    p = _sweep_yaml(tmp_path, "rates", monte_carlo=None, n_runs=None, grid={"dI11": [0.0]}, orbits=0.1)
    d = yaml.safe_load(p.read_text())
    d["sweep"].pop("base")
    d["sweep"]["bases"] = [str(CONFIGS / "ac.yaml"), str(tmp_path / "ac_slow.yaml")]
    p.write_text(yaml.safe_dump(d))
    h = read_h5(run_sweep(load_sweep(p), workers=1).path)
    rates = [load_sweep(p).bases[int(b)].config.orbit_rate for b in h["base"]]
    np.testing.assert_allclose(h["orbit_period"], 2 * np.pi / np.array(rates), rtol=1e-15)
    import h5py

    with h5py.File(tmp_path / "runs" / "rates" / "sweep.h5") as f:
        attrs = f["time_to_divergence"].attrs
        assert "units_definition" not in attrs and attrs["units_per_case"] == "orbit = orbit_period[case] * s"


def test_workers_and_a_scheduler_together_are_refused(tmp_runs, run_acmm):
    """-j was silently ignored beside --scheduler (a review)."""
    r = run_acmm("sweep", "sweep_smoke", "-j", "2", "--scheduler", "tcp://127.0.0.1:1", "sweep.n_runs=2")
    assert r.exit_code == 2 and r.output.strip().startswith("error: --workers and --scheduler: give one"), r.output
