"""The stair-case's dwell-time certificate (:mod:`acmm.design.dwell`, :mod:`acmm.stages.certify`),
checked independently of the code under test: the Lyapunov matrices stored in ``design.h5`` against
Geromel and Colaneri's conditions with matrix exponentials of the test's own (Taylor series with
scaling and squaring, not scipy's Padé), the jump ratios by eigenvalues of the stored matrices,
the Hespanha–Morse dwell the certificate replaced (Kronecker solves of the Lyapunov equations), and
the transient bound against the exact response of the linear switched system."""
from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design import dwell as dwell_module
from acmm.design.dwell import DECAY_FRACTION, DWELL_RESOLUTION, DwellProof, dwell_certificate, dwell_margins
from acmm.io.config import load_config
from acmm.io.design_file import load_design_table
from acmm.stages import certify as certify_module
from acmm.stages.certify import compute_certificate, _level_closed_loops, _stored_proof
from acmm.stages.design import run_design

from tests.conftest import LQR_ROUTE

ORBIT_DWELL = 10.8                                   # orbits each stair-case level is held (ch. 6)


@pytest.fixture(scope="module", params=["report's route", pytest.param("shipped", marks=pytest.mark.slow)])
def staircase_h5(request):
    """(config, the ``dwell`` group of ``design.h5``, its design table) of the packaged stair-case
    on the report's route (sector LQR points) and as shipped (regional LMI points, slow)."""
    if request.param == "shipped":
        r, path = request.getfixturevalue("staircase_shipped")
        cfg = r.config
    else:
        r, path = request.getfixturevalue("staircase_lqr_h5")
        cfg = r.config
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


def _expm(A):
    """e^A by a Taylor series of degree 30 on A/2^s (‖A/2^s‖ ≤ 1/2), squared s times."""
    s = max(0, int(np.ceil(np.log2(max(np.linalg.norm(A, 1), 1e-300) / 0.5))))
    B = A / 2.0 ** s
    E, term = np.eye(len(A)), np.eye(len(A))
    for k in range(1, 31):
        term = term @ B / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def _largest(M):
    return float(np.max(np.linalg.eigvalsh(0.5 * (M + M.T))))


def _hespanha_morse(As):
    """The earlier certificate: one decay rate λ, P_k by Kronecker solves, τ* = ln μ/(2λ),
    minimized over a grid of λ (s)."""
    alpha = min(-np.max(np.linalg.eigvals(A).real) for A in As)
    best = np.inf
    for lam in np.linspace(0.05, 0.95, 19) * alpha:
        P = [_kron_lyapunov(A, lam) for A in As]
        mu = max(max(np.max(np.linalg.eigvals(np.linalg.solve(P[k], P[k + 1])).real),
                     np.max(np.linalg.eigvals(np.linalg.solve(P[k + 1], P[k])).real)) for k in range(len(P) - 1))
        best = min(best, np.log(mu) / (2 * lam))
    return best


