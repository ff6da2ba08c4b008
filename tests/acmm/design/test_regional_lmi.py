"""The regional LMI design route (``design.pole_method: lmi``, :mod:`acmm.design.regional_lmi`),
checked from what ``design.h5`` stores by computations of the test's own: the region LMIs re-verified
by eigenvalues of the stored certificate, the poles and their condition numbers by numpy, the
robustness by random relative gain perturbations, and the control energy by a Lyapunov solve, against
the LQR route on the same station (issue 32)."""
from __future__ import annotations

import os
import subprocess
import sys

import h5py
import numpy as np
import pytest
import scipy.linalg as sla

from acmm.design import regional_lmi as rl
from acmm.design.regional_lmi import RegionalLMISettings, regional_lmi
from acmm.design.schedule import design_one
from acmm.design.schedule_points import point_specs
from acmm.design.settings import design_settings
from acmm.io.config import load_config
from acmm.model.state_scaling import torque_scale
from acmm.stages.design import compute_design, run_design
from acmm_qpp.errors import DesignError



def _point(path):
    with h5py.File(path, "r") as f:
        g = f["points"][sorted(f["points"])[0]]
        out = {k: g[k][()] for k in ("A", "B", "K", "scales")}
        if "lmi" in g:
            out.update({k: g["lmi"][k][()] for k in ("X", "certified_margin", "random_radius", "energy")})
            out["solver"] = g["lmi"]["solver_tolerance"].attrs["solver"]
            out["rejected"] = g["lmi"]["solver_tolerance"].attrs["rejected"]
    return out


@pytest.fixture(scope="module")
def mb3_both_routes(tmp_path_factory):
    root = tmp_path_factory.mktemp("lmi")
    lmi = run_design(load_config("mb3", [f"output.root={root}", "name=mb3_lmi", "design.pole_method=lmi"]),
                     figures=False)[1]
    lqr = run_design(load_config("mb3", [f"output.root={root}"]), figures=False)[1]
    return load_config("mb3"), _point(lmi), _point(lqr)


def _margin(lam, n, sigma=0.5, phi=np.radians(45.0)):
    x, y = lam.real, np.abs(lam.imag)
    return np.minimum(-sigma * n - x, -(y * np.cos(phi) + x * np.sin(phi))) / n


def _scaled(p, n):
    d, e = p["scales"], torque_scale(p["scales"])
    return p["A"] / d[:, None] * d[None, :] / n, p["B"] / d[:, None] * e / n, p["K"] * d[None, :] / e


def test_every_pole_in_the_sector_with_margin_and_well_conditioned(mb3_both_routes):
    cfg, lmi, _ = mb3_both_routes
    n = cfg.orbit_rate
    lam, V = np.linalg.eig(lmi["A"] - lmi["B"] @ lmi["K"])
    assert _margin(lam, n).min() >= 0.1
    As, Bs, Ks = _scaled(lmi, n)
    lam_s, Vs = np.linalg.eig(As - Bs @ Ks)
    W = np.linalg.inv(Vs)
    kappa = np.linalg.norm(Vs, axis=0) * np.linalg.norm(W, axis=1)
    assert kappa.max() <= 2e4 and lmi["solver"] == "conelp" and lmi["rejected"] == "none"


def test_the_stored_certificate_proves_the_regions(mb3_both_routes):
    """With the stored X: M + Mᵀ + 2(σ + μ)X ⪯ 0 and the cone of apex −μ/sin φ, M = (Ã − B̃K̃)X."""
    cfg, lmi, _ = mb3_both_routes
    As, Bs, Ks = _scaled(lmi, cfg.orbit_rate)
    X, mu, phi = lmi["X"], 0.1, np.radians(45.0)
    assert np.linalg.eigvalsh(X).min() > 0
    M = (As - Bs @ Ks) @ X
    assert np.linalg.eigvalsh(M + M.T + 2 * (0.5 + mu) * X).max() < 0
    Mc = M + mu / np.sin(phi) * X
    cone = np.block([[np.sin(phi) * (Mc + Mc.T), np.cos(phi) * (Mc - Mc.T)],
                     [np.cos(phi) * (Mc.T - Mc), np.sin(phi) * (Mc + Mc.T)]])
    assert np.linalg.eigvalsh(0.5 * (cone + cone.T)).max() < 0
    assert lmi["certified_margin"] >= mu


