"""The report's examples searched over procedure 12.1's family (issue 43, deliverable 5): the bounds
that hold for every design (β1 ≥ 1, m ≤ β_o/(β_i + |k∘C x0|), m ≤ 1 for ch. 13 once T ≥ π/2)
against numbers computed here from the configs and the independent verifier's Hamiltonian norm."""
from __future__ import annotations

import numpy as np
import pytest

from qpp.design.certificate import certify
from qpp.design.family import REPORT_GRIDS, family_bounds, refine, search, servo_frequencies
from qpp.design.hinf import hinf_gains
from qpp.design.procedure import weighted_plant
from qpp.model.lure import closed_loop
from tests.qpp.conftest import _pub
from tests.qpp.independent_verifier import hinf


def test_the_bounds_of_the_report_examples(siso, arm):
    b = family_bounds(siso)
    assert b.servo_frequencies == [5.0]                      # Ac = [[0, 1], [−25, 0]]: ±5j
    assert b.m_upper == pytest.approx(0.2 / 0.1)             # y_o(0) = 0: only β_i = 0.1 remains
    assert b.T_sin == pytest.approx(np.pi / 2) and b.m_upper_sin == pytest.approx(0.2 / (0.1 + 0.2 * 0.5))
    assert not b.excluded
    b = family_bounds(arm)
    assert b.servo_frequencies == [0.0]
    assert b.m_upper == pytest.approx(0.14 / (0.5 * 0.5))    # x0 = [0.5, 0, …], sector ±0.5, β_i = 0
    assert b.excluded


def test_servo_frequencies_of_an_oscillator_and_an_integrator():
    assert servo_frequencies([[0, 1], [-9, 0]]) == [3.0]
    assert servo_frequencies([[0, 0, 0], [0, 0, 1], [0, 0, 0]]) == [0.0]
    assert servo_frequencies([[-1.0]]) == []


@pytest.mark.parametrize("rho, w, a", [(1e-5, 0.3, 1e-8), (1e-2, 3.0, 0.3), (1e-3, 10.0, 1e-2)])
def test_beta1_is_at_least_one_whatever_the_gains(siso, rho, w, a):
    """β1 by the verifier's own Hamiltonian bisection, and |T_ry(5j)| = 1 (internal model)."""
    P = siso.lure_plant()
    g = hinf_gains(weighted_plant(P, w), rho=rho, a=a)
    Az, Bz, Cz = closed_loop(P, g.K1, g.Kc, g.H)
    An = Az + a * np.eye(len(Az))
    assert np.linalg.eigvals(An).real.max() < 0
    assert hinf(An, Bz, Cz) >= 1.0 - 1e-9
    Tr = Cz @ np.linalg.solve(5j * np.eye(len(Az)) - Az, Bz[:, :1])
    assert abs(Tr[0, 0]) == pytest.approx(1.0, abs=1e-9)


def test_m_stays_below_the_bounds(siso, arm):
    """The printed gains: the manipulator's m ≤ 0.56 at every T; ch. 13's m ≤ 1 at T = 2 s > π/2."""
    for T in (0.3, 1.0, np.pi):
        assert certify(arm, *_pub(arm), arm.hinf.a, T=T).consistent.m <= 0.14 / 0.25
    assert certify(siso, *_pub(siso), siso.hinf.a, T=2.0).consistent.m <= 1.0


@pytest.mark.slow
@pytest.mark.parametrize("name", list(REPORT_GRIDS))
def test_the_grid_of_the_family_certifies_nothing(name, siso, arm):
    """The grids of docs/qpp-certificates.md (~2 min for ch. 13): no design certified; on each,
    β1 ≥ 1 (its gain at the servo frequencies is 1), m below the bound, and β1 < m fails; a short
    local search from the best point certifies nothing either."""
    cfg = {"qpp_siso": siso, "qpp_manipulator": arm}[name]
    grid = REPORT_GRIDS[name]
    cands = search(cfg, grid["rho"], grid["w"], grid["a"])
    b = family_bounds(cfg)
    assert len(cands) >= 20
    for c in cands:
        assert not c.certified and "contraction" in c.failed
        assert c.servo_gain == pytest.approx(1.0, abs=1e-8) and c.beta1 >= 1.0 - 1e-9
        assert c.m <= b.m_upper * (1 + 1e-12)
        if b.T_sin is not None and c.T >= b.T_sin:
            assert c.m <= b.m_upper_sin * (1 + 1e-12)
    best, n = refine(cfg, max(cands, key=lambda c: c.m - c.beta1), max_evals=12)
    assert n >= 1 and not best.certified and best.m < best.beta1