def test_the_stored_certificate_holds_when_recomputed_independently(staircase_h5):
    """P_k ≻ 0, (A_k + λI)ᵀP_k + P_k(A_k + λI) ≺ 0 and e^{A_kᵀτ*}P_j e^{A_kτ*} ≺ e^{−2λτ*}P_k for
    j = k ± 1 (Geromel–Colaneri: every switching sequence between neighbouring levels, each held at
    least τ*, decays at rate λ), by eigenvalues of the stored matrices with the test's own
    exponentials, each with room far above rounding; τ* ≤ 0.6 orbit (issue 41) and below every
    level's dwell."""
    cfg, g, _ = staircase_h5
    n = cfg.orbit_rate
    orbit = 2 * np.pi / n
    d = g["scales"]
    As = g["closed_loop"] / d[None, :, None] * d[None, None, :]
    lam, P = float(g["decay_rate"]), g["lyapunov"]
    tau = float(g["tau_star"]) * orbit
    assert P.shape == (12, 24, 24) and lam > 0
    alpha = min(-np.max(np.linalg.eigvals(A).real) for A in As)
    assert lam == pytest.approx(alpha * DECAY_FRACTION, rel=1e-9)
    for k in range(12):
        norm = np.linalg.norm(P[k], 2)
        assert np.min(np.linalg.eigvalsh(P[k])) > 1e-9 * norm
        At = As[k] + lam * np.eye(24)
        assert _largest(At.T @ P[k] + P[k] @ At) < -1e-12 * norm
        E = _expm(As[k] * tau)
        for j in (k - 1, k + 1):
            if 0 <= j < 12:
                assert _largest(E.T @ P[j] @ E - np.exp(-2 * lam * tau) * P[k]) < -1e-9 * norm, (k, j)
    up = [np.max(np.linalg.eigvals(np.linalg.solve(P[k], P[k + 1])).real) for k in range(11)]
    down = [np.max(np.linalg.eigvals(np.linalg.solve(P[k + 1], P[k])).real) for k in range(11)]
    np.testing.assert_allclose(g["jump_up"], up, rtol=1e-6)
    np.testing.assert_allclose(g["jump_down"], down, rtol=1e-6)
    # the requirement and the scenario: τ* ≤ 0.6 orbit, below the 10.8 orbits each level is held
    assert float(g["tau_star"]) <= 0.6 and np.all(g["dwell"] >= g["tau_star"]) and bool(g["attrs"]["certified"])
    assert g["attrs"]["statement"] == "certificate of the linearized switched system"
    # the bisection's bracket: the dwell below it was tried and not certified
    lower = float(g["attrs"]["not_certified_below_orbit"]) * orbit
    assert 0 < lower < tau <= lower + DWELL_RESOLUTION / alpha * (1 + 1e-9)


def test_the_certificate_is_sharper_than_hespanha_morse(staircase_h5):
    """Geromel and Colaneri's LMIs certify a shorter dwell than the common-rate Lyapunov equations
    with the jump ratio (the earlier certificate, 1.65 orbit on the packaged stair-case),
    recomputed here by Kronecker solves over a grid of rates."""
    cfg, g, _ = staircase_h5
    d = g["scales"]
    As = g["closed_loop"] / d[None, :, None] * d[None, None, :]
    hm = _hespanha_morse(As) * cfg.orbit_rate / (2 * np.pi)
    assert float(g["tau_star"]) < 0.5 * hm, (float(g["tau_star"]), hm)


def test_the_transient_bound_holds_on_the_exact_linear_response(staircase_h5):
    """The exact response of the linear switched stair-case (levels held as in the scenario,
    the equilibrium jumping at each switch) stays inside the certified bounds on √V, |u| and |h|."""
    cfg, g, table = staircase_h5
    d = g["scales"]
    Acl, P, jumps, dwell = g["closed_loop"], g["lyapunov"], g["jump"], g["dwell"] * 2 * np.pi / cfg.orbit_rate
    _, gains, *_ = _level_closed_loops(cfg, table)
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
    assert np.all(short.transient == 0) and short.tau_lower < short.tau_star
    unstable = dwell_certificate(np.array([Acl[0], -Acl[1]]), K, np.ones(2), np.array([100.0]), np.zeros((1, 2)),
                                 (0, 1, 1), 1.0, 1.0)
    assert unstable.unstable_levels == (1,) and not unstable.certified and unstable.tau_star == np.inf


def test_both_directions_are_checked():
    """The matrices satisfy the switch conditions both ways (a one-way chain can be rescaled to
    any ratio and certifies nothing), checked with the test's own exponentials."""
    Acl = np.array([[[-1.0, 10.0], [0.0, -1.0]], [[-1.0, 0.0], [3.0, -2.0]]])
    c = dwell_certificate(Acl, np.zeros((2, 3, 2)), np.ones(2), np.array([100.0]), np.zeros((1, 2)), (0, 1, 1),
                          1.0, 1.0)
    assert c.certified and 0 < c.tau_star < 100 and c.mu == max(c.jump_up[0], c.jump_down[0])
    lam, P, tau = c.decay, c.P, c.tau_star
    for k, j in ((0, 1), (1, 0)):
        E = _expm(Acl[k] * tau)
        assert _largest(E.T @ P[j] @ E - np.exp(-2 * lam * tau) * P[k]) < 0