def test_random_gain_errors_of_3e_4_keep_every_pole_in_the_sector(mb3_both_routes):
    cfg, lmi, lqr = mb3_both_routes
    n = cfg.orbit_rate
    rng = np.random.default_rng(2026)
    worst = {}
    for name, p in (("lmi", lmi), ("lqr", lqr)):
        worst[name] = min(_margin(np.linalg.eigvals(p["A"] - p["B"] @ (p["K"] * (1 + 3e-4 * rng.uniform(-1, 1, p["K"].shape)))),
                                  n).min() for _ in range(200))
    assert worst["lmi"] > 0                  # the LQR route's radius is a few 1e-6: it does not hold
    assert lmi["random_radius"] >= 3e-4


def test_the_control_energy_is_below_the_lqr_routes(mb3_both_routes):
    """E = tr(K̃ W K̃ᵀ), W the closed-loop gramian of the disturbance torque (G̃ = −B̃), both routes."""
    cfg, lmi, lqr = mb3_both_routes

    def energy(p):
        As, Bs, Ks = _scaled(p, cfg.orbit_rate)
        W = sla.solve_continuous_lyapunov(As - Bs @ Ks, -Bs @ Bs.T)
        return float(np.trace(Ks @ W @ Ks.T))

    assert energy(lmi) < energy(lqr)
    assert energy(lmi) == pytest.approx(lmi["energy"], rel=1e-6)


def _points(path):
    """Every stored design point of a ``design.h5`` (in the order of the points)."""
    with h5py.File(path, "r") as f:
        out = []
        for key in sorted(f["points"]):
            g = f["points"][key]
            p = {k: g[k][()] for k in ("A", "B", "K", "scales")}
            if "lmi" in g:
                p["X"] = g["lmi"]["X"][()]
            out.append(p)
    return out


def _energy(p, n):
    As, Bs, Ks = _scaled(p, n)
    W = sla.solve_continuous_lyapunov(As - Bs @ Ks, -Bs @ Bs.T)
    return float(np.trace(Ks @ W @ Ks.T))


@pytest.mark.slow
def test_every_shipped_staircase_point_meets_the_lmi_targets(staircase_shipped, staircase_lqr):
    """Issue 32, at every point of the shipped stair-case (MB3 … AC, regional LMI): every pole
    ≥ 0.1n inside the sector, κ ≤ 2e4 and the stored certificate proving the regions (eigenvalues
    of the stored matrices), no pole leaving the sector under 100 random relative gain errors of
    3e-4, and less control energy than the report's route at the same point (its gains from the
    LQR stair-case of the same config)."""
    r, path = staircase_shipped
    n, phi, mu = r.config.orbit_rate, np.radians(45.0), 0.1
    pts = _points(path)
    with h5py.File(path, "r") as f:
        level = f["level"][()].astype(bool)
    # the LQR stair-case has the 12 levels only (refine_points=0); the shipped one also its nodes
    lqr_K = iter([p.gain.K for p in staircase_lqr.points])
    assert level.sum() == len(staircase_lqr.points) == 12 and len(pts) > 12
    rng = np.random.default_rng(32)
    for k, p in enumerate(pts):
        lam = np.linalg.eigvals(p["A"] - p["B"] @ p["K"])
        assert _margin(lam, n).min() >= mu, k
        As, Bs, Ks = _scaled(p, n)
        _, Vs = np.linalg.eig(As - Bs @ Ks)
        kappa = np.linalg.norm(Vs, axis=0) * np.linalg.norm(np.linalg.inv(Vs), axis=1)
        assert kappa.max() <= 2e4, (k, kappa.max())
        X = p["X"]
        assert np.linalg.eigvalsh(X).min() > 0
        M = (As - Bs @ Ks) @ X
        assert np.linalg.eigvalsh(M + M.T + 2 * (0.5 + mu) * X).max() < 0, k
        Mc = M + mu / np.sin(phi) * X
        cone = np.block([[np.sin(phi) * (Mc + Mc.T), np.cos(phi) * (Mc - Mc.T)],
                         [np.cos(phi) * (Mc.T - Mc), np.sin(phi) * (Mc + Mc.T)]])
        assert np.linalg.eigvalsh(0.5 * (cone + cone.T)).max() < 0, k
        for _ in range(100):
            Kp = p["K"] * (1 + 3e-4 * rng.uniform(-1, 1, p["K"].shape))
            assert _margin(np.linalg.eigvals(p["A"] - p["B"] @ Kp), n).min() > 0, k
        if level[k]:
            assert _energy(p, n) < _energy({**p, "K": next(lqr_K)}, n), k


