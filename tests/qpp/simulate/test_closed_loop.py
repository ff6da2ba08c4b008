"""qpp simulations (qpp.simulate.closed_loop): the sphere checks of 13.4 and 14.5, a diverging
scenario or nominal loop as a result, a large reference that is no divergence."""
import numpy as np
import pytest
import yaml

from qpp.io.config import load_config, parse_config
from qpp.simulate.closed_loop import simulate

from tests.qpp.conftest import _base


def test_siso_scenarios_meet_output_sphere():
    cfg = load_config("qpp_siso")
    p = cfg.published
    res = {r.name: r for r in simulate(cfg, p.K1, p.Kc, p.H)}
    # report: < 0.094 (Fig 13.5) and < 0.16 (Fig 13.9); sphere 0.2
    assert res["step_offset"].error_inf < 0.094
    assert res["sin10"].error_inf < 0.16
    assert all(r.passed for r in res.values())
    # the perturbation really is in the input sphere: ||r - r_o||inf = 0.1
    for r in res.values():
        assert np.max(np.abs(r.r - r.r_o)) == pytest.approx(0.1, abs=1e-3)


def test_manipulator_masses_meet_output_sphere():
    cfg = load_config("qpp_manipulator")
    p = cfg.published
    res = simulate(cfg, p.K1, p.Kc, p.H)
    assert [r.gamma for r in res] == [45.0, 50.0, 55.0]
    for r in res:
        assert r.error_inf <= 0.14
    # the path ends near Cartesian [0, -1.5] m with Y_A1 = (x1 + a) sin x2, Y_A2 = (x1 + a) cos x2
    y = res[1].y_o[:, -1]
    assert (y[0] + 1.0) * np.sin(y[1]) == pytest.approx(0.0, abs=0.02)
    assert (y[0] + 1.0) * np.cos(y[1]) == pytest.approx(-1.5, abs=0.02)


def test_a_diverging_scenario_is_a_result_not_a_failure(tmp_path):
    """φ = 3·y fed back with + destabilizes the loop (eigenvalue check): a long run diverges; the
    scenario is reported OUTSIDE with the time it diverged, the other scenario as usual."""
    from qpp.cli import app
    from typer.testing import CliRunner
    from qpp.model.lure import closed_loop

    data = _base(**{"plant.A": [[0, 1], [-1, -0.5]], "plant.C": [[1, 0]], "nonlinearity.f1": ["k*y1"],
                    "nonlinearity.parameters": {"k": {"min": 0.0, "max": 3.0, "nominal": 0.0}},
                    "design": {"gains": "published"},
                    "published": {"K1": [[-4.0, -3.0]], "Kc": [[3.0]], "H": [[-4.0], [-4.0]]},
                    "simulation.t_final": 3000.0, "simulation.n_samples": 3001,
                    "simulation.scenarios": [{"name": "k3", "parameters": {"k": 3.0}},
                                             {"name": "k1", "parameters": {"k": 1.0}}],
                    "output.root": str(tmp_path)})
    cfg = parse_config(data)
    Az, Bz, Cz = closed_loop(cfg.lure_plant(), *(np.array(v, float) for v in ([[-4, -3]], [[3]], [[-4], [-4]])))
    assert np.linalg.eigvals(Az + 3.0 * Bz[:, 1:] @ Cz).real.max() > 0       # k = 3: unstable
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(data))
    r = CliRunner().invoke(app, ["simulate", str(tmp_path / "c.yaml"), "--no-figures"])
    assert r.exit_code == 0, r.output
    assert "k3" in r.output and "DIVERGED at t =" in r.output and "OUTSIDE" in r.output
    import h5py

    with h5py.File(tmp_path / "base" / "qpp_sim.h5", "r") as f:
        assert np.isinf(f["k3/error_inf"][()]) and 0 < f["k3/error_inf"].attrs["diverged_at_s"] < 3000
        assert not f["k3/error_inf"].attrs["passed"]
        assert np.isfinite(f["k1/error_inf"][()]) and "diverged_at_s" not in f["k1/error_inf"].attrs


def test_an_unstable_nominal_loop_is_a_result_not_an_integrator_error(tmp_runs):
    """The ch. 13 gains on a plant with a pole at +120 rad/s: the nominal loop itself grows until
    the integrator fails (it used to exit 3, "Required step size ..."); now every scenario is
    DIVERGED, exit 0 (1 with --strict), the results written with the time each diverged."""
    import h5py
    from typer.testing import CliRunner

    from qpp.cli import app

    args = ["simulate", "qpp_siso", "design.gains=published", "plant.A=[[0,1],[0,120]]", "--no-figures"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    assert r.output.count("DIVERGED at t =") == 2 and "Traceback" not in r.output
    with h5py.File(tmp_runs / "runs" / "qpp_siso" / "qpp_sim.h5", "r") as f:
        for name in ("step_offset", "sin10"):
            assert np.isinf(f[f"{name}/error_inf"][()]) and not f[f"{name}/error_inf"].attrs["passed"]
            assert 0 < f[f"{name}/error_inf"].attrs["diverged_at_s"] < 1.0
    assert CliRunner().invoke(app, args + ["--strict"]).exit_code == 1


def test_a_large_reference_is_not_a_divergence(tmp_path):
    """The ch. 13 loop tracking r_o = 1e7·sin 5t: a stable loop with large signals, not a divergence
    (the threshold is relative to the nominal loop's size, not 1e6 in the output's units)."""
    from qpp.simulate.closed_loop import simulate

    big = load_config("qpp_siso", ["simulation.r_o=[[{kind: sin, amplitude: 1.0e7, omega: 5.0}]]",
                                   "simulation.n_samples=201"])
    p = big.published
    for s in simulate(big, p.K1, p.Kc, p.H):
        assert s.diverged_at is None and np.isfinite(s.error_inf) and np.all(np.isfinite(s.y))
