"""The stair-case's dwell-time certificate (:mod:`acmm.design.dwell`, :mod:`acmm.stages.certify`),
checked independently of the code under test: the Lyapunov matrices stored in ``design.h5``
recomputed by a Kronecker-product linear solve, the decay inequalities and the jump ratios by
eigenvalues of the stored matrices, and the transient bound against the exact response of the
linear switched system (matrix exponentials)."""
from __future__ import annotations

import h5py
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design.dwell import dwell_certificate, jump_ratios, lyapunov_matrices
from acmm.io.config import load_config
from acmm.io.design_file import load_design_table
from acmm.stages.design import run_design

from tests.conftest import LQR_ROUTE

ORBIT_DWELL = 10.8                                   # orbits each stair-case level is held (ch. 6)


@pytest.fixture(scope="module", params=["report's route", pytest.param("shipped", marks=pytest.mark.slow)])
def staircase_h5(request, tmp_path_factory):
    """(config, the ``dwell`` group of ``design.h5``, its design table) of the packaged stair-case
    on the report's route (sector LQR points) and as shipped (regional LMI points, slow)."""
    if request.param == "shipped":
        r, path = request.getfixturevalue("staircase_shipped")
        cfg = r.config
    else:
        cfg = load_config("staircase", [*LQR_ROUTE, f"output.root={tmp_path_factory.mktemp('dwell')}"])
        _, path = run_design(cfg, figures=False)
    with h5py.File(path, "r") as f:
        g = f["dwell"]
        data = {k: g[k][()] for k in g if isinstance(g[k], h5py.Dataset)}
        data["attrs"] = dict(g["tau_star"].attrs)
    return cfg, data, load_design_table(path)


def _kron_lyapunov(A, lam):
    """P with (A + λI)ᵀP + P(A + λI) = −I, by the Kronecker form of the equation (not scipy's
    Bartels–Stewart)."""
    N = A.shape[0]
    M = A + lam * np.eye(N)
    I = np.eye(N)
    op = np.kron(I, M.T) + np.kron(M.T, I)
    return np.linalg.solve(op, -I.reshape(-1)).reshape(N, N)


def test_the_stored_certificate_holds_when_recomputed_independently(staircase_h5):
    cfg, g, _ = staircase_h5
    n = cfg.orbit_rate
    d = g["scales"]
    As = g["closed_loop"] / d[None, :, None] * d[None, None, :]
    lam, P = float(g["decay_rate"]), g["lyapunov"]
    assert P.shape == (12, 24, 24) and lam > 0
    for k in range(12):
        ref = _kron_lyapunov(As[k], lam)
        assert np.max(np.abs(P[k] - ref)) <= 1e-7 * np.max(np.abs(ref))
        assert np.min(np.linalg.eigvalsh(P[k])) > 0
        lhs = (As[k] + lam * np.eye(24)).T @ P[k] + P[k] @ (As[k] + lam * np.eye(24))
        assert np.max(np.linalg.eigvalsh(0.5 * (lhs + lhs.T))) < 0          # V̇ ≤ −2λV
    up = [np.max(np.linalg.eigvals(np.linalg.solve(P[k], P[k + 1])).real) for k in range(11)]
    down = [np.max(np.linalg.eigvals(np.linalg.solve(P[k + 1], P[k])).real) for k in range(11)]
    np.testing.assert_allclose(g["jump_up"], up, rtol=1e-6)
    np.testing.assert_allclose(g["jump_down"], down, rtol=1e-6)
    mu = max(max(up), max(down))
    tau = np.log(mu) / (2 * lam) * n / (2 * np.pi)
    assert g["tau_star"] == pytest.approx(tau, rel=1e-9)
    # the requirement and the scenario: τ* below the 10.8 orbits each level is held
    assert tau < ORBIT_DWELL and np.all(g["dwell"] > tau) and bool(g["attrs"]["certified"])
    assert g["attrs"]["statement"] == "certificate of the linearized switched system"


def test_the_decay_rate_minimizes_the_dwell_time(staircase_h5):
    """λ is the minimizer of τ*(λ): a nearby λ on either side gives a longer certified dwell."""
    cfg, g, _ = staircase_h5
    d = g["scales"]
    As = g["closed_loop"] / d[None, :, None] * d[None, None, :]
    lam = float(g["decay_rate"])

    def tau(x):
        up, down = jump_ratios(lyapunov_matrices(As, x))
        return np.log(max(up.max(), down.max())) / (2 * x)

    assert tau(lam) <= min(tau(0.97 * lam), tau(1.03 * lam))


