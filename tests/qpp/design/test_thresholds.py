"""The ch. 14 β3/β4 bookkeeping of the polar arm (qpp.design.thresholds)."""
import copy

import numpy as np
import pytest

from qpp.io.config import load_config, parse_config


def test_manipulator_beta3_beta4_bookkeeping():
    """β4 = 0.056 is reached along the trajectory for an arm mass μ* (φ = N(f1 − f1o), N = 10: μ* ≈ 1.19 kg;
    without N: μ* ≈ 30.4 kg), but β3 = ‖[∂φ/∂y1]_T‖₂ vanishes along any trajectory with x3 = 0:
    R/(μ+M) = x1 + aM/(μ+M) makes φ1 independent of x1 and φ2 ∝ x3 — so 0.018 is reached by none."""
    from qpp.design.thresholds import _arm_betas, nominal_output

    base = load_config("qpp_manipulator").model_dump(mode="json")
    p = base["published"]
    for mu, scale in ((1.1852, 1.0), (30.366, 0.1)):
        d = copy.deepcopy(base)
        d["nonlinearity"]["mu"] = mu
        cfg = parse_config(d)
        T = cfg.spheres.T
        t, _, x = nominal_output(cfg, p["K1"], p["Kc"], p["H"], T, 2001)
        b3, b4 = _arm_betas(cfg, t, x, T)
        assert scale * b4 == pytest.approx(0.056, abs=5e-4)
        assert b3 < 1e-6 < 0.018
        assert np.max(np.abs(x[2])) < 1e-6                    # x3 = ẋ1 stays 0 on the nominal path
