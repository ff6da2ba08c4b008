"""Stations far from Space Station Freedom's size (``docs/ERRATA.md`` § Scaling): beyond the band
of :data:`acmm.model.linearize.MOMENTUM_BAND` the momentum scale and the torque unit of the solve follow
the station, so a station k times smaller — torques and limits k times smaller, R k² times larger — is the
same scaled problem: the same poles (in n), gains in proportion, the same PBH ratio.  With fixed
scales a 0.05 slug·ft² station was "uncontrollable" (PBH 3e-13) and 1e-5 of SSF had no
accurate Riccati solution."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.io.config import parse_config

N = 0.00115


def _station(k: float):
    return parse_config({
        "name": "scaled",
        "inertia": {"I11": 5e6 * k, "I22": 4e6 * k, "I33": 6e6 * k, "I12": 1e5 * k},
        "orbit_rate": N,
        "disturbance": {"bias": [0.1 * k, -0.2 * k, 0.1 * k], "A": [0, 0, 0], "B": [0, 0, 0]},
        "actuators": {"torque_limit": 1e5 * k, "momentum_limit": 1e6 * k},
        "design": {"R": 1e-4 / k ** 2},
        "output": {"figures": False},
    })


def _design(k):
    from acmm.design.design_core import design_schedule
    from acmm.design.schedule_points import point_specs
    from acmm.design.settings import design_settings

    cfg = _station(k)
    return design_schedule(point_specs(cfg), design_settings(cfg), None).points[0]


@pytest.fixture(scope="module")
def designs():
    return {k: _design(k) for k in (1e-4, 1e-8)}


def test_small_stations_design_and_are_the_same_scaled_problem(designs):
    from acmm.model.state_scaling import MOMENTUM_BAND, NOMINAL_ANGLE, NOMINAL_MOMENTUM

    a, b = designs[1e-4], designs[1e-8]
    for p, k in ((a, 1e-4), (b, 1e-8)):
        # both lie beyond the band (its natural momentum λmax(I)·n·0.01 below 1e-2 × 1000)
        assert 6e6 * k * 1.0001 * N * NOMINAL_ANGLE / NOMINAL_MOMENTUM < MOMENTUM_BAND[0]
        assert p.gain.margin > 0 and p.gain.riccati.residual < 1e-9
        poles = np.linalg.eigvals(p.model.A - p.model.B @ p.gain.K)       # re-checked here
        assert np.all(poles.real <= -0.5 * N * 0.999) and np.all(np.abs(poles.imag) <= np.abs(poles.real) * 1.001)
    np.testing.assert_allclose(np.sort_complex(a.gain.poles / N), np.sort_complex(b.gain.poles / N),
                               rtol=0, atol=1e-4)   # a mirrored cluster: ill-conditioned poles
    # u ∝ k; rates and angles unchanged, momentum and its integral ∝ k: K·D (D the state scales)
    # over the torque unit is the same matrix, to what the mirrored cluster's pole shifting
    # determines: the two problems differ by rounding, which moves the clustered poles by ~1e-4n
    # (above) and the gains by a few 1e-5 (measured 3e-5; 5.7e-4 under another BLAS build)
    ka = a.gain.K * a.model.scales / (a.model.scales[6] / NOMINAL_MOMENTUM)
    kb = b.gain.K * b.model.scales / (b.model.scales[6] / NOMINAL_MOMENTUM)
    assert np.linalg.norm(ka - kb) <= 1e-3 * np.linalg.norm(ka)
    assert a.model.scales[6] / b.model.scales[6] == pytest.approx(1e4, rel=1e-12)


def test_pbh_ratio_does_not_depend_on_the_station_size():
    from acmm.model.controllability import controllability
    from acmm.model.linearize import linearize_config

    ratios = [controllability(linearize_config(_station(k))).min_ratio for k in (1e-4, 1e-8)]
    assert ratios[0] > 1e-6
    assert ratios[1] == pytest.approx(ratios[0], rel=1e-6)


def test_report_sized_stations_keep_the_fixed_scales():
    """Within the band nothing changes: MB3 to AC (and ±30 % of them) keep 1000 ft·lbf·s and the
    ft·lbf torque unit, so the report's numbers are untouched."""
    from acmm.io.config import load_config
    from acmm.model.state_scaling import momentum_scale, torque_scale
    from acmm.model.linearize import state_scales

    for name in ("mb3", "ac"):
        cfg = load_config(name)
        for f in (0.7, 1.0, 1.3):
            I = cfg.inertia.matrix() * f
            assert momentum_scale(cfg.orbit_rate, I) == 1000.0
            assert torque_scale(state_scales(cfg.orbit_rate, inertia=I)) == 1.0
