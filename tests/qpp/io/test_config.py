"""qpp on plants of the user's own (a review's findings): stated sectors that do not hold φ,
channel counts the circle criterion cannot take, scenario parameters out of range, round-off in
N = G⁺B, a printed H of zeros."""
import numpy as np
import pytest
import yaml

from acmm_qpp.errors import ConfigError
from qpp.io.config import load_config, parse_config


def _base(**edits):
    data = {
        "name": "base",
        "plant": {"A": [[0, 1], [2, -1]], "B": [[0], [1]], "C": [[2, -1]], "G": [[0], [1]],
                  "Ac": [[0]], "Bc": [[1]], "Cc": [[1]]},
        "nonlinearity": {"kind": "expression", "f1": ["k*sat(y1, 0.5)"],
                         "parameters": {"k": {"min": -0.3, "max": 0.3, "nominal": 0.0}},
                         "y_range": [[-2, 2]]},
        "hinf": {"rho": 1e-2, "a": 1e-4, "search": True},
        "spheres": {"beta_o": 0.5, "beta_ri": 0.05, "T": 1.0},
        "design": {},
        "simulation": {"t_final": 10.0, "n_samples": 101, "r_o": [[{"kind": "step", "amplitude": 0.3}]],
                       "scenarios": [{"name": "kmax", "parameters": {"k": 0.3}}]},
        "output": {"root": "runs", "figures": False},
    }
    for path, value in edits.items():
        node = data
        keys = path.split(".")
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value
    return data


@pytest.mark.parametrize("field", ["nonlinearity.sector", "design.sector"])
def test_a_stated_sector_narrower_than_phi_is_refused(field):
    # φ = k·sat(y, 0.5), |k| ≤ 0.3: its sector is ±0.3 (exactly, at |y| ≤ 0.5)
    with pytest.raises(ConfigError, match=r"does not hold φ_1.*\[-0\.3, 0\.3\]"):
        parse_config(_base(**{field: [[-0.01, 0.01]]}))
    parse_config(_base(**{field: [[-0.3, 0.3]]}))            # the exact sector, stated: accepted
    parse_config(_base(**{field: [[-0.5, 0.4]]}))            # wider: accepted


def test_a_sinusoidal_plant_needs_as_many_phi_channels_as_outputs():
    data = _base(**{"plant.A": [[0, 1, 0], [0, 0, 1], [-1, -2, -2]], "plant.B": [[0], [0], [1]],
                    "plant.C": [[1, 0, 0], [0, 1, 0]], "plant.G": [[0], [0], [1]], "plant.Bc": [[1, 0]],
                    "nonlinearity": {"kind": "sinusoidal", "F0": [[0.0, 0.0]], "F1": [[0.1, 0.0]],
                                     "F_unc": [[1.0, 0.0]], "omega": 1.0, "gamma_max": 0.05},
                    "simulation.r_o": [[{"kind": "step", "amplitude": 0.5}], [{"kind": "step", "amplitude": 0.0}]],
                    "simulation.scenarios": [{"name": "g", "gamma": 0.05}]})
    with pytest.raises(ConfigError, match="as many disturbance channels as outputs"):
        parse_config(data)


@pytest.mark.parametrize("name, gamma, ok", [("qpp_siso", 5.0, False), ("qpp_siso", -0.05, True),
                                             ("qpp_manipulator", 0.0, False), ("qpp_manipulator", 1000.0, False),
                                             ("qpp_manipulator", 50.0, True)])
def test_scenario_gamma_within_the_nonlinearity_range(name, gamma, ok):
    over = [f"simulation.scenarios.0.gamma={gamma}"]
    if ok:
        load_config(name, over)
    else:
        with pytest.raises(ConfigError, match="gamma .* outside"):
            load_config(name, over)
    with pytest.raises(ConfigError, match="takes gamma, not parameters"):
        load_config(name, ["simulation.scenarios.0.parameters={dm: 1}"])