# ---------------------------------------------------------------------------------------------
# the solvers (issue 40): the same program by conelp, DSDP and Clarabel, answers accepted on checks only
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def mb3_model():
    """MB3's design model and the reference (sector LQR) gain, physical units."""
    cfg = load_config("mb3", ["design.pole_method=shift"])
    s = design_settings(cfg)
    p = design_one(point_specs(cfg)[0], s)
    return p.model, p.gain.K, cfg.orbit_rate


def _design(mb3_model, **settings):
    model, K_ref, n = mb3_model
    st = RegionalLMISettings(n_random=0, **settings)
    return regional_lmi(model.A, model.B, n, K_ref, st, scale=model.scales,
                        input_scale=torque_scale(model.scales))


def _certificate_holds(model, n, r, mu=0.1, phi=np.radians(45.0)):
    """The regions re-verified by eigenvalues of the returned X and K (scaled coordinates)."""
    p = {"A": model.A, "B": model.B, "K": r.K, "scales": model.scales}
    As, Bs, Ks = _scaled(p, n)
    X = r.X
    M = (As - Bs @ Ks) @ X
    Mc = M + mu / np.sin(phi) * X
    cone = np.block([[np.sin(phi) * (Mc + Mc.T), np.cos(phi) * (Mc - Mc.T)],
                     [np.cos(phi) * (Mc.T - Mc), np.sin(phi) * (Mc + Mc.T)]])
    return (np.linalg.eigvalsh(X).min() > 0 and np.linalg.eigvalsh(M + M.T + 2 * (0.5 + mu) * X).max() < 0
            and np.linalg.eigvalsh(0.5 * (cone + cone.T)).max() < 0
            and _margin(np.linalg.eigvals(model.A - model.B @ r.K), n).min() >= mu)


@pytest.mark.slow
def test_every_solver_finds_the_same_gain_with_valid_certificates(mb3_model):
    """The default solver, DSDP and the reference solve one program: K equal to 3e-5 relative (each
    converges to its own tolerance, 1e-7 in the gap, and the optimum is flat along directions the
    gain barely uses: Clarabel and DSDP differ by ~3e-6, conelp from either by ~1e-5), the energy
    to 3e-6 (conelp's is ~1e-6 above the others'), every certificate proved by eigenvalues."""
    model, _, n = mb3_model
    a = _design(mb3_model, solver="conelp")
    d = _design(mb3_model, solver="dsdp")
    c = _design(mb3_model, solver="clarabel")
    assert (a.solver, d.solver, c.solver) == ("conelp", "dsdp", "clarabel")
    assert a.rejected == d.rejected == c.rejected == ()
    for r in (a, d):
        assert np.linalg.norm(r.K - c.K) / np.linalg.norm(c.K) <= 3e-5
        assert r.energy == pytest.approx(c.energy, rel=3e-6)
    assert all(_certificate_holds(model, n, r) for r in (a, d, c))


@pytest.mark.slow
def test_the_regularization_costs_under_0_1_percent_of_energy(mb3_model):
    """ε (tr X + tr X₂) makes the optimum attained; the energy of its answer is within 0.1 % of
    the unregularized program's (Clarabel, which stops near that program's infimum)."""
    reg = _design(mb3_model)
    bare = _design(mb3_model, solver="clarabel", regularization=0.0)
    assert bare.energy <= reg.energy <= 1.001 * bare.energy



def _fake_route(result, X_scale=1.0, residual=0.0, status="fake optimal"):
    """A solver route that answers ``result``: "zero" (K = 0: poles outside the sector),
    "reference" (the reference LQR's gain, poles inside), with X = X_scale·I and the given cost
    residual; or raises the exception ``result``."""
    def route(As, Bs, Gs, K0, T, st):
        if isinstance(result, BaseException):
            raise result
        Ks = K0 if result == "reference" else np.zeros_like(K0)
        N = As.shape[0]
        return status, (1,), (Ks, X_scale * np.eye(N), np.eye(N), 1e9, residual)
    return route


