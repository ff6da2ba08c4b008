"""Issue 14: schedule.to by reference, netCDF layout (xarray), units (pint, SI output), the API."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from acmm.io.config import load_config, parse_config
from acmm_qpp.errors import ConfigError
from tests.conftest import CONFIGS


# ---------------------------------------------------------------- schedule.to by reference
def _staircase_data():
    return yaml.safe_load((CONFIGS / "staircase.yaml").read_text())


def test_schedule_to_file_relative_to_referring_file_or_packaged_name(tmp_path, monkeypatch):
    inline = load_config(CONFIGS / "staircase.yaml")
    sub = tmp_path / "cfgs" / "ends"
    sub.mkdir(parents=True)
    (sub / "end.yaml").write_text((CONFIGS / "ac.yaml").read_text())
    data = _staircase_data()
    data["schedule"]["to"] = "ends/end.yaml"          # relative to the referring file, not the cwd
    (tmp_path / "cfgs" / "main.yaml").write_text(yaml.safe_dump(data))
    monkeypatch.chdir(tmp_path)
    by_file = load_config(tmp_path / "cfgs" / "main.yaml")
    data["schedule"]["to"] = "ac"                     # a packaged name
    by_name = parse_config(data)
    for cfg in (by_file, by_name):
        assert cfg.schedule.to == inline.schedule.to
        assert cfg.n_design_points() == inline.n_design_points()
    data["schedule"]["to"] = "nowhere.yaml"
    with pytest.raises(ConfigError, match="schedule.to: config file not found"):
        parse_config(data)


# ---------------------------------------------------------------- API: python-control systems
def test_scheduled_closed_loop_equals_independent_linearization():
    import control
    from scipy.optimize import brentq

    from acmm import api
    from acmm.model import linearize as lin
    from acmm.model.tea import resolve_bias, solve_tea

    cfg = api.load_config("staircase")
    d = api.design(cfg)
    cl = d.scheduled_closed_loop(-20.0)
    # independent: the blend station with pitch TEA −20°, its TEA, the 24-state model, K(θ2*)
    n = cfg.orbit_rate
    i0, i1 = cfg.inertia.matrix(), cfg.schedule.to.inertia.matrix()
    b0, b1 = resolve_bias(cfg.disturbance, i0, n), resolve_bias(cfg.schedule.to.disturbance, i1, n)
    tea = lambda s: solve_tea((1 - s) * i0 + s * i1, n, (1 - s) * b0 + s * b1)  # noqa: E731
    s = brentq(lambda s: tea(s).theta[1] - np.radians(-20.0), 0.0, 1.0, xtol=1e-13)
    theta = tea(s).theta
    assert np.degrees(theta[1]) == pytest.approx(-20.0, abs=1e-8)
    m = lin.linearize((1 - s) * i0 + s * i1, theta, n)
    # the packaged table look-up: each K_ij linear in θ2* between the design points' own gains
    assert d.result.fit.form == "table"
    th = np.array([p.tea.theta[1] for p in d.result.points])
    Ks = np.array([p.lqr.K for p in d.result.points])
    K = np.array([[np.interp(theta[1], th, Ks[:, i, j]) for j in range(24)] for i in range(3)])
    scale = max(np.abs(m.A).max(), np.abs(m.B @ K).max())
    np.testing.assert_allclose(cl.A, m.A - m.B @ K, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(cl.B, np.hstack([m.B, m.G]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(cl.C[24:], -K, rtol=1e-9, atol=1e-12 * np.abs(K).max())
    assert cl.state_labels == lin.STATE_NAMES and cl.input_labels == ["v1", "v2", "v3", "w1", "w2", "w3"]
    assert cl.output_labels[-3:] == ["u1", "u2", "u3"]
    # python-control interoperates: stable loop, a step response, disk margins of the loop
    assert np.max(cl.poles().real) < 0
    resp = control.step_response(cl, T=np.linspace(0.0, 2000.0, 50), input=3, output=4)
    assert np.all(np.isfinite(resp.outputs))
    dm = control.disk_margins(d.loop_transfer(0), np.logspace(-5, -1, 100))
    assert dm[0] > 0
    ol = d.open_loop(0)
    assert ol.input_labels == ["u1", "u2", "u3", "w1", "w2", "w3"] and ol.nstates == 24
    np.testing.assert_allclose(d.closed_loop(0).A, d.result.points[0].model.A - d.result.points[0].model.B
                               @ d.result.points[0].lqr.K)


# ---------------------------------------------------------------- netCDF layout, SI output
def _short(name, tmp_path, **output):
    data = load_config(name).model_dump(mode="json")
    data["simulation"]["orbits"] = 1.0
    data["simulation"]["sample_interval"] = 600.0
    data["output"].update({"root": str(tmp_path / "runs"), "figures": False, **output})
    return parse_config(data)


def _netcdf_c_reads(path):
    """The reference netCDF-C library (netCDF4-python) opens the file and reads every variable of
    every group: the netCDF-4 claim checked by the reference implementation, not only by h5netcdf."""
    import netCDF4

    def walk(g):
        for name, v in g.variables.items():
            v.set_auto_mask(False)
            data = v[...]
            assert np.shape(data) == v.shape, (path, g.path, name)     # (a scalar text: a str)
            assert "units" in v.ncattrs(), (path, g.path, name)
        for sub in g.groups.values():
            walk(sub)

    with netCDF4.Dataset(path, "r") as ds:
        walk(ds)


def _open_all(path):
    import h5py
    import xarray as xr

    _netcdf_c_reads(path)

    groups = [None]
    with h5py.File(path, "r") as f:
        f.visit(lambda n: groups.append(n) if isinstance(f[n], h5py.Group) else None)
        # fixed-length text is declared UTF-8 (a sweep's reasons hold "ft·lbf"): h5py's asstr()
        # and netCDF-C decode it
        texts = []
        f.visititems(lambda n, o: texts.append(o) if isinstance(o, h5py.Dataset) and o.dtype.kind == "S" else None)
        for o in texts:
            assert o.id.get_type().get_cset() == h5py.h5t.CSET_UTF8, (path, o.name)
            o.asstr()[()]
    out = {}
    for g in groups:
        ds = xr.open_dataset(path, engine="h5netcdf", group=g)
        assert not [d for d in ds.dims if "phony" in str(d)], (path, g, dict(ds.sizes))
        # an array along an axis that has a name shares it (an unnamed "<var>_dim0" of the same
        # length multiplies the rows of to_dataframe(): 5 of them made design.h5's table 6e8 rows)
        auto = [d for d in ds.dims if str(d).rsplit("_dim", 1)[-1].isdigit()]
        assert not auto, (path, g, auto)
        out[g or "/"] = ds.load()
        ds.close()
    return out


@pytest.mark.slow
def test_results_open_in_xarray_with_named_dimensions_and_time(tmp_path):
    from acmm.stages.runners import run_linearize, run_tea
    from acmm.stages.simulate import run_simulate
    from qpp.io.stages import run_design as qpp_design
    from qpp.io.stages import run_simulate as qpp_simulate

    cfg = _short("mb3", tmp_path)
    _, sim_path = run_simulate(cfg)
    _, tea_path = run_tea(cfg)
    _, lin_path = run_linearize(cfg)
    sim = _open_all(sim_path)["/"]
    assert sim["t"].attrs["units"] == "s" and "orbits" in sim.coords and "t" in sim.coords
    assert sim["theta"].dims == ("t", "axis") and list(sim["axis"].values) == ["roll", "pitch", "yaw"]
    assert sim["theta"].attrs["units"] == "rad" and sim["rate_rel_lvlh"].attrs["units"] == "rad/s"
    np.testing.assert_allclose(sim["orbits"].values, sim["t"].values * cfg.orbit_rate / (2 * np.pi))
    df = sim[["theta", "h"]].to_dataframe()
    assert len(df) == sim.sizes["t"] * 3
    assert sim["theta"].sel(axis="pitch").values.shape == (sim.sizes["t"],)
    for p in (tea_path, lin_path, sim_path.parent / "design.h5"):
        _open_all(p)
    design = _open_all(sim_path.parent / "design.h5")["/"]
    assert design["K"].dims == ("point", "axis", "state") and design["state"].values[0] == "domega1"
    qcfg_path = CONFIGS / "qpp_siso.yaml"
    qdata = yaml.safe_load(qcfg_path.read_text())
    qdata["output"] = {"root": str(tmp_path / "runs"), "figures": False}
    qdata["simulation"]["n_samples"] = 201
    (tmp_path / "q.yaml").write_text(yaml.safe_dump(qdata))
    _, _, sims, qsim = qpp_simulate(tmp_path / "q.yaml")
    _, _, qdes = qpp_design(tmp_path / "q.yaml")
    q = _open_all(qsim)
    scen = q[sims[0].name]
    assert scen["y"].dims == ("t", "output") and "t" in scen.coords and scen["t"].attrs["units"] == "s"
    np.testing.assert_allclose(scen["y"].values[:, 0], sims[0].y[0])
    qd = _open_all(qdes)["/"]           # the gains carry their units (not "1": m, rad, N in ch. 14)
    assert qd["K1"].attrs["units"] == "input units per state unit"
    assert qd["Kc"].attrs["units"] == "input units per servo-state unit"
    assert qd["H"].attrs["units"] == "state units per output unit per s"


@pytest.mark.parametrize("n_runs", [2, 3])
def test_sweep_h5_opens_in_xarray(tmp_path, n_runs):
    """With 3 cases, the (case, axis) arrays were labelled (axis, axis_col) (a review):
    ``.sel(axis="pitch")`` failed for that case count only."""
    from acmm.sweep.run import run_sweep
    from acmm.sweep.config import load_sweep

    data = yaml.safe_load((CONFIGS / "sweep_smoke.yaml").read_text())
    data["output"] = {"root": str(tmp_path / "runs"), "figures": False}
    data["sweep"]["n_runs"] = n_runs
    if n_runs == 2:                         # (with 3 cases the margin groups are checked too)
        data["sweep"].pop("margin", None)
    data["sweep"]["bases"] = [str(CONFIGS / "ac.yaml")] if "bases" in data["sweep"] else None
    if data["sweep"]["bases"] is None:
        data["sweep"].pop("bases")
        data["sweep"]["base"] = str(CONFIGS / "ac.yaml")
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    r = run_sweep(load_sweep(tmp_path / "s.yaml"), workers=1)
    sw = _open_all(r.path)["/"]
    for k in ("peak_attitude_error", "steady_attitude_error", "peak_momentum", "tea_true", "tea_estimate", "bias"):
        assert sw[k].dims == ("case", "axis"), k
        assert sw[k].sel(axis="pitch").shape == (sw.sizes["case"],)
    assert sw["inertia"].dims == ("case", "axis", "axis_col")
    import h5py

    def fixed_length_text(name, obj):     # README: text variables other than coordinates
        info = h5py.check_string_dtype(obj.dtype) if isinstance(obj, h5py.Dataset) else None
        if info is not None and obj.attrs.get("CLASS") != b"DIMENSION_SCALE":
            assert info.length is not None and info.encoding == "utf-8", name
    with h5py.File(r.path) as f:
        f.visititems(fixed_length_text)
        assert f.attrs["complete"].dtype == np.int8 and f.attrs["complete"] == 1     # a flag: int8 0/1
    assert sw["peak_attitude_error"].attrs["units"] == "rad"      # one angle unit in every file
    sw[["peak_attitude_error"]].to_dataframe()


def test_si_config_round_trips(tmp_path):
    """Input in SI, output in SI = the imperial run's numbers converted."""
    import h5py

    from acmm.stages.simulate import run_simulate
    from acmm_qpp.units import FT_LBF_IN_NM

    imp = _short("mb3", tmp_path / "imp")
    d = imp.model_dump(mode="json")
    k = FT_LBF_IN_NM
    d["inertia"] = {key: f"{v * k!r} kg*m^2" for key, v in d["inertia"].items()}
    d["actuators"] = {"torque_limit": f"{150 * k!r} N*m", "momentum_limit": f"{20000 * k!r} N*m*s"}
    d["disturbance"]["A"] = [f"{a * k!r} N*m" for a in d["disturbance"]["A"]]
    d["disturbance"]["B"] = [f"{b * k!r} N*m" for b in d["disturbance"]["B"]]
    d["design"]["R"] = f"{1e-4 / k ** 2!r} 1/(N*m)^2"
    d["orbit_rate"] = f"{d['orbit_rate'] * 180 / np.pi!r} deg/s"
    d["output"].update({"root": str(tmp_path / "si" / "runs"), "units": "SI"})
    si = parse_config(d)
    assert si.design.R == pytest.approx(imp.design.R, rel=1e-12)
    _, p_imp = run_simulate(imp)
    _, p_si = run_simulate(si)
    conv = {"h": k, "u": k, "w": k, "int_h": k, "levels/inertia": k, "levels/bias": k,
            "theta": 1.0, "t": 1.0, "levels/peak_momentum": k}
    si_units = {"h": "N*m*s", "u": "N*m", "w": "N*m", "int_h": "N*m*s^2", "levels/inertia": "kg*m^2",
                "theta": "rad", "t": "s"}
    with h5py.File(p_imp) as a, h5py.File(p_si) as b:
        assert b.attrs["unit_system"] == "SI" and a.attrs["unit_system"] == "imperial"
        for name, factor in conv.items():
            # inputs equal to ~1e-16 after the unit round trip; the adaptive integrator (rtol 1e-8)
            # may then pick other steps, so agreement is to ~1e-6 of each signal's range
            np.testing.assert_allclose(b[name][()], a[name][()] * factor, rtol=1e-5,
                                       atol=1e-5 * np.abs(a[name][()]).max() * factor + 1e-300, err_msg=name)
        for name, unit in si_units.items():
            assert b[name].attrs["units"] == unit, name


