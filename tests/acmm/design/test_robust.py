"""One gain for a family of inertias (acmm.design.robust, issue 41 items 1–2).

The certificates are re-verified here from the stored matrices with our own formulas: the
half-plane and cone LMIs of each plant's closed loop, built from ``design.h5``'s family (inertia,
TEA → our own linearization through :func:`acmm.model.linearize.design_point`) and checked by
symmetric eigenvalues of the LMIs themselves (not of the whitened loop the code uses); the
family's members are rigid bodies at equilibria (residual of eqs 4.1–4.3 by
:func:`acmm.model.tea.equilibrium_residual`) connected to the design TEA.  The ±30 % Monte Carlo
of the fixed robust gain on the packaged sweep's draws (which the family never saw: another seed)
is in the slow group.
"""
from __future__ import annotations

import collections
import dataclasses

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from acmm.cli.app import app
from acmm.design.robust import RobustSettings, _plant_family, _region_certificate
from acmm.io.config import load_config
from acmm.model import linearize as lin
from acmm.model.inertia import unphysical_reason
from acmm.model.tea import equilibrium_residual
from acmm_qpp.errors import ConfigError

N = 0.0011


def _lmis_hold(Acl, X, decay, cone_deg, tol=1e-9):
    """He(Acl X) + 2·decay·X ⪯ 0 and the cone LMI of half-angle cone_deg hold for X ≻ 0 (the
    LMIs of Chilali & Gahinet 1996 themselves, scaled by ‖X‖)."""
    if np.min(np.linalg.eigvalsh(X)) <= 0:
        return False
    M = Acl @ X
    half = M + M.T + 2 * decay * X
    phi = np.radians(cone_deg)
    cone = np.block([[np.sin(phi) * (M + M.T), np.cos(phi) * (M - M.T)],
                     [np.cos(phi) * (M.T - M), np.sin(phi) * (M + M.T)]])
    scale = np.linalg.norm(M, 2)
    return bool(np.max(np.linalg.eigvalsh(half)) <= tol * scale and np.max(np.linalg.eigvalsh(cone)) <= tol * scale)


def test_region_certificate_proves_what_the_poles_allow():
    """A random stable loop: the certified decay and cone are within 1e-6 of what the poles show
    (the certificate is tight for X = Re(VVᴴ)), and the LMIs hold with them, not with more."""
    rng = np.random.default_rng(3)
    V = rng.normal(size=(6, 6))            # poles −0.3 ± 0.2j, −1, −2 ± 1.5j, −0.7
    T = np.zeros((6, 6))
    T[0:2, 0:2] = [[-0.3, 0.2], [-0.2, -0.3]]
    T[2, 2], T[5, 5] = -1.0, -0.7
    T[3:5, 3:5] = [[-2.0, 1.5], [-1.5, -2.0]]
    A = V @ T @ np.linalg.inv(V)
    c = _region_certificate(A, np.zeros((6, 1)), np.zeros((1, 6)))
    assert c.decay == pytest.approx(0.3, abs=1e-6) and c.max_real == pytest.approx(-0.3, abs=1e-9)
    assert c.cone_deg == pytest.approx(np.degrees(np.arctan(1.5 / 2.0)), abs=1e-5)
    assert _lmis_hold(A, c.X, c.decay, c.cone_deg)
    assert not _lmis_hold(A, c.X, c.decay + 1e-3, c.cone_deg)
    assert not _lmis_hold(A, c.X, c.decay, c.cone_deg - 0.1)
    # an unstable loop is not certified: no decay, no cone
    u = _region_certificate(-A, np.zeros((6, 1)), np.zeros((1, 6)))
    assert not u.decay > 0 and np.isnan(u.cone_deg)


def test_family_members_are_connected_rigid_body_equilibria():
    cfg = load_config("mb3")
    I0 = cfg.inertia.matrix()
    from acmm.model.tea import resolve_bias, solve_tea

    b0 = resolve_bias(cfg.disturbance, I0, N)
    th0 = solve_tea(I0, N, b0, expected=cfg.disturbance.requested_tea()).theta
    fam = _plant_family(I0, b0, th0, N, RobustSettings(30, 8, 5))
    assert fam.labels[0] == "nominal" and fam.labels[-2:] == ("scale 0.7", "scale 1.3")
    assert len(fam.labels) == 11 and fam.draws == 8 + fam.unphysical + fam.folded and fam.scalings_folded == ()
    assert np.allclose(fam.inertia[-1], 1.3 * I0) and np.allclose(fam.inertia[0], I0)
    for I, th in zip(fam.inertia, fam.theta):
        assert unphysical_reason(I) is None
        assert np.max(np.abs(equilibrium_residual(th, I, N, b0))) < 1e-6 * np.max(np.abs(b0))
    ratio = fam.inertia[1:-2] / I0                      # element draws within ±30 %
    assert np.all(np.abs(ratio - 1) <= 0.3 + 1e-12)
    # the same settings draw the same family; another seed another one
    again = _plant_family(I0, b0, th0, N, RobustSettings(30, 8, 5))
    assert np.array_equal(again.inertia, fam.inertia)
    assert not np.allclose(_plant_family(I0, b0, th0, N, RobustSettings(30, 8, 6)).inertia[1], fam.inertia[1])