def test_acmm_certify_prints_the_certificate_and_strict_fails_an_unstable_claim_1(tmp_path, staircase_lqr_h5):
    """``acmm certify`` after ``acmm design`` (the design and its proof reused, checked again)."""
    from typer.testing import CliRunner

    from acmm.cli.app import app

    (tmp_path / "staircase").mkdir()
    shutil.copyfile(staircase_lqr_h5[1], tmp_path / "staircase" / "design.h5")
    run = lambda *a: CliRunner().invoke(app, ["certify", *a, f"output.root={tmp_path}"])   # noqa: E731
    ok = run("staircase", *LQR_ROUTE)
    assert ok.exit_code == 0 and "CERTIFIED" in ok.stdout and "linearized switched system" in ok.stdout, ok.output
    bad = run("mb3_decoupled", "--strict")
    assert bad.exit_code == 1 and "not stable" in bad.stdout and "strict:" in bad.output


class Solved(Exception):
    """The dwell-time program was solved: the stored proof was not reused."""


def _no_bisection(*args, **kwargs):
    raise Solved


def test_an_initial_offset_enters_the_transient_bound(staircase_lqr_h5, monkeypatch):
    """A run that does not start at the first level's equilibrium (simulation.initial_offset) has
    a non-zero bound from the first level on, and larger ones after (a review: it was ignored)."""
    r, path = staircase_lqr_h5
    cfg = load_config("staircase", [*LQR_ROUTE])
    with h5py.File(path, "r") as f:
        P = f["dwell/lyapunov"][()]
    # the stability part depends on the levels only: the stored proof is reused (checked again),
    # as `acmm certify` does, and no program is solved
    monkeypatch.setattr(dwell_module, "smallest_dwell", _no_bisection)
    at_rest = compute_certificate(cfg, r.table, path).certificate
    offset = compute_certificate(load_config("staircase", [*LQR_ROUTE, "simulation.initial_offset=[3,3,3]"]),
                                 r.table, path).certificate
    assert at_rest.transient[0] == 0 and offset.transient[0] > 0
    assert np.all(offset.transient[1:] >= at_rest.transient[1:])
    assert np.array_equal(at_rest.P, P) and np.array_equal(offset.P, P)


#: the commit this process and the copies of design.h5 are made to have (whatever git says here)
COMMIT = "c0ffee" * 6 + "c0ff"


def _as_clean_checkout(path, monkeypatch, commit: str = COMMIT):
    """Mark the copy ``path`` as written from a checkout at ``commit`` without uncommitted changes,
    and this process as running from one at :data:`COMMIT`."""
    monkeypatch.setattr(certify_module, "git_dirty", lambda: "no")
    monkeypatch.setattr(certify_module, "git_commit", lambda: COMMIT)
    with h5py.File(path, "r+") as f:
        f.attrs["git_dirty"] = "no"
        f.attrs["git_commit"] = commit


def test_a_design_of_the_same_stair_case_reuses_the_proof_of_the_file_it_replaces(tmp_path, staircase_lqr_h5,
                                                                                   monkeypatch):
    """``acmm design`` again in the same run folder: the ``design.h5`` it replaces holds a proof that
    this program found for the same closed loops (element by element), which is reused (checked
    again; no program solved) with the same matrices and dwells to the bit; from another commit,
    it is not."""
    r, written = staircase_lqr_h5
    root = tmp_path / "runs"
    path = root / "staircase" / "design.h5"
    path.parent.mkdir(parents=True)
    shutil.copyfile(written, path)
    _as_clean_checkout(path, monkeypatch)
    with h5py.File(path, "r") as f:
        P, tau = f["dwell/lyapunov"][()], f["dwell/tau_star"][()]
        lower = f["dwell/tau_star"].attrs["not_certified_below_orbit"]
    monkeypatch.setattr(dwell_module, "smallest_dwell", _no_bisection)
    cfg = load_config("staircase", [*LQR_ROUTE, f"output.root={root}"])
    _, new = run_design(cfg, figures=False)
    with h5py.File(new, "r") as f:
        assert np.array_equal(f["dwell/lyapunov"][()], P) and f["dwell/tau_star"][()] == tau
        assert f["dwell/tau_star"].attrs["not_certified_below_orbit"] == lower
    # the same file from another commit: the design solves the program (here: stops where it would)
    _as_clean_checkout(new, monkeypatch, commit="0" * 40)
    with pytest.raises(Solved):
        run_design(cfg, figures=False)


