"""Fixtures and helpers of the qpp tests: the packaged ch. 13 and ch. 14 configs (``siso``,
``arm``) and their published gains (``_pub``), a packaged config as a dict writing into a test's
folder (``_cfg``), and a small user plant with an expression nonlinearity (``_base``)."""
import numpy as np
import pytest

from qpp.io.config import load_config


@pytest.fixture(scope="module")
def siso():
    return load_config("qpp_siso")


@pytest.fixture(scope="module")
def arm():
    return load_config("qpp_manipulator")


def _pub(cfg):
    p = cfg.published
    return np.array(p.K1), np.array(p.Kc), np.array(p.H)


def _cfg(name, tmp_path, **edits):
    d = load_config(name).model_dump(mode="json")
    d["output"] = {"root": str(tmp_path / "runs"), "figures": False}
    for k, v in edits.items():
        d[k] = v
    return d


def _base(**edits):
    data = {
        "name": "base",
        "plant": {"A": [[0, 1], [2, -1]], "B": [[0], [1]], "C": [[2, -1]], "G": [[0], [1]],
                  "Ac": [[0]], "Bc": [[1]], "Cc": [[1]]},
        "nonlinearity": {"kind": "expression", "f1": ["k*sat(y1, 0.5)"],
                         "parameters": {"k": {"min": -0.3, "max": 0.3, "nominal": 0.0}},
                         "y_range": [[-2, 2]]},
        "hinf": {"rho": 1e-2, "a": 1e-4, "search": True},
        "spheres": {"beta_o": 0.5, "beta_ri": 0.05, "T": 1.0},
        "design": {},
        "simulation": {"t_final": 10.0, "n_samples": 101, "r_o": [[{"kind": "step", "amplitude": 0.3}]],
                       "scenarios": [{"name": "kmax", "parameters": {"k": 0.3}}]},
        "output": {"root": "runs", "figures": False},
    }
    for path, value in edits.items():
        node = data
        keys = path.split(".")
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value
    return data