def test_an_answer_failing_the_checks_is_refused_whatever_its_status(mb3_model, monkeypatch):
    """A solver reporting "optimal" with a gain whose poles leave the sector is refused, the next
    solver tried with a warning; when every answer fails: one DesignError naming each solver's
    outcome and the settings to relax, never "infeasible"."""
    good = dict(rl.ROUTES)
    monkeypatch.setitem(rl.ROUTES, "clarabel", _fake_route("zero"))
    with pytest.warns(RuntimeWarning, match="clarabel returned no gain that passes the checks"):
        r = _design(mb3_model, solver="clarabel")
    assert r.solver == "conelp" and r.rejected[0].startswith("clarabel: worst sector margin")
    assert _certificate_holds(mb3_model[0], mb3_model[2], r)
    monkeypatch.setitem(rl.ROUTES, "conelp", _fake_route("zero"))
    monkeypatch.setitem(rl.ROUTES, "dsdp", _fake_route("zero"))
    with pytest.raises(DesignError) as exc, pytest.warns(RuntimeWarning):
        _design(mb3_model, solver="clarabel")
    msg = str(exc.value)
    assert "\n" not in msg and "infeasib" not in msg.lower()
    assert all(f"{x}: worst sector margin" in msg for x in ("clarabel", "conelp", "dsdp"))
    assert "relax design.min_margin" in exc.value.hint          # raised with its hint (; hint: on the CLI)
    assert all(good[x] is not rl.ROUTES[x] for x in ("conelp", "dsdp", "clarabel"))


def test_a_solver_crash_is_named_as_a_crash_not_as_infeasibility(mb3_model, monkeypatch):
    """A solver that raises (a singular system, say) is reported as an error of that solver, and
    the fallback answers."""
    monkeypatch.setitem(rl.ROUTES, "conelp", _fake_route(np.linalg.LinAlgError("singular KKT")))
    monkeypatch.setitem(rl.ROUTES, "dsdp", _fake_route(ZeroDivisionError("division by zero")))
    monkeypatch.setitem(rl.ROUTES, "clarabel", _fake_route(ArithmeticError("stalled")))
    with pytest.raises(DesignError) as exc, pytest.warns(RuntimeWarning, match="singular KKT"):
        _design(mb3_model)
    msg = str(exc.value)
    assert "conelp: LinAlgError: singular KKT" in msg and "clarabel: ArithmeticError: stalled" in msg
    assert "dsdp: ZeroDivisionError: division by zero" in msg
    assert "infeasib" not in msg.lower()


class _Panic(BaseException):
    """What a Rust solver's panic raises through pyo3 (not an Exception)."""


@pytest.mark.parametrize("route, reason", [
    (_fake_route("reference", X_scale=1.0), "certified"),                 # poles inside, X = I proves nothing
    (_fake_route("reference", X_scale=-1.0), "X is not positive definite"),
    (_fake_route(_Panic("rust panic")), "_Panic: rust panic"),
    (_fake_route("zero", status="infeasible"), "worst sector margin"),
])
def test_each_check_refuses_its_answer_and_a_solver_status_never_reaches_the_message(mb3_model, monkeypatch,
                                                                                     route, reason):
    """Every refusal names its cause; the solver's own status ("infeasible") is not repeated."""
    monkeypatch.setattr(rl, "ROUTES", {"conelp": route})
    monkeypatch.setattr(rl, "SOLVERS", ("conelp",))
    with pytest.raises(DesignError) as exc:
        _design(mb3_model)
    msg = str(exc.value)
    assert "(conelp: " in msg and reason in msg and "infeasib" not in msg.lower(), msg


def test_a_cost_bound_the_energy_exceeds_is_refused(mb3_model, monkeypatch):
    """An answer whose gain proves the regions but whose cost LMIs are violated (residual) or whose
    tr W is below the gain's energy is refused: the cost bound is checked, not trusted."""
    good = rl.ROUTES["conelp"]

    def tampered(residual=None, cost=None):
        def route(*args):
            status, it, sol = good(*args)
            Ks, Xs, X2s, c, res = sol
            return status, it, (Ks, Xs, X2s, c if cost is None else cost, res if residual is None else residual)
        return route

    for kwargs, reason in (({"residual": 1e-3}, "cost LMIs violated"), ({"cost": 1.0}, "above the cost bound")):
        monkeypatch.setattr(rl, "ROUTES", {"conelp": tampered(**kwargs)})
        monkeypatch.setattr(rl, "SOLVERS", ("conelp",))
        with pytest.raises(DesignError, match=reason):
            _design(mb3_model)