def test_a_proof_is_taken_for_a_new_design_only_from_the_same_program_on_the_same_loops(tmp_path, staircase_lqr_h5,
                                                                                       monkeypatch):
    """What a new design does not take: loops that differ in one element by one unit in the last
    place, other levels, a file in SI units, another commit, a checkout with uncommitted changes,
    no regular file, a group where the loops were, no git; and what no reader takes: soft links
    (to itself, to the data), data in an external raw file (a FIFO would block), an external link
    to a FIFO, a matrix of another shape (not read)."""
    r, written = staircase_lqr_h5
    cfg = load_config("staircase", [*LQR_ROUTE])
    Acl = _level_closed_loops(cfg, r.table)[0]
    orbit = 2 * np.pi / cfg.orbit_rate
    path = tmp_path / "design.h5"

    def fresh(commit=COMMIT):
        shutil.copyfile(written, path)
        _as_clean_checkout(path, monkeypatch, commit)
        return path

    assert _stored_proof(fresh(), orbit, Acl, exact=True) is not None
    nudged = Acl.copy()
    nudged[3, 0, 3] = np.nextafter(nudged[3, 0, 3], np.inf)
    assert _stored_proof(path, orbit, nudged, exact=True) is None and _stored_proof(path, orbit, nudged) is not None
    assert _stored_proof(path, orbit, Acl[1:], exact=True) is None and _stored_proof(path, orbit, Acl[1:]) is None
    assert _stored_proof(tmp_path, orbit, Acl) is None and _stored_proof(tmp_path / "none.h5", orbit, Acl) is None
    assert _stored_proof(fresh(commit="0" * 40), orbit, Acl, exact=True) is None
    assert _stored_proof(path, orbit, Acl) is not None
    fresh()
    monkeypatch.setattr(certify_module, "git_dirty", lambda: "yes")      # this checkout changed since
    assert _stored_proof(path, orbit, Acl, exact=True) is None
    monkeypatch.setattr(certify_module, "git_dirty", lambda: "unknown")     # no git: the version alone
    monkeypatch.setattr(certify_module, "git_commit", lambda: "unknown")
    with h5py.File(path, "r+") as f:
        f.attrs["git_dirty"] = f.attrs["git_commit"] = "unknown"
    assert _stored_proof(path, orbit, Acl, exact=True) is None and _stored_proof(path, orbit, Acl) is not None
    with h5py.File(fresh(), "r+") as f:
        f.attrs["unit_system"] = "SI"
    assert _stored_proof(path, orbit, Acl, exact=True) is None and _stored_proof(path, orbit, Acl) is not None
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    raw = tmp_path / "lyapunov.raw"
    # the readable cases first: a reader that followed links or external storage fails the test on
    # them before it could block on the FIFO
    for edit in ("group", "self link", "soft link to the data", "external raw file", "external raw FIFO",
                 "external link", "shape"):
        with h5py.File(fresh(), "r+") as f:
            g = f["dwell"]
            if edit == "group":
                del g["closed_loop"]
                g.create_group("closed_loop")
            elif edit == "self link":
                del g["lyapunov"]
                g["lyapunov"] = h5py.SoftLink("/dwell/lyapunov")
            elif edit == "soft link to the data":
                g.move("lyapunov", "lyapunov_data")
                g["lyapunov"] = h5py.SoftLink("/dwell/lyapunov_data")
            elif edit.startswith("external raw"):
                P = g["lyapunov"][()]
                P.tofile(raw)
                del g["lyapunov"]
                g.create_dataset("lyapunov", shape=P.shape, dtype=P.dtype,
                                 external=[(str(raw if edit.endswith("file") else fifo), 0, P.nbytes)])
            elif edit == "external link":
                del f["dwell"]
                f["dwell"] = h5py.ExternalLink(str(fifo), "/dwell")
            else:
                del g["lyapunov"]
                g.create_dataset("lyapunov", shape=(10**6, 24, 24), dtype=float)      # 4.6 GB if read
        assert _stored_proof(path, orbit, Acl, exact=True) is None, edit
        assert (_stored_proof(path, orbit, Acl) is None) == (edit != "group"), edit   # certify reads no loops