@pytest.fixture(scope="module")
def robust_mb3(tmp_path_factory):
    """``acmm design mb3 design.robust.inertia_percent=30`` (the report's route as the start)."""
    root = tmp_path_factory.mktemp("robust")
    res = CliRunner().invoke(app, ["design", "mb3", "design.robust.inertia_percent=30", f"output.root={root}",
                                   "--no-figures"])
    return res, root / "mb3" / "design.h5"


def test_robust_design_from_the_command_line(robust_mb3):
    res, path = robust_mb3
    assert res.exit_code == 0, res.output
    assert "robust gain at mb3: 23 plants" in res.output
    lines = [ln for ln in res.output.splitlines() if ln.startswith("    ") and ("draw" in ln or "scale" in ln
                                                                               or "nominal" in ln)]
    verdicts = collections.Counter(ln.split("  ")[-1].strip() for ln in lines)
    # the sector LQR start: every plant proved stable, none in the sector (the search leaves the cone free)
    assert len(lines) == 23 and verdicts == {"stable, not in the sector": 23}, verdicts
    assert "every plant is certified in Re <= -" in res.output and "NOT proved stable" not in res.output


def test_robust_certificates_reverified_from_design_h5(robust_mb3):
    """Every plant's certificate, from the stored inertia, TEA, K and X and our own LMI check;
    the stored verdicts agree."""
    _, path = robust_mb3
    with h5py.File(path) as f:
        g = f["points"][list(f["points"])[0]]
        K = g["K"][()]
        scales = g["scales"][()]
        r = g["robust"]
        inertia, tea, X = r["inertia"][()], r["tea"][()], r["X"][()]
        decay, cone = r["certified_decay"][()], np.degrees(r["certified_cone"][()])
        held = r["sector_held"][()]
        nominal_K = r["nominal_K"][()]
    assert inertia.shape == (23, 3, 3) and X.shape == (23, 24, 24)
    assert not np.allclose(K, nominal_K)
    for I, th, Xi, a, c in zip(inertia, tea, X, decay, cone):
        m = lin.design_point(I, th, N, model="coupled", drf_mode="attitude_hold")
        Acl = (m.A - m.B @ K) / scales[:, None] * scales[None, :] / N
        assert a > 0
        assert _lmis_hold(Acl, Xi, a, c, tol=1e-7)
        assert np.max(np.linalg.eigvals(Acl).real) <= -a + 1e-9
    assert np.array_equal(held, (decay >= 0.5) & (cone <= 45.0))


def test_robust_settings_are_validated():
    with pytest.raises(ConfigError, match="inertia_percent"):
        load_config("mb3", ["design.robust.inertia_percent=-1"])
    with pytest.raises(ConfigError, match="samples"):
        load_config("mb3", ["design.robust.samples=0"])


@pytest.mark.slow
@pytest.mark.parametrize("base", ["mb3", "ac"])
def test_robust_gain_on_the_packaged_draws(base):
    """Issue 41 item 2, on the packaged sweep's 200 ±30 % draws (seed 185644; the family's seed
    is 1): the fixed robust gain (LMI route start) keeps ≥ 150/200 MB3 draws bounded and settled
    and tolerates a uniform scaling over at least [0.7, 1.3].  At AC the draws whose design
    branch folds (no equilibrium connected to the design TEA: the case starts at the root
    continued from LVLH) and those with no equilibrium at all are out of any fixed gain's reach
    here; of the others ≥ 90 % are bounded and settled (the target of 150/200 is out of reach:
    tested as the evidence, docs/results/robustness.md)."""
    from acmm.sweep.case import margin_search, prepare_base, run_case
    from acmm.sweep.config import load_sweep

    sw = load_sweep("configs/sweep_inertia30.yaml")
    b = next(x for x in sw.bases if x.label == base)
    cfg = load_config(base, ["design.pole_method=lmi", "design.robust.inertia_percent=30"])
    ctx = prepare_base(dataclasses.replace(b, config=cfg), sw.spec)
    rows = [run_case(ctx, i) for i in range(200)]
    verdicts = collections.Counter(r["verdict"] for r in rows)
    lo, hi = margin_search(ctx, "down")["limit"], margin_search(ctx, "up")["limit"]
    assert lo <= 0.7 and hi >= 1.3
    if base == "mb3":
        assert verdicts["bounded"] >= 150
    else:
        folded = [r for r in rows if "folds" in r.get("reason", "")]
        reach = [r for r in rows if "folds" not in r.get("reason", "")]
        assert len(folded) + len(reach) == 200 and len(folded) >= 90
        assert sum(r["verdict"] == "bounded" for r in reach) >= 0.9 * len(reach)