def test_round_off_in_N_does_not_couple_the_phi_channels():
    """B = G with a column that lstsq returns with 1e-16 off-diagonal entries: N is I exactly, so
    each φ_i depends on its own output only (one-sided sectors stay one-sided)."""
    data = _base(**{"plant.A": [[0, 1, 0, 0], [-2, -1, 0, 0], [0, 0, 0, 1], [0, 0, -3, -2]],
                    "plant.B": [[0, 0], [0, 0], [1, 0.5], [0, 1]], "plant.G": [[0, 0], [0, 0], [1, 0.5], [0, 1]],
                    "plant.C": [[1, 0, 0, 0], [0, 0, 1, 0]], "plant.Ac": [[0, 0], [0, 0]],
                    "plant.Bc": [[1, 0], [0, 1]], "plant.Cc": [[1, 0], [0, 1]],
                    "nonlinearity.f1": ["k*sat(y1, 0.4)", "k*sat(y2, 0.4)"],
                    "nonlinearity.parameters": {"k": {"min": 0.0, "max": 0.5, "nominal": 0.0}},
                    "nonlinearity.y_range": [[-2, 2], [-2, 2]],
                    "simulation.r_o": [[{"kind": "step", "amplitude": 0.1}], [{"kind": "step", "amplitude": 0.0}]]})
    cfg = parse_config(data)
    N = cfg.lure_plant().N()
    np.testing.assert_array_equal(N, np.eye(2))
    info = cfg.expression_model().sector_info
    assert info.diagonal.all()
    np.testing.assert_allclose(info.sector, [[0.0, 0.5], [0.0, 0.5]], atol=1e-9)


def test_a_printed_H_of_zeros_is_no_difference_to_report(tmp_path):
    from typer.testing import CliRunner

    from qpp.cli import app

    r = CliRunner().invoke(app, ["design", "qpp_siso", f"output.root={tmp_path}", "--no-figures",
                                 "published.H=[[0],[0]]"])
    assert r.exit_code in (0, 3), r.output
    assert "Traceback" not in r.output and r.exception is None or isinstance(r.exception, SystemExit)
    assert (tmp_path / "qpp_siso" / "qpp_design.h5").is_file()
    assert yaml.safe_load((tmp_path / "qpp_siso" / "config.yaml").read_text())["name"] == "qpp_siso"


def test_a_saturation_on_a_wide_output_range_is_sector_bounded():
    """k·sat(y, 0.5) on |y| ≤ 1e6: φ/y steps from 0.3 (|y| < 0.5) down between the grid's points
    near 0; that is a corner, not growth without bound (√|y| still is refused)."""
    info = parse_config(_base(**{"nonlinearity.y_range": [[-1e6, 1e6]]})).expression_model().sector_info
    np.testing.assert_allclose(info.sector, [[-0.3, 0.3]], atol=1e-9)
    for rng in ([[-2, 2]], [[-1e6, 1e6]]):
        with pytest.raises(ConfigError, match="not sector-bounded near y = 0"):
            parse_config(_base(**{"nonlinearity.y_range": rng, "nonlinearity.f1": ["k*sign(y1)*abs(y1)**0.5"]}))


def test_a_supremum_in_a_basin_the_grid_does_not_lead_to_is_found():
    """φ/y = −(c − 1)y² + (sin wt − sin 2t)/2 (f1 = −c y³ + y sin(wt)/2, nominal c = 1, w = 2):
    its supremum 1.125 + 1 = 2.125 at y = ±1.5, c = 0.5, sin wt = 1 = −sin 2t (w = 10/7,
    t = 7π/4) lies among many local maxima in (w, t); the grid's best point climbed to 2.078."""
    data = _base(**{"plant.A": [[0, 1], [-1, -0.5]], "plant.C": [[1, 0]],
                    "nonlinearity.f1": ["-c*y1**3 + 0.5*y1*sin(w*t)"],
                    "nonlinearity.parameters": {"c": {"min": 0.5, "max": 1.5, "nominal": 1.0},
                                                "w": {"min": 1.0, "max": 3.0, "nominal": 2.0}},
                    "nonlinearity.y_range": [[-1.5, 1.5]], "nonlinearity.t_range": 10.0,
                    "simulation.scenarios": [{"name": "c05", "parameters": {"c": 0.5, "w": 1.4285714}}]})
    info = parse_config(data).expression_model().sector_info
    exact = 0.5 * 1.5 ** 2 + 1.0
    np.testing.assert_allclose(info.sector, [[-exact, exact]], rtol=1e-7)


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


