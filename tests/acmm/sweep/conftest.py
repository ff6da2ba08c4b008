"""Helpers of the sweep tests: the data keys two sweep tables must agree on, and a chunked
sweep config run to its table and CSV bytes."""
from __future__ import annotations

import os

import numpy as np
import yaml

from acmm_qpp.results import read_h5
from acmm.sweep.run import run_sweep

from tests.conftest import CONFIGS

DATA_KEYS = ("case", "base", "index", "verdict", "verdict_code", "reason", "stable", "time_to_divergence",
             "peak_attitude_error", "steady_attitude_error", "peak_momentum", "torque_saturation_time",
             "momentum_saturation_time", "tea_true", "tea_estimate", "inertia", "bias", "n_draws")


def _assert_same_data(a: dict, b: dict):
    for k in DATA_KEYS:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert a["parameters"].keys() == b["parameters"].keys()
    for k in a["parameters"]:
        np.testing.assert_array_equal(a["parameters"][k], b["parameters"][k], err_msg=k)


def _cfg(tmp, name="chunks", n_runs=7):
    spec = {"base": str(CONFIGS / "ac.yaml"), "monte_carlo": {"inertia": {"percent": 10}},
            "n_runs": n_runs, "seed": 16, "orbits": 1.0,
            "margin": {"low": 0.8, "high": 1.25, "scan_points": 1, "rel_tol": 0.1}}
    p = tmp / f"{name}.yaml"
    p.write_text(yaml.safe_dump({"name": name, "sweep": spec,
                                 "output": {"root": str(tmp / "runs"), "figures": False}}))
    return p


def _run_bytes(path, **kw):
    r = run_sweep(path, **kw)
    data = read_h5(r.path)
    csv = (r.path.parent / "sweep.csv").read_bytes()
    os.replace(r.path, r.path.with_name(f"sweep_{len(os.listdir(r.path.parent))}.h5"))
    return data, csv