def test_the_default_solver_answer_is_proved_by_eigenvalues(mb3_model):
    """conelp's answer on MB3 (the default route, in the fast suite): margin ≥ 0.1n proved by the
    returned X (eigenvalues), the cost LMIs hold to 1e-6, the energy is the Lyapunov solve's."""
    model, _, n = mb3_model
    r = _design(mb3_model)
    assert r.solver == "conelp" and _certificate_holds(model, n, r)
    p = {"A": model.A, "B": model.B, "K": r.K, "scales": model.scales}
    assert _energy(p, n) == pytest.approx(r.energy, rel=1e-9) and r.energy <= r.cost_bound


def test_a_loose_gap_tolerance_still_gives_an_answer_that_passes_the_checks(mb3_model):
    """``design.lmi.tol=1e-3`` loosens conelp's gap only: its feasibility stays at 1e-7, so its answer
    holds the cost LMIs to the checks' 1e-6 and no fallback is needed (with the feasibility at 1e-3
    too, the answer was refused and DSDP solved)."""
    r = _design(mb3_model, tol=1e-3)
    assert r.solver == "conelp" and r.rejected == () and r.lmi_residual <= rl.COST_TOL
    assert _certificate_holds(mb3_model[0], mb3_model[2], r)


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["conelp", "dsdp", "clarabel"])
def test_an_unreachable_margin_is_one_line_and_exit_3_with_every_solver(solver, tmp_path):
    """``design.min_margin=5`` on the LMI route: no solver's answer passes the checks; one line
    naming the settings to relax, exit 3, nothing written, and no claim of infeasibility."""
    r = subprocess.run([sys.executable, "-m", "acmm.cli.app", "design", "mb3", "design.pole_method=lmi",
                        "design.min_margin=5", f"design.lmi.solver={solver}", f"output.root={tmp_path}",
                        "--no-figures"], capture_output=True, text=True, timeout=600,
                       env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert r.returncode == 3, r.stderr
    lines = [x for x in r.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: regional LMI: no solver returned"), r.stderr
    assert "relax design.min_margin" in lines[0] and "infeasib" not in lines[0].lower()
    assert not list(tmp_path.rglob("*.h5"))


#: Stations beyond SSF (issue 40): other inertias, SI units, other orbit rates, each designed by
#: the sector LQR (which must reach the margin, else the case says nothing) and by the LMI route.
STATIONS = {
    "si_small": ["inertia.I11=6.0e7 kg*m^2", "inertia.I22=1.5e7 kg*m^2", "inertia.I33=7.0e7 kg*m^2",
                 "inertia.I12=-4e5 kg*m^2", "inertia.I13=2e5 kg*m^2", "inertia.I23=1e5 kg*m^2",
                 "orbit_rate=0.0011 rad/s", "disturbance.bias_from_tea=[0.3, -8.0, 0.6]", "output.units=SI"],
    "fast_orbit": ["orbit_rate=0.0013 rad/s", "disturbance.bias_from_tea=[1.0, -12.0, 0.5]"],
    "slow_orbit_heavy": ["orbit_rate=0.0009 rad/s", "inertia.I22=2.0e7", "inertia.I33=3.4e7",
                         "disturbance.bias_from_tea=[0.5, -20.0, 1.0]"],
}


@pytest.mark.slow
@pytest.mark.parametrize("station", sorted(STATIONS))
def test_stations_beyond_ssf_design_on_the_lmi_route(station, tmp_path):
    over = [*STATIONS[station], "design.min_margin=0.1", f"output.root={tmp_path}"]
    lqr = compute_design(load_config("mb3", [*over, "design.pole_method=shift"]))
    lmi = compute_design(load_config("mb3", [*over, "design.pole_method=lmi"]))
    n = load_config("mb3", over).orbit_rate
    assert lqr.points[0].gain.margin >= 0.1
    point = lmi.points[0]
    assert point.gain.lmi.certified_margin >= 0.1 and point.gain.lmi.rejected == ()
    assert _certificate_holds(point.model, n, point.gain.lmi)


def test_without_cvxopt_the_route_names_the_missing_solver_and_uses_clarabel(mb3_model, monkeypatch):
    """cvxopt (GPL-3) is optional: where it is not installed the default ``conelp`` is named in a
    warning and Clarabel solves (here a fake Clarabel, whose refused answer ends the design)."""
    monkeypatch.setattr(rl, "ROUTES", {"clarabel": _fake_route("zero")})
    monkeypatch.setattr(rl, "SOLVERS", ("clarabel",))
    with pytest.raises(DesignError, match=r"\(clarabel: worst sector margin"), \
            pytest.warns(RuntimeWarning, match="'conelp' is not installed"):
        _design(mb3_model)