def test_the_transient_bound_holds_on_the_exact_linear_response(staircase_h5):
    """The exact response of the linear switched stair-case (levels held as in the scenario,
    the equilibrium jumping at each switch) stays inside the certified bounds on √V, |u| and |h|."""
    cfg, g, table = staircase_h5
    d = g["scales"]
    Acl, P, jumps, dwell = g["closed_loop"], g["lyapunov"], g["jump"], g["dwell"] * 2 * np.pi / cfg.orbit_rate
    from acmm.stages.certify import level_closed_loops

    _, gains, *_ = level_closed_loops(cfg, table)
    x = np.zeros(24)
    for k in range(12):
        if k:
            x = x + jumps[k - 1]
        hold = dwell[k] if k < 11 else dwell[-1]
        for t in np.linspace(0.0, hold, 400):
            xt = sla.expm(Acl[k] * t) @ x
            z = xt / d
            assert np.sqrt(z @ P[k] @ z) <= g["transient"][k] * (1 + 1e-9) + 1e-12
            assert np.all(np.abs(gains[k] @ xt) <= g["u_bound"][k] * (1 + 1e-9) + 1e-12)
            assert np.all(np.abs(xt[6:9]) <= g["h_bound"][k] * (1 + 1e-9) + 1e-12)
        x = sla.expm(Acl[k] * hold) @ x


def _two_levels(a1, a2, rot):
    """Two stable 2-state levels whose Lyapunov ellipses are rotated against each other."""
    A = np.array([[-a1, 10.0], [0.0, -a2]])
    R = np.array([[np.cos(rot), -np.sin(rot)], [np.sin(rot), np.cos(rot)]])
    return np.array([A, R @ A @ R.T])


def test_a_short_dwell_is_not_certified_and_an_unstable_level_gives_no_certificate():
    Acl = _two_levels(1.0, 1.0, 1.2)
    K = np.zeros((2, 3, 2))
    short = dwell_certificate(Acl, K, np.ones(2), np.array([0.01]), np.zeros((1, 2)), (0, 1, 1), 1.0, 1.0)
    long = dwell_certificate(Acl, K, np.ones(2), np.array([100.0]), np.zeros((1, 2)), (0, 1, 1), 1.0, 1.0)
    assert short.tau_star == long.tau_star > 0.01 and not short.certified and long.certified
    unstable = dwell_certificate(np.array([Acl[0], -Acl[1]]), K, np.ones(2), np.array([100.0]), np.zeros((1, 2)),
                                 (0, 1, 1), 1.0, 1.0)
    assert unstable.unstable_levels == (1,) and not unstable.certified and unstable.tau_star == np.inf


def test_both_directions_are_checked():
    """A one-way chain can be rescaled to any ratio: the certificate takes the worse direction."""
    Acl = np.array([[[-1.0, 10.0], [0.0, -1.0]], [[-1.0, 0.0], [3.0, -2.0]]])
    c = dwell_certificate(Acl, np.zeros((2, 3, 2)), np.ones(2), np.array([100.0]), np.zeros((1, 2)), (0, 1, 1),
                          1.0, 1.0)
    assert c.mu == max(c.jump_up[0], c.jump_down[0]) and c.jump_up[0] != pytest.approx(c.jump_down[0])


def test_acmm_certify_prints_the_certificate_and_strict_fails_an_unstable_claim_1(tmp_path):
    from typer.testing import CliRunner

    from acmm.cli.app import app

    run = lambda *a: CliRunner().invoke(app, ["certify", *a, f"output.root={tmp_path}"])   # noqa: E731
    ok = run("staircase", *LQR_ROUTE)
    assert ok.exit_code == 0 and "CERTIFIED" in ok.stdout and "linearized switched system" in ok.stdout, ok.output
    bad = run("mb3_decoupled", "--strict")
    assert bad.exit_code == 1 and "not stable" in bad.stdout and "strict:" in bad.output


def test_an_initial_offset_enters_the_transient_bound():
    """A run that does not start at the first level's equilibrium (simulation.initial_offset) has
    a non-zero bound from the first level on, and larger ones after (a review: it was ignored)."""
    from acmm.stages.certify import compute_certificate
    from acmm.stages.design import compute_design

    cfg = load_config("staircase", [*LQR_ROUTE])
    table = compute_design(cfg).table
    at_rest = compute_certificate(cfg, table).certificate
    offset = compute_certificate(load_config("staircase", [*LQR_ROUTE, "simulation.initial_offset=[3,3,3]"]), table).certificate
    assert at_rest.transient[0] == 0 and offset.transient[0] > 0
    assert np.all(offset.transient[1:] >= at_rest.transient[1:]) and offset.tau_star == at_rest.tau_star
