"""The netCDF-4 layout of the HDF5 results (acmm_qpp.netcdf_layout): every results file opens in
xarray and in netCDF-C with named dimensions; the layout annotated by name lookup is the one made
with the handles; ``output.units`` read from the config text."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
import yaml

from acmm.io.config import load_config, parse_config
from acmm_qpp.hdf5_lowlevel import Writer
from acmm_qpp.results import Dataset, write_h5

from tests.conftest import CONFIGS
from tests.acmm_qpp.test_hdf5_lowlevel import _describe


# ---------------------------------------------------------------- netCDF layout: xarray, netCDF-C
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

    def fixed_length_text(name, obj):     # docs/howto/results.md: text variables other than coordinates
        info = h5py.check_string_dtype(obj.dtype) if isinstance(obj, h5py.Dataset) else None
        if info is not None and obj.attrs.get("CLASS") != b"DIMENSION_SCALE":
            assert info.length is not None and info.encoding == "utf-8", name
    with h5py.File(r.path) as f:
        f.visititems(fixed_length_text)
        assert f.attrs["complete"].dtype == np.int8 and f.attrs["complete"] == 1     # a flag: int8 0/1
    assert sw["peak_attitude_error"].attrs["units"] == "rad"      # one angle unit in every file
    sw[["peak_attitude_error"]].to_dataframe()


def test_write_h5_overrides_and_layout_without_handles(tmp_path):
    """Dataset attributes replace the defaults as before (units, a coordinates attribute that the
    layout then sets), and annotating by name lookup gives the same file as with the handles."""
    from acmm_qpp.netcdf_layout import annotate

    items = {"t": Dataset(np.arange(3.0), "s", "time", dims=("t",)),
             "orbits": Dataset(np.arange(3.0) / 2, "1", "orbit count", dims=("t",)),
             "w": Dataset(np.ones((3, 3)), "rad/s", "rate", ["roll", "pitch", "yaw"],
                          attrs={"units": "deg/s", "coordinates": "mine", "long_name": "own"}, dims=("t", "axis")),
             "grp": {"k": Dataset(np.ones((2, 3)), "1", "gain", ["roll", "pitch", "yaw"])}}
    path = write_h5(tmp_path / "a.h5", items, "name: x\n")
    with h5py.File(path, "r") as f:
        w = f["w"]
        assert w.attrs["units"] == "deg/s" and w.attrs["coordinates"] == "orbits"
        assert w.attrs["long_name"] == "own" and json.loads(w.attrs["names"]) == ["roll", "pitch", "yaw"]
        assert [d[0].name for d in w.dims] == ["/t", "/axis"]
        assert f["orbits"].dims[0][0].name == "/t"
        assert f["t"].attrs["standard_name"] == "time" and f["grp/k"].dims[1][0].name == "/grp/axis"
    # the same layout, annotated by looking the datasets up by name
    from acmm_qpp.results import _write_group

    with h5py.File(tmp_path / "b.h5", "w") as f:
        _write_group(f, items, Writer())
        annotate(f, items)
    with h5py.File(path, "r") as a, h5py.File(tmp_path / "b.h5", "r") as b:
        names = []
        a.visit(names.append)
        for n in names:
            if isinstance(a[n], h5py.Dataset):
                assert _describe(a[n]) == _describe(b[n]), n
                assert [[s.name for s in d.values()] for d in a[n].dims] == \
                    [[s.name for s in d.values()] for d in b[n].dims], n


@pytest.mark.parametrize("text,system", [
    ("output: {units: SI}\n", "SI"), ("output:\n  units: imperial\n", "imperial"),
    ("name: x\n", "imperial"), ("output: {}\n", "imperial"), ("", "imperial"),
    ("- a\n- b\n", "imperial"),                 # not a mapping
    ("output: {units: SI\n", "imperial"),       # not YAML
    ("output: {units: \"\\x00\"}\n", "\x00"),   # whatever the config says
])
def test_unit_system_of_config_text(text, system):
    from acmm_qpp.netcdf_layout import unit_system_of

    assert unit_system_of(text) == system