def test_a_scenario_cannot_take_the_cartesian_figures_name():
    """The polar arm writes qpp_sim_cartesian.png beside qpp_sim_<scenario>.png: a scenario named
    'cartesian' lost one of the two figures silently; it is refused, elsewhere allowed."""
    with pytest.raises(ConfigError, match="'cartesian' is the polar arm's cartesian figure"):
        load_config("qpp_manipulator", ["simulation.scenarios.0.name=cartesian"])
    assert load_config("qpp_siso", ["simulation.scenarios.0.name=cartesian"]).simulation.scenarios[0].name == "cartesian"


@pytest.mark.slow
@pytest.mark.parametrize("f1, codes", [("k*y1*0", (0,)), ("k*y1*1e-318", (0, 4))])
def test_a_zero_or_denormal_nonlinearity_is_designed_without_a_traceback(tmp_runs, f1, codes):
    """φ ≡ 0 samples to the sector [0, 0], φ = 1e-318·k·y to a denormal one that scales to
    [-0, 0]: both used to end in "ValueError: need alpha < beta" with a traceback.  The flat
    sector is widened by 1e-12 (as a zero sinusoidal one); a scale that underflows is not a
    sector.  The results are written (exit 4 at most: a figure of the denormal case)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    r = CliRunner().invoke(app, ["design", "qpp_saturation", f'nonlinearity.f1=["{f1}"]'])
    assert r.exit_code in codes, r.output
    assert "Traceback" not in r.output and r.exception is None or isinstance(r.exception, SystemExit)
    assert (tmp_runs / "runs" / "qpp_saturation" / "qpp_design.h5").is_file()


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


@pytest.mark.parametrize("plant, words", [
    (([[1, 0], [0, -2]], [[0], [1]], [[1, 1]]), "not controllable from u"),
    (([[1, 0], [0, -2]], [[1], [1]], [[0, 1]]), "not observable from y"),
    (([[0, 1], [2, -1]], [[0], [1]], [[1, -1]]), "not observable from y"),        # zero cancels the pole
    (([[0, 1], [-1, -0.5]], [[0], [1]], [[0, 1]]), "servo-compensator's pole at s = 0"),
])
def test_a_structurally_impossible_plant_names_its_obstacle(plant, words):
    """No gains of eqs 10.5–10.6 exist: the failure says why (PBH tests), not only that none was found."""
    from qpp.model.lure import LurePlant, structural_obstacles

    A, B, C = plant
    why = structural_obstacles(LurePlant(A, B, C, B, [[0]], [[1]], [[1]]))
    assert len(why) == 1 and words in why[0]
    # the same structure without the obstacle (C = [2, −1]: observable, no zero at 0) has none
    assert structural_obstacles(LurePlant([[0, 1], [2, -1]], [[0], [1]], [[2, -1]], [[0], [1]],
                                          [[0]], [[1]], [[1]])) == []


def test_a_large_reference_is_not_a_divergence(tmp_path):
    """The ch. 13 loop tracking r_o = 1e7·sin 5t: a stable loop with large signals, not a divergence
    (the threshold is relative to the nominal loop's size, not 1e6 in the output's units)."""
    from qpp.simulate.closed_loop import simulate

    big = load_config("qpp_siso", ["simulation.r_o=[[{kind: sin, amplitude: 1.0e7, omega: 5.0}]]",
                                   "simulation.n_samples=201"])
    p = big.published
    for s in simulate(big, p.K1, p.Kc, p.H):
        assert s.diverged_at is None and np.isfinite(s.error_inf) and np.all(np.isfinite(s.y))


def test_a_badly_scaled_plant_has_no_false_obstacle():
    """A = [[0, 1e6], [0, 0]], B = [0; 1e-4]: controllable (rank 2), observable from y = x1, no
    zero at the integrator's pole; a rank test relative to max|A| called it uncontrollable."""
    from qpp.model.lure import LurePlant, structural_obstacles

    A, B, C = np.array([[0.0, 1e6], [0.0, 0.0]]), np.array([[0.0], [1e-4]]), np.array([[1.0, 0.0]])
    assert np.linalg.matrix_rank(np.hstack([B, A @ B])) == 2                   # independent: Kalman rank
    assert structural_obstacles(LurePlant(A, B, C, B, [[0]], [[1]], [[1]])) == []