def test_a_stored_proof_is_reused_only_where_it_holds():
    """A proof for other closed loops (or with another decay rate) is not taken: the certificate is
    found anew."""
    Acl = _two_levels(1.0, 1.0, 1.2)
    args = (np.zeros((2, 3, 2)), np.ones(2), np.array([100.0]), np.zeros((1, 2)), (0, 1, 1), 1.0, 1.0)
    c = dwell_certificate(Acl, *args)
    same = dwell_certificate(Acl, *args, proof=DwellProof(c.decay, c.tau_star * (1 + 1e-15), c.tau_lower, c.P))
    assert same.P is c.P and same.tau_star == c.tau_star and same.tau_lower == c.tau_lower   # the grid's, to the bit
    other = _two_levels(1.0, 3.0, 0.4)
    fresh = dwell_certificate(other, *args)
    wrong = dwell_certificate(other, *args, proof=DwellProof(c.decay, c.tau_star, c.tau_lower, c.P))
    assert wrong.P is not c.P and wrong.tau_star == fresh.tau_star
    short = dwell_certificate(Acl, *args, proof=DwellProof(c.decay, 0.5 * c.tau_lower, 0.0, c.P))
    assert short.P is not c.P and short.tau_star == c.tau_star


def test_the_acceptance_check_refuses_what_it_does_not_prove():
    """dwell_margins is positive for the certificate's own matrices at τ* and not for: the same
    matrices at a quarter of τ*, a huge multiple of I (the products would overflow unscaled), a
    NaN, an asymmetric candidate (a review found the first three accepted)."""
    Acl = _two_levels(1.0, 1.0, 1.2)
    c = dwell_certificate(Acl, np.zeros((2, 3, 2)), np.ones(2), np.array([100.0]), np.zeros((1, 2)), (0, 1, 1),
                          1.0, 1.0)
    assert np.all(dwell_margins(Acl, c.P, c.tau_star, c.decay) > 0)
    assert np.min(dwell_margins(Acl, c.P, 0.25 * c.tau_star, c.decay)) <= 0
    huge = np.array([np.eye(2), np.eye(2)]) * 1.7e308
    short = 0.25 * c.tau_star
    E = _expm(Acl[0] * short)
    assert _largest(E.T @ np.eye(2) @ E - np.exp(-2 * c.decay * short) * np.eye(2)) > 0   # violated
    assert np.min(dwell_margins(Acl, huge, short, c.decay)) <= 0
    bad = c.P.copy()
    bad[0, 0, 0] = np.nan
    assert np.all(dwell_margins(Acl, bad, c.tau_star, c.decay) == -np.inf)
    skew = c.P.copy()
    skew[0, 0, 1] *= 1 + 1e-12
    assert np.all(dwell_margins(Acl, skew, c.tau_star, c.decay) == -np.inf)


def test_the_transient_bound_of_a_level_held_shorter_than_tau_star():
    """A level held shorter than τ* takes the jump ratio √μ into the bound (the branch the
    stair-case never reaches): the exact response of two switched levels with equilibrium jumps
    stays inside it, and the same recursion without √μ would not."""
    Acl = _two_levels(1.0, 1.0, 1.2)
    K = np.array([np.eye(3, 2), np.eye(3, 2)])
    jumps = np.array([[1.0, -0.5]])
    c = dwell_certificate(Acl, K, np.ones(2), np.array([0.05]), jumps, (0, 1, 1), 1e9, 1e9, start=np.array([0.3, 0.8]))
    assert not c.certified and 0.05 < c.tau_star
    x = np.array([0.3, 0.8])
    worst = 0.0
    for t in np.linspace(0.0, 0.05, 200):
        z = sla.expm(Acl[0] * t) @ x
        assert np.sqrt(z @ c.P[0] @ z) <= c.transient[0] * (1 + 1e-9)
    x = sla.expm(Acl[0] * 0.05) @ x + jumps[0]
    for t in np.linspace(0.0, 5.0, 400):
        z = sla.expm(Acl[1] * t) @ x
        worst = max(worst, np.sqrt(z @ c.P[1] @ z))
    assert worst <= c.transient[1] * (1 + 1e-9)
    dj = jumps[0]
    without = np.exp(-c.decay * 0.05) * c.transient[0] + np.sqrt(dj @ c.P[1] @ dj)
    assert np.sqrt(c.jump_up[0]) > 1 and c.transient[1] > without
