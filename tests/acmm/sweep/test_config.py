"""Sweep configs (acmm.sweep.config): the resolved sweep runs again as the same sweep, the work
limits apply at the sweep's own orbits, a bad sweep config is one line with exit 2."""
from __future__ import annotations

import pytest
import yaml

from acmm_qpp.errors import ConfigError
from acmm.sweep.config import load_sweep, parse_sweep

from tests.conftest import CONFIGS
from tests.acmm.conftest import _sweep_yaml


@pytest.mark.parametrize("name", ["sweep_smoke", "sweep_inertia30", "inline"])
def test_the_resolved_sweep_it_writes_runs_again_as_the_same_sweep(tmp_path, name):
    """``runs/<name>/config.yaml`` (and sweep.h5's ``config``) of a sweep is a sweep config itself:
    the same results key and text, no base file needed; a bad one is one line."""
    from acmm.cli.command import CONFIGS as KINDS

    if name == "inline":                    # a sweep section inside a run config
        data = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
        data["sweep"] = {"monte_carlo": {"inertia": {"percent": 10}}, "n_runs": 2}
        sw = parse_sweep(data, directory=CONFIGS)
    else:
        sw = load_sweep(name)
    resolved = yaml.safe_load(sw.to_yaml())
    assert KINDS.kind_of(resolved) == "sweep"
    again = parse_sweep(resolved, directory=tmp_path)          # no file next to it
    assert again.results_key() == sw.results_key() and again.to_yaml() == sw.to_yaml()
    assert [b.label for b in again.bases] == [b.label for b in sw.bases]
    for bad, words in (({**resolved, "extra": 1}, "extra: not a key"),
                       ({"sweep_file": resolved["sweep_file"]}, "bases: missing"),
                       ({**resolved, "bases": {"x": next(iter(resolved["bases"].values()))}}, "bases.x")):
        with pytest.raises(ConfigError, match=words) as exc:
            parse_sweep(bad)
        assert "\n" not in str(exc.value)


def test_the_per_run_sample_limit_applies_at_the_sweeps_own_orbits(tmp_path, monkeypatch):
    """Only the base's simulation.orbits was checked against SIM_SAMPLES (a review: 20 sweep
    orbits at 60 s samples ran under a limit of 1 000 that `acmm simulate` applies)."""
    monkeypatch.setenv("ACMM_LIMIT_SIM_SAMPLES", "1000")
    load_sweep(_sweep_yaml(tmp_path, "sl", orbits=5.0, margin=None))           # 476 samples per run
    with pytest.raises(ConfigError, match=r"sweep\.orbits: 20 orbits of ac .* output samples per run"):
        load_sweep(_sweep_yaml(tmp_path, "sl", orbits=20.0, margin=None))


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


@pytest.mark.parametrize("section", [
    {"monte_carlo": {"inertia": {"percent": 1}, "dI11": {"uniform": [0.5, 0.6]}}},
    {"monte_carlo": {"offset": {"uniform": [-1, 1]}, "offset_pitch": {"uniform": [-2, 2]}}},
])
def test_a_parameter_given_twice_is_refused(section):
    """A parameter given directly and through a shorthand: refused naming both (the later key
    used to win silently, both drawing random numbers)."""
    with pytest.raises(ConfigError, match="given twice"):
        parse_sweep({"name": "dup", "sweep": {"base": "mb3", "n_runs": 2, "orbits": 1, **section}})