def _mass_on_integrator(name, f1, *, beta_o, step, delta_r=None):
    """A review's plant: a damped mass tracking a step of ``step`` through an integrator servo,
    φ = ``f1`` with k ∈ [−0.8, 0.8], β_ri = 0.004, simulated 8 s, one scenario at k = 0.8."""
    scenario = {"name": "kmax", "parameters": {"k": 0.8}, **({"delta_r": delta_r} if delta_r else {})}
    return {"name": name,
            "plant": {"A": [[0, 1], [0, -0.5]], "B": [[0], [1]], "C": [[1, 0]], "G": [[0], [1]],
                      "Ac": [[0]], "Bc": [[1]], "Cc": [[1]]},
            "nonlinearity": {"kind": "expression", "f1": [f1],
                             "parameters": {"k": {"min": -0.8, "max": 0.8, "nominal": 0}}, "y_range": [[-3, 3]]},
            "hinf": {"rho": 0.1, "a": 1.0e-4}, "spheres": {"beta_o": beta_o, "beta_ri": 0.004, "T": 1.0},
            "design": {"a_max": 1.0e-2, "rho_min": 0.05, "wider_search": False},
            "simulation": {"t_final": 8.0, "n_samples": 401, "r_o": [[{"kind": "step", "amplitude": step}]],
                           "scenarios": [scenario]},
            "output": {"root": "runs", "figures": False}}