def test_si_design_h5_is_the_imperial_design_in_si_and_is_reused_exactly(tmp_path):
    """Per-state matrices in SI: D A D⁻¹, k K D⁻¹ (D: state factors, k = N·m per ft·lbf), poles
    unchanged; the SI design.h5 read back equals the imperial design."""
    import h5py

    from acmm.io.design_file import load_design_table
    from acmm.stages.design import run_design
    from acmm_qpp.units import FT_LBF_IN_NM as k

    imp = _short("ac", tmp_path / "imp")
    d = imp.model_dump(mode="json")
    d["output"].update({"root": str(tmp_path / "si" / "runs"), "units": "SI"})
    si = parse_config(d)
    r_imp, p_imp = run_design(imp, figures=False)
    _, p_si = run_design(si, figures=False)
    # independent state factors: rad, rad/s unchanged; ft·lbf·s → N·m·s etc.; attitude-hold DRFs
    # filter (h1, θ2, θ3): α1, β1 carry ft·lbf·s·s(²), the others rad·s(²)
    f = np.ones(24)
    f[6:12] = k
    f[[12, 13, 18, 19]] = k
    with h5py.File(p_imp) as a, h5py.File(p_si) as b:
        pa, pb = (g["points"][next(iter(g["points"]))] for g in (a, b))
        np.testing.assert_allclose(pb["A"][()], f[:, None] * pa["A"][()] / f[None, :], rtol=1e-12)
        np.testing.assert_allclose(pb["K"][()], k * pa["K"][()] / f, rtol=1e-12)
        np.testing.assert_allclose(pb["R"][()], pa["R"][()] / k ** 2, rtol=1e-12)
        np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(pb["A"][()] - pb["B"][()] @ pb["K"][()])),
                                   np.sort_complex(pa["poles"][()]), rtol=0, atol=1e-5 * imp.orbit_rate)
        # (near-repeated poles: eigenvalues agree to ~1e-6 n, not to machine precision)
        np.testing.assert_allclose(b["inertia"][()], a["inertia"][()] * k, rtol=1e-12)
        assert b["inertia"].attrs["units"] == "kg*m^2" and b["bias"].attrs["units"] == "N*m"
    ta, tb = load_design_table(p_imp), load_design_table(p_si)
    np.testing.assert_allclose(tb.gain, ta.gain, rtol=1e-12)
    np.testing.assert_allclose(tb.inertia, ta.inertia, rtol=1e-12)


