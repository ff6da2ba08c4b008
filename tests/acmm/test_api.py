"""The Python API (acmm.api): python-control systems of the scheduled closed loop, against an
independent linearization; misuse raises the documented errors."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.io.config import load_config
from acmm_qpp.errors import ConfigError

from tests.conftest import LQR_ROUTE


# ---------------------------------------------------------------- API: python-control systems
def test_scheduled_closed_loop_equals_independent_linearization():
    import control
    from scipy.optimize import brentq

    from acmm import api
    from acmm.model import linearize as lin
    from acmm.model.tea import resolve_bias, solve_tea

    cfg = load_config("staircase", [*LQR_ROUTE])
    d = api.design(cfg)
    cl = d.scheduled_closed_loop(-20.0)
    # independent: the blend station with pitch TEA −20°, its TEA, the 24-state model, K(θ2*)
    n = cfg.orbit_rate
    i0, i1 = cfg.inertia.matrix(), cfg.schedule.to.inertia.matrix()
    b0, b1 = resolve_bias(cfg.disturbance, i0, n), resolve_bias(cfg.schedule.to.disturbance, i1, n)
    tea = lambda s: solve_tea((1 - s) * i0 + s * i1, n, (1 - s) * b0 + s * b1)  # noqa: E731
    s = brentq(lambda s: tea(s).theta[1] - np.radians(-20.0), 0.0, 1.0, xtol=1e-13)
    theta = tea(s).theta
    assert np.degrees(theta[1]) == pytest.approx(-20.0, abs=1e-8)
    m = lin.linearize((1 - s) * i0 + s * i1, theta, n)
    # the packaged table look-up: each K_ij linear in θ2* between the design points' own gains
    assert d.result.fit.form == "table"
    th = np.array([p.tea.theta[1] for p in d.result.points])
    Ks = np.array([p.gain.K for p in d.result.points])
    K = np.array([[np.interp(theta[1], th, Ks[:, i, j]) for j in range(24)] for i in range(3)])
    scale = max(np.abs(m.A).max(), np.abs(m.B @ K).max())
    np.testing.assert_allclose(cl.A, m.A - m.B @ K, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(cl.B, np.hstack([m.B, m.G]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(cl.C[24:], -K, rtol=1e-9, atol=1e-12 * np.abs(K).max())
    assert cl.state_labels == lin.STATE_NAMES and cl.input_labels == ["v1", "v2", "v3", "w1", "w2", "w3"]
    assert cl.output_labels[-3:] == ["u1", "u2", "u3"]
    # python-control interoperates: stable loop, a step response, disk margins of the loop
    assert np.max(cl.poles().real) < 0
    resp = control.step_response(cl, T=np.linspace(0.0, 2000.0, 50), input=3, output=4)
    assert np.all(np.isfinite(resp.outputs))
    dm = control.disk_margins(d.loop_transfer(0), np.logspace(-5, -1, 100))
    assert dm[0] > 0
    ol = d.open_loop(0)
    assert ol.input_labels == ["u1", "u2", "u3", "w1", "w2", "w3"] and ol.nstates == 24
    np.testing.assert_allclose(d.closed_loop(0).A, d.result.points[0].model.A - d.result.points[0].model.B
                               @ d.result.points[0].gain.K)


def test_api_misuse_raises_the_documented_errors():
    """A design point that is not there, a schedule a config does not have, a config of the wrong
    type: AcmmError subclasses naming what is valid (they were IndexError, KeyError, ValueError and
    TypeError); a missing point is still a KeyError/IndexError for code that caught those."""
    from acmm import api
    from acmm_qpp.errors import AcmmError, ConfigError

    d = api.design(api.load_config("mb3"))
    for bad in (5, "zzz", 1.5):
        with pytest.raises(ConfigError, match="no design point") as exc:
            d.closed_loop(bad)
        assert isinstance(exc.value, (KeyError, IndexError)) and "mb3" in str(exc.value)
    np.testing.assert_array_equal(d.gain(-1), d.gain("mb3"))
    for call in (lambda: d.scheduled_closed_loop(-20.0), lambda: d.loop_transfer(tea_pitch_deg=-20.0)):
        with pytest.raises(ConfigError, match="no gain schedule"):
            call()
    with pytest.raises(AcmmError, match="not int"):
        api.load_config(42)


def test_design_points_and_plain_system_names():
    """Issue 34: ``Design.points`` and python-control names without ``$indexed``."""
    from acmm import api

    d = api.design(api.load_config("mb3"))
    assert [p.spec.name for p in d.points] == d.names == ["mb3"]
    assert d.points[0].gain.K.shape == (3, 24)
    cl = d.closed_loop("mb3")
    assert cl.name == "closed loop at mb3"
    sub = d.closed_loop("mb3", outputs=["dtheta2"], inputs=["w2"])
    assert sub.name == "closed loop at mb3" and "$" not in sub.name
    assert sub.output_labels == ["dtheta2"] and sub.input_labels == ["w2"]
    full = cl[["dtheta2"], ["w2"]]                                      # python-control's own indexing
    assert np.allclose(sub.C, full.C) and np.allclose(sub.B, full.B) and np.allclose(sub.A, full.A)
    assert "$" not in d.loop_transfer("mb3").name


def test_a_blend_point_with_a_dot_in_its_name_gives_a_valid_system(staircase_lqr):
    from acmm import api

    d = api.Design(staircase_lqr.config, staircase_lqr)
    name = next(n for n in d.names if "." in n)               # blend_0.017 ...
    assert d.closed_loop(name).name == f"closed loop at {name.replace('.', ',')}"
    assert d.loop_transfer(name).name == f"loop transfer at {name.replace('.', ',')}"