def test_nothing_to_track_is_no_reason_for_a_vanishing_T(tmp_runs):
    """r_o ≡ 0: the nominal loop 'settles' at t = 0, T fell to 1e-3·t_final, β3 = k‖(1)_T‖₂ to ~0
    and a design was certified whose simulation leaves the output sphere (a review's case: k at
    the end of its range, ‖δr‖∞ = β_ri, ‖y − y_o‖∞ = 0.0072 > β_o = 0.006).  T is now the
    settling time of the loop's slowest mode: no certificate, and the simulation agrees."""
    import h5py
    from typer.testing import CliRunner

    from qpp.cli import app

    cfg = _mass_on_integrator("regulate", "k*y1", beta_o=0.006, step=0.0,
                              delta_r=[[{"kind": "sin", "amplitude": 0.004, "omega": 1.0}]])
    (tmp_runs / "reg.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "reg.yaml"])
    assert r.exit_code == 3 and "hint: no tracking loop meets these spheres" in r.output, r.output
    CliRunner().invoke(app, ["simulate", "reg.yaml"])
    with h5py.File(tmp_runs / "runs" / "regulate" / "qpp_design.h5") as f:
        certified, T = int(f.attrs["certified"]), float(f["certificate/T_settle"][()])
    with h5py.File(tmp_runs / "runs" / "regulate" / "qpp_sim.h5") as f:
        err = float(f["kmax/error_inf"][()])
    assert err > 0.006                        # the simulation leaves the sphere ...
    assert certified == 0, r.output           # ... so no certificate may claim it
    assert T > 1.0                            # the slowest mode's settling time, not 0.008 s


def test_a_nominal_loop_that_never_settles_is_named(tmp_runs):
    """A servo-compensator that does not model the step r_o (Ac = −1): the nominal loop never
    settles, T took the horizon and the certificate silently depended on t_final (review)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    plant = {"A": [[0, 1], [2, -1]], "B": [[0], [1]], "C": [[1, 0]], "G": [[0], [1]], "Ac": [[-1]],
             "Bc": [[1]], "Cc": [[1]]}
    cfg = {"name": "nosettle", "plant": plant,
           "nonlinearity": {"kind": "expression", "f1": ["-k*sat(y1, 0.5)"],
                            "parameters": {"k": {"min": 0.8, "max": 1.2}}, "y_range": [[-3, 3]]},
           "hinf": {"rho": 0.1, "a": 1.0e-4, "search": True},
           "spheres": {"beta_o": 0.3, "beta_ri": 0.05, "T": 1.0}, "design": {"a_max": 1.0e-2},
           "simulation": {"t_final": 5.0, "n_samples": 201, "r_o": [[{"kind": "step", "amplitude": 1.0}]],
                          "scenarios": [{"name": "kmin", "parameters": {"k": 0.8}}]},
           "output": {"root": "runs", "figures": False}}
    (tmp_runs / "ns.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "ns.yaml"])
    assert "warning: the nominal loop does not settle within 5 s" in r.output, r.output
    cfg["plant"]["Ac"] = [[0]]                        # an integrator models the step: it settles
    (tmp_runs / "ns.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "ns.yaml"])
    assert "does not settle" not in r.output, r.output


def test_a_nonlinearity_that_switches_on_after_T_is_named(tmp_runs):
    """φ = k·y·(sat(10(t − 3)) + 1)/2 is off on [0, T] and on after 3 s: β3 = β4 = 0 and a
    certificate that the simulation beyond T contradicted (26 β_o; review).  The design now warns
    that the certificate (on [0, T], eqs 10.53–10.54) does not reach beyond T; a periodic φ (the
    ch. 13 form, sin t) is as stiff within T as after it: no warning."""
    from typer.testing import CliRunner

    from qpp.cli import app
    from qpp.design.certificate import late_slope
    from qpp.io.config import load_config

    cfg = _mass_on_integrator("late", "k*y1*(sat(10*(t-3), 1) + 1)/2", beta_o=0.02, step=1.0)
    (tmp_runs / "late.yaml").write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["design", "late.yaml"])
    assert "warning: the nonlinearity is stiffer after T" in r.output, r.output
    before, after = late_slope(load_config(str(tmp_runs / "late.yaml")), 2.0, 8.0)
    assert before == pytest.approx(0.0, abs=1e-9) and after == pytest.approx(0.8, rel=1e-6)
    assert late_slope(load_config("qpp_unstable"), 2.0, 10.0) is None


def test_a_slow_mode_beyond_the_horizon_is_named_with_nothing_to_track(tmp_runs):
    """r_o ≡ 0 on the ch. 13 loop: T is its slowest mode's settling time, ln 20/0.1005 = 29.8 s,
    beyond the 10 s horizon; the warning blamed the servo-compensator (review)."""
    from typer.testing import CliRunner

    from qpp.cli import app

    import re

    import h5py

    r = CliRunner().invoke(app, ["design", "qpp_siso", "spheres.adapt_T=true",
                                 "simulation.r_o=[[{kind: step, amplitude: 0.0}]]"])
    said = re.search(r"the loop's slowest mode settles in ([0-9.]+) s", r.output)
    assert said and "plant.Ac" not in r.output, r.output
    # independent: ln(1/band)/min(−Re λ) of the stored closed loop, eigenvalues by numpy
    with h5py.File(tmp_runs / "runs" / "qpp_siso" / "qpp_design.h5") as f:
        decay = float(np.min(-np.linalg.eigvals(f["Az"][()]).real))
    assert float(said.group(1)) == pytest.approx(np.log(20.0) / decay, rel=1e-3)
    assert float(said.group(1)) > 10.0                        # beyond the 10 s horizon
