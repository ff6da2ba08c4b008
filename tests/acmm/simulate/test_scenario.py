"""Per-level statistics of a simulation (acmm.simulate.scenario.level_statistics): taken over
every integrator step, whatever the output sampling."""
import h5py
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from acmm.simulate import kernel
from acmm.io.config import load_config
from acmm.stages.simulate import run_simulate

from tests.conftest import LQR_ROUTE


def test_level_statistics_do_not_depend_on_the_output_sampling(tmp_path):
    """Per-level peak momentum and steady error came from the output samples: 9.58° at 60 s but
    1.10° at 2800 s on a review's station.  They are now tracked at every integrator step; an
    independent dense solve_ivp of the same closed loop (the kernel's own right-hand side) bounds
    them from below."""
    from scipy.integrate import solve_ivp

    import acmm.simulate.kernel as sm
    from acmm.simulate import scenario as scen

    cfg = load_config("mb3", ["simulation.orbits=2", "output.figures=false", f"output.root={tmp_path}"])
    stats = {}
    for si in (60.0, 2800.0):
        res, _ = run_simulate(load_config("mb3", ["simulation.orbits=2", "output.figures=false",
                                                  f"output.root={tmp_path}", f"simulation.sample_interval={si}",
                                                  f"name=si{int(si)}"]))
        stats[si] = (res.stats[0]["steady_error_deg"], res.stats[0]["peak_momentum"])
    np.testing.assert_allclose(stats[60.0][0], stats[2800.0][0], rtol=2e-2)
    assert stats[60.0][1] == pytest.approx(stats[2800.0][1], rel=2e-3)
    # independent: dense RK45 on the kernel's rhs over the same 2 orbits
    res, _ = run_simulate(cfg)
    sc = res.scenario
    sol = solve_ivp(lambda t, x: kernel.kernel_rhs(sc, t, x)[0], (0.0, sc.t_end), sc.x0, rtol=1e-9,
                    atol=sc.atol * 1e-2, dense_output=True, max_step=50.0)
    tt = np.linspace(0.0, sc.t_end, 20001)
    X = sol.sol(tt)
    peak = np.abs(X[6:9]).max()
    assert stats[60.0][1] == pytest.approx(peak, rel=2e-3)
    half = tt >= 0.5 * sc.t_end
    steady = np.degrees(np.abs(X[3:6, half] - sc.theta_est[0][:, None]).max(axis=1))
    np.testing.assert_allclose(stats[60.0][0], steady, rtol=2e-2, atol=1e-4)


def test_a_level_without_a_sample_in_its_second_half_keeps_its_statistics(tmp_path):
    """Levels of 0.3 orbit sampled every 3000 s: level 0 has no sample in the second half of its
    dwell; its steady error was dropped (NaN, 'the run ended before it') although the kernel had
    tracked it (review)."""
    res, path = run_simulate(load_config("staircase", [
        "name=sparse", *LQR_ROUTE, "schedule.n_points=3", "schedule.fit=least_squares", "schedule.n_check=2",
        "simulation.orbits=1", "simulation.levels=[0, 0.3, 0.6]", "simulation.sample_interval=3000",
        "output.figures=false", f"output.root={tmp_path}"]))
    assert [s["level"] for s in res.stats] == [0, 1, 2]
    with h5py.File(path) as f:
        assert np.all(np.isfinite(f["levels/steady_error"][()]))
