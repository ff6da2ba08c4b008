"""The nominal loop enclosed on time cells (issue 43, deliverable 3): the samples against an
independent high-order integration, every value of the trajectory inside its cell's box, and the
certificate's m a lower bound of m(T') for every truncation time, with the integrals of β4 taken by
adaptive quadrature of the independent solution (scipy's quad on DOP853's dense output)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from qpp.design.certificate import certify
from qpp.design.nominal_enclosure import breakpoints, enclose
from qpp.io.config import Term
from qpp.simulate.closed_loop import initial_state
from tests.qpp.conftest import _pub


def _ref(terms, t):
    """r_o(t) written again here from the config's description (sin, step on [t_on, t_off), ramp)."""
    v = 0.0
    for s in terms:
        if s.kind == "sin":
            v += s.amplitude * np.sin(s.omega * t + s.phase)
        elif s.kind == "step":
            v += s.amplitude if ((s.t_on is None or t >= s.t_on) and (s.t_off is None or t < s.t_off)) else 0.0
        else:
            on = s.t_on or 0.0
            end = t if s.t_off is None else min(t, s.t_off)
            v += s.amplitude * max(end - on, 0.0)
    return v


#: a stable 3-state loop driven through two channels by every kind of term, with switches inside [0, T]
A3 = np.array([[-1.0, 4.0, 0.0], [-4.0, -1.0, 1.0], [0.5, 0.0, -3.0]])
B3 = np.array([[1.0, 0.0], [0.0, 0.5], [0.2, 1.0]])
R3 = [[Term(kind="sin", amplitude=1.0, omega=5.0, phase=0.3), Term(kind="step", amplitude=-0.4, t_on=0.7, t_off=1.3)],
      [Term(kind="ramp", amplitude=2.0, t_on=0.2, t_off=1.1), Term(kind="step", amplitude=0.25)]]


def _dense(A, B, z0, r_o, T, points):
    """An independent solution (DOP853 at rtol 1e-12), integrated piecewise between the switches."""
    cuts = [0.0, *sorted({x for ch in r_o for s in ch if s.kind != "sin" for x in (s.t_on, s.t_off)
                          if x is not None and 0 < x < T}), T]
    out, z = [], np.asarray(z0, float)
    sols = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        mid = 0.5 * (a + b)
        sol = solve_ivp(lambda t, x: A @ x + B @ np.array([_ref(ch, t if a < t < b else mid) for ch in r_o]),
                        (a, b), z, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
        sols.append((a, b, sol.sol))
        z = sol.y[:, -1]
    for t in points:
        a, b, s = next(x for x in sols if x[0] <= t <= x[1])
        out.append(s(t))
    return np.array(out).T, sols


def test_samples_and_boxes_contain_an_independent_solution():
    z0 = np.array([0.3, -0.2, 0.1])
    T = 1.6
    assert breakpoints(R3, T) == [0.2, 0.7, 1.1, 1.3]
    enc = enclose(A3, B3, z0, R3, T, cells=2048)
    assert enc.edges[0] == 0.0 and enc.edges[-1] == T and set(breakpoints(R3, T)) <= set(enc.edges)
    ref, _ = _dense(A3, B3, z0, R3, T, enc.edges)
    assert np.max(np.abs(ref - enc.z)) < 1e-9
    tt = np.random.default_rng(3).uniform(0, T, 5000)
    j = np.clip(np.searchsorted(enc.edges, tt, side="right") - 1, 0, enc.lo.shape[1] - 1)
    zz, _ = _dense(A3, B3, z0, R3, T, tt)
    assert np.all(zz >= enc.lo[:, j]) and np.all(zz <= enc.hi[:, j])
    # the box is no wider than a few times h·|ż| (the a-priori bound is not vacuous)
    width = np.max(enc.hi - enc.lo, axis=0)
    assert np.max(width) < 10 * (T / 2048) * 10.0


def test_a_loop_too_stiff_for_the_cell_budget_is_refused():
    with pytest.raises(ValueError, match="cells"):
        enclose(np.array([[-1e9]]), np.array([[1.0]]), [0.0], [[Term(kind="step", amplitude=1.0)]], 10.0)


def _m_exact(cfg, res, Tp):
    """m(T') of the consistent reading, computed here: β4 by adaptive quadrature of |k y_o|² on the
    independent solution, β3 of ch. 13's φ in closed form (k·sup_{[0, T']} |sin t|)."""
    P = cfg.lure_plant()
    Az, Bz = res.Az["eq10.7"], res.Bz["eq10.7"]
    z0 = initial_state(cfg, P, res.K1, res.Kc)
    k = 0.5
    a = res.a
    _, sols = _dense(Az, Bz[:, :1], z0, cfg.simulation.r_o, float(res.T), [0.0])
    (_, _, s), = sols
    out = []
    for T in Tp:
        I = quad(lambda t: (k * (res.Cz @ s(t))[0]) ** 2, 0, T, limit=500, epsabs=1e-14, epsrel=1e-12)[0]
        E = np.sqrt(np.expm1(2 * a * T) / (2 * a))
        b4 = np.exp(a * T) * np.sqrt(I) / E
        b3 = k * (1.0 if T >= np.pi / 2 else np.sin(T))
        out.append(0.2 / (0.1 + 0.2 * b3 + b4))
    return np.array(out)


def test_the_certificates_m_bounds_m_of_every_truncation_time(siso):
    """Ch. 13 with the printed gains: the tool's m is below m(T') for T' anywhere in (0, T] (here
    400 times, cell edges and interiors, quadrature to 1e-12), and within 1e-3 of their least."""
    res = certify(siso, *_pub(siso), siso.hinf.a)
    Tp = np.concatenate([np.linspace(1e-3, res.T, 300), np.random.default_rng(1).uniform(1e-3, res.T, 100)])
    m = _m_exact(siso, res, Tp)
    assert res.consistent.m <= m.min()
    assert res.consistent.m == pytest.approx(m.min(), rel=1e-3)
    assert res.consistent.m <= res.consistent.m_sampled