def test_si_simulation_is_the_same_whether_its_design_was_just_made_or_reused(tmp_path):
    """The SI design.h5 holds K in SI; a run that reuses it converts it back (rounding at 1e-16),
    so a fresh run uses the table as read back too: sim.h5 identical bit for bit."""
    from acmm.stages.simulate import run_simulate
    from acmm.report.manifest import dataset_hashes

    cfg = _short("mb3", tmp_path, units="SI")
    _, fresh = run_simulate(cfg)
    first = dataset_hashes(fresh)
    fresh.unlink()
    r, again = run_simulate(cfg)
    assert "reused" in r.design_note
    assert dataset_hashes(again) == first


# ---------------------------------------------------------------- unit strings everywhere
def test_unit_strings_in_acmm_sweep_and_qpp_configs():
    from acmm.sweep.spec import SweepSpec
    from acmm_qpp.units import FT_LBF_IN_NM as k
    from qpp.io.config import QppConfig

    base = yaml.safe_load((CONFIGS / "mb3.yaml").read_text())
    plain = parse_config(base)
    with_units = parse_config({**base, "design": {**base.get("design", {}), "R": f"{1e-4 / k ** 2!r} 1/(N*m)^2",
                                                  "sector": {"sigma": 0.5, "half_angle_deg": f"{np.pi / 4!r} rad"}}})
    assert with_units.design.R == pytest.approx(plain.design.R, rel=1e-12)
    assert with_units.design.sector.half_angle_deg == pytest.approx(45.0, rel=1e-12)
    with pytest.raises(ConfigError, match=r"^config: design\.R: unit 'N\*m' is not a unit of"):
        parse_config({**base, "design": {"R": "1 N*m"}})
    # sweep: grid values and distribution bounds in the parameter's unit
    s = SweepSpec.model_validate({"base": "ac", "grid": {"bias_pitch": [f"{k!r} N*m", 2.0], "offset_roll": ["1 rad"]}})
    assert s.grid["bias_pitch"] == pytest.approx([1.0, 2.0]) and s.grid["offset_roll"] == pytest.approx([np.degrees(1)])
    m = SweepSpec.model_validate({"base": "ac", "n_runs": 2, "monte_carlo": {"bias_roll": {"uniform": ["0 N*m", f"{k!r} N*m"]}}})
    assert m.monte_carlo["bias_roll"].uniform == pytest.approx((0.0, 1.0))
    with pytest.raises(ValueError, match="grid.bias_pitch: unit 'kg' is not a unit of ft"):
        SweepSpec.model_validate({"base": "ac", "grid": {"bias_pitch": ["1 kg"]}})
    # qpp: time, frequency, 1/s, mass, length, kg·m²
    q = yaml.safe_load((CONFIGS / "qpp_manipulator.yaml").read_text())
    ref = QppConfig.model_validate(q)
    q["spheres"]["T"] = f"{ref.spheres.T * 1000!r} ms"
    q["hinf"]["a"] = f"{ref.hinf.a * 60!r} 1/min"
    q["nonlinearity"].update(mu=f"{ref.nonlinearity.mu * 1000!r} g", a=f"{ref.nonlinearity.a * 100!r} cm",
                             J1=f"{ref.nonlinearity.J1 * 1e4!r} kg*cm^2")
    q["simulation"]["t_final"] = f"{ref.simulation.t_final / 60!r} min"
    got = QppConfig.model_validate(q)
    assert got.spheres.T == pytest.approx(ref.spheres.T, rel=1e-12)
    assert got.hinf.a == pytest.approx(ref.hinf.a, rel=1e-12)
    assert got.simulation.t_final == pytest.approx(ref.simulation.t_final, rel=1e-12)
    for f in ("mu", "a", "J1"):
        assert getattr(got.nonlinearity, f) == pytest.approx(getattr(ref.nonlinearity, f), rel=1e-12)
    q["spheres"]["T"] = "2 kg"
    with pytest.raises(ValueError, match="spheres.T"):
        QppConfig.model_validate(q)


def test_api_misuse_raises_the_documented_errors():
    """A design point that is not there, a schedule a config does not have, a config of the wrong
    type: AcmmError subclasses naming what is valid (they were IndexError, KeyError, ValueError and
    TypeError); a missing point is still a KeyError/IndexError for code that caught those."""
    from acmm import api
    from acmm_qpp.errors import AcmmError, ConfigError

    d = api.design(api.load_config("mb3"))
    for bad in (5, "zzz", 1.5):
        with pytest.raises(ConfigError, match="no design point") as exc:
            d.closed_loop(bad)
        assert isinstance(exc.value, (KeyError, IndexError)) and "mb3" in str(exc.value)
    np.testing.assert_array_equal(d.gain(-1), d.gain("mb3"))
    for call in (lambda: d.scheduled_closed_loop(-20.0), lambda: d.loop_transfer(tea_pitch_deg=-20.0)):
        with pytest.raises(ConfigError, match="no gain schedule"):
            call()
    with pytest.raises(AcmmError, match="not int"):
        api.load_config(42)
