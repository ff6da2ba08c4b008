"""The design routes (``design.pole_method``, :mod:`acmm.design.methods`, issue 40 item 3): one
record from every route, the string read in one product file."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design.methods import METHODS, PointGain, pole_method
from acmm.design.schedule import design_one
from acmm.design.schedule_points import point_specs
from acmm.design.sector_lqr import SectorLQR
from acmm.design.settings import design_settings
from acmm.io.config import load_config
from acmm.model.state_scaling import torque_scale

REPO = Path(__file__).resolve().parents[3]


def _energy(model, K, n):
    """H2 energy of u = −Kx under a unit torque disturbance at the input, scaled input, time 1/n."""
    d, e = model.scales, torque_scale(model.scales)
    As = model.A / d[:, None] * d[None, :] / n
    Bs = model.B / d[:, None] * e / n
    Ks = K * d[None, :] / e
    W = sla.solve_continuous_lyapunov(As - Bs @ Ks, -Bs @ Bs.T)
    return float(np.trace(Ks @ W @ Ks.T))


@pytest.mark.parametrize("route", sorted(METHODS))
def test_every_route_returns_one_record(route):
    cfg = load_config("mb3", [f"design.pole_method={route}", "design.lmi.n_random=0"])
    s = design_settings(cfg)
    assert s.method is pole_method(route)
    p = design_one(point_specs(cfg)[0], s)
    g = p.gain
    assert isinstance(g, PointGain) and isinstance(g.riccati, SectorLQR) and g.method == route
    lam = np.linalg.eigvals(p.model.A - p.model.B @ g.K)
    # each stored pole within 1e-5 n of one recomputed here (the uniform route: κ_CARE ~1e18)
    assert lam.size == g.poles.size and np.abs(lam[:, None] - g.poles[None, :]).min(axis=1).max() <= 1e-5 * cfg.orbit_rate
    assert g.energy == pytest.approx(_energy(p.model, g.K, cfg.orbit_rate), rel=1e-9)
    assert g.margin >= 0.1
    if route == "lmi":
        assert g.lmi is not None and g.lmi.certified_margin >= 0.1 and not np.array_equal(g.K, g.riccati.K)
    else:
        assert g.lmi is None and np.array_equal(g.K, g.riccati.K)


def test_an_unknown_route_names_the_key():
    with pytest.raises(ValueError, match="design.pole_method"):
        pole_method("newton")


def test_the_route_string_is_compared_in_one_product_file_at_most():
    """``design.pole_method`` becomes a :class:`~acmm.design.methods.PoleMethod` in one place;
    no product module compares it with a route's name but the sector LQR's own ``method``
    argument (``"shift"`` / ``"uniform"``) in ``sector_lqr.py``."""
    pattern = re.compile(r"""pole_method\s*[!=]=|[!=]=\s*["'](shift|uniform|lmi)["']""")
    hits = [str(p.relative_to(REPO)) for pkg in ("acmm", "acmm_qpp", "qpp") for p in (REPO / pkg).rglob("*.py")
            for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if pattern.search(line)]
    assert set(hits) <= {"acmm/design/sector_lqr.py"}, hits
