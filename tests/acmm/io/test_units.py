"""Output in SI (acmm.io.units, output.units: SI): the imperial run's numbers converted, per-state
matrices D A D⁻¹ and k K D⁻¹, an SI design.h5 reused exactly."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.io.config import load_config, parse_config


# ---------------------------------------------------------------- SI output
def _short(name, tmp_path, **output):
    data = load_config(name).model_dump(mode="json")
    data["simulation"]["orbits"] = 1.0
    data["simulation"]["sample_interval"] = 600.0
    data["output"].update({"root": str(tmp_path / "runs"), "figures": False, **output})
    return parse_config(data)


def test_si_config_round_trips(tmp_path):
    """Input in SI, output in SI = the imperial run's numbers converted."""
    import h5py

    from acmm.stages.simulate import run_simulate
    from acmm.model.unit_systems import FT_LBF_IN_NM

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
    from acmm.model.unit_systems import FT_LBF_IN_NM as k

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


def test_convert_items_to_si_and_angles_to_rad():
    """Datasets are converted by their unit strings: ft·lbf → N·m under SI, deg → rad in both
    systems, units pint does not know kept; groups alike."""
    from acmm.io.units import convert_items
    from acmm.model.unit_systems import FT_LBF_IN_NM
    from acmm_qpp.results import Dataset

    items = {"torque": Dataset(2.0, "ft*lbf"), "g": {"angle": Dataset(180.0, "deg")},
             "odd": Dataset(1.0, "output units"), "n": Dataset(3, "1")}
    si = convert_items(items, "SI")
    assert (si["torque"].data, si["torque"].units) == (pytest.approx(2.0 * FT_LBF_IN_NM), "N*m")
    assert (si["g"]["angle"].data, si["g"]["angle"].units) == (pytest.approx(np.pi), "rad")
    assert si["odd"] is items["odd"] and si["n"] is items["n"]
    imperial = convert_items(items, "imperial")
    assert imperial["torque"] is items["torque"] and imperial["g"]["angle"].units == "rad"
