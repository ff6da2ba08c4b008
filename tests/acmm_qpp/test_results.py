"""Self-describing HDF5 results written atomically (acmm_qpp.results): their netCDF-4 layout (every
results file opens in xarray and in netCDF-C with named dimensions), ``output.units`` read from the
config text, and a stage's figures drawn after its results (acmm_qpp.results.draw_figures)."""
from __future__ import annotations

import hashlib
import json
import re

import h5py
import numpy as np
import pytest
import yaml

import acmm
from acmm.io.config import load_config, parse_config
from acmm_qpp.results import Dataset, h5_text, read_h5, write_h5
from acmm.plots import simulation as sim_plots

from tests.conftest import CONFIGS

CONFIG_TEXT = "name: demo\ninertia: {I11: 1.0, I22: 1.0, I33: 1.0}\n"


def _all_datasets(path):
    """Datasets other than the netCDF dimension scales."""
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.__setitem__(name, dict(obj.attrs))
                     if isinstance(obj, h5py.Dataset) and not h5py.h5ds.is_scale(obj.id) else None)
    return found


def _leftovers(directory, keep):
    return sorted(p.name for p in directory.iterdir() if p.name not in keep)


def test_write_h5_units_provenance_and_round_trip(tmp_path):
    target = tmp_path / "sub" / "dir" / "r.h5"
    items = {
        "x": Dataset(np.arange(3.0), "rad", "angles", ["roll", "pitch", "yaw"], dims=("axis",)),
        "scalar": Dataset(2.5, "s"),
        "label": Dataset("hello", "1"),
        "group": {"y": Dataset(np.eye(2), "ft*lbf", attrs={"extra": 7}, dims=("row", "col"))},
    }
    out = write_h5(target, items, CONFIG_TEXT, {"stage": "unit-test"})
    assert out == target and target.is_file()
    ds = _all_datasets(target)
    assert set(ds) == {"x", "scalar", "label", "group/y"}
    assert {k: v["units"] for k, v in ds.items()} == {"x": "rad", "scalar": "s", "label": "1",
                                                      "group/y": "ft*lbf"}
    assert json.loads(ds["x"]["names"]) == ["roll", "pitch", "yaw"]
    assert ds["x"]["description"] == "angles"
    assert ds["group/y"]["extra"] == 7
    back = read_h5(target)
    np.testing.assert_array_equal(back["x"], np.arange(3.0))
    np.testing.assert_array_equal(back["group"]["y"], np.eye(2))
    assert back["scalar"] == 2.5 and back["label"] == "hello"
    attrs = back["attrs"]
    assert attrs["config"] == CONFIG_TEXT
    assert attrs["config_hash"] == hashlib.sha256(CONFIG_TEXT.encode()).hexdigest()[:16]
    assert attrs["package_version"] == acmm.__version__
    assert attrs["git_commit"] == "unknown" or re.fullmatch(r"[0-9a-f]{40}", attrs["git_commit"])
    assert attrs["stage"] == "unit-test"
    assert _leftovers(target.parent, {"r.h5"}) == []


def test_fixed_length_text_is_utf8_and_decodes(tmp_path):
    """Fixed-length text (names, a sweep's verdicts and reasons) is declared UTF-8: non-ASCII
    reasons ("ft·lbf") decode with h5py's asstr() and with netCDF-C as text; ASCII keeps its bytes."""
    import netCDF4

    words = ["bounded", "no equilibrium for bias [1, 2, 3] ft·lbf", ""]
    items = {"reason": Dataset(np.array([w.encode() for w in words], dtype="S"), "1", dims=("case",)),
             "names": Dataset(np.array(["mb3", "ac"], dtype="S"), "1", dims=("point",))}
    target = write_h5(tmp_path / "t.h5", items, CONFIG_TEXT, {"stage": "unit-test"})
    with h5py.File(target, "r") as f:
        assert f["reason"].dtype.kind == "S" and list(f["reason"].asstr()[()]) == words
        assert f["names"][()].tolist() == [b"mb3", b"ac"]           # the same bytes as before
        assert f["reason"].id.get_type().get_cset() == h5py.h5t.CSET_UTF8
    with netCDF4.Dataset(target) as nc:
        assert list(nc["reason"][...]) == words


def test_write_h5_failure_leaves_no_file_and_keeps_old_one(tmp_path):
    target = tmp_path / "r.h5"
    with pytest.raises(TypeError):
        write_h5(target, {"ok": Dataset([1.0], "s", dims=("i",)), "bad": [1, 2, 3]}, CONFIG_TEXT)
    assert list(tmp_path.iterdir()) == []
    write_h5(target, {"v": Dataset([1.0], "s", dims=("i",))}, CONFIG_TEXT)
    before = target.read_bytes()
    with pytest.raises(TypeError):
        write_h5(target, {"v": Dataset([2.0], "s", dims=("i",)), "bad": object()}, CONFIG_TEXT)
    assert target.read_bytes() == before
    assert _leftovers(tmp_path, {"r.h5"}) == []


def test_config_hash_changes_with_config(tmp_path):
    a = write_h5(tmp_path / "a.h5", {"v": Dataset(1.0, "s")}, CONFIG_TEXT)
    b = write_h5(tmp_path / "b.h5", {"v": Dataset(1.0, "s")}, CONFIG_TEXT.replace("demo", "other"))
    assert read_h5(a)["attrs"]["config_hash"] != read_h5(b)["attrs"]["config_hash"]


def test_results_are_readable_by_others_not_mkstemp_0600(tmp_path):
    import os
    import stat

    from acmm_qpp.results import Dataset, write_h5
    from acmm_qpp.outputs import write_text

    old = os.umask(0o022)
    try:
        h5 = write_h5(tmp_path / "x.h5", {"x": Dataset([1.0], "1", dims=("i",))}, "c: 1")
        txt = write_text(tmp_path / "x.txt", "hello")
    finally:
        os.umask(old)
    for p in (h5, txt):
        assert stat.S_IMODE(p.stat().st_mode) == 0o644


def _small_histories(n=300):
    t = np.linspace(0.0, 3.0, n)
    x = np.column_stack([np.sin(5 * t), np.cos(3 * t), t]) * 2.0
    return t, x


def test_draw_figures_draws_every_figure_and_raises_the_first_failure(tmp_path):
    """A stage's figures are drawn in order in this process after its results; all of them even
    if one fails, and that first failure is raised then, as a FigureError (exit 4)."""
    from functools import partial

    from acmm_qpp.errors import FigureError
    from acmm_qpp.results import draw_figures

    t, x = _small_histories()
    (tmp_path / "file").write_text("")
    calls = [partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "file" / "bad.png"),
             partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "after.png"),
             lambda: (_ for _ in ()).throw(ValueError("Axis limits cannot be NaN or Inf"))]
    with pytest.raises(FigureError, match="bad.png") as got:
        draw_figures(calls)
    assert got.value.exit_code == 4
    assert (tmp_path / "after.png").stat().st_size > 10_000 and not (tmp_path / "file" / "bad.png").exists()
    with pytest.raises(FigureError, match="Axis limits"):
        draw_figures(calls[2:])
    draw_figures([])


def _interrupting_figure():
    raise KeyboardInterrupt


def test_ctrl_c_while_a_figure_is_drawn_is_an_interrupt_not_a_figure_error(tmp_path):
    from acmm_qpp.results import draw_figures

    t, x = _small_histories()
    from functools import partial

    with pytest.raises(KeyboardInterrupt):
        draw_figures([_interrupting_figure, partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "a.png")])
    assert not (tmp_path / "a.png").exists()


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


def test_write_h5_layout_dims_coordinates_and_attribute_overrides(tmp_path):
    """Dataset attributes replace the defaults (units, coordinates, long_name); each group declares
    its own dimensions; names give a dimension without a dataset of its name its coordinate (a
    product's own coordinates: tests/acmm/io/test_dimensions.py)."""
    items = {"t": Dataset(np.arange(3.0), "s", "time", dims=("t",)),
             "orbits": Dataset(np.arange(3.0) / 2, "1", "orbit count", dims=("t",)),
             "w": Dataset(np.ones((3, 3)), "rad/s", "rate", ["roll", "pitch", "yaw"],
                          attrs={"units": "deg/s", "coordinates": "mine", "long_name": "own"}, dims=("t", "axis")),
             "flag": Dataset(np.array([True, False]), "1", dims=("two",)),
             "poles": Dataset(np.array([1 + 2j, 3 - 1j]), "rad/s", dims=("two",)),
             "grp": {"k": Dataset(np.ones((2, 3)), "1", "gain", ["a", "b", "c"], dims=("row", "col"))}}
    path = write_h5(tmp_path / "a.h5", items, "name: x\n", {"n": 3, "ok": True})
    with h5py.File(path, "r") as f:
        w = f["w"]
        assert w.attrs["units"] == "deg/s" and w.attrs["coordinates"] == "mine"
        assert w.attrs["long_name"] == "own" and json.loads(w.attrs["names"]) == ["roll", "pitch", "yaw"]
        assert [d[0].name for d in w.dims] == ["/t", "/axis"]
        assert f["axis"].asstr()[()].tolist() == ["roll", "pitch", "yaw"]
        assert f["axis"].attrs["long_name"] == "name along axis" and "description" not in f["axis"].attrs
        assert f["orbits"].dims[0][0].name == "/t" and "coordinates" not in f["orbits"].attrs
        assert f["t"].attrs["standard_name"] == "time" and f["t"].attrs["axis"] == "T"
        assert [d[0].name for d in f["grp/k"].dims] == ["/grp/row", "/grp/col"]
        assert f["grp/col"].asstr()[()].tolist() == ["a", "b", "c"]       # a coordinate from names
        assert f["grp/col"].attrs["long_name"] == "name along col"
        assert f.attrs["n"] == 3 and f.attrs["n"].shape == ()              # numbers stay scalars
        assert f.attrs["ok"].dtype == np.int8 and f.attrs["Conventions"] == "CF-1.8"
        assert f["flag"].dtype == bool and f["poles"][()].tolist() == [1 + 2j, 3 - 1j]
    back = read_h5(path)
    assert set(back) == {"t", "orbits", "w", "flag", "poles", "axis", "grp", "attrs"}   # no bare dims
    assert set(back["grp"]) == {"k", "col"}
    _netcdf_c_reads(path)


@pytest.mark.parametrize("items,match", [
    ({"x": Dataset(np.zeros(3), "1")}, "'x': 0 dimension names"),
    ({"x": Dataset(np.zeros((3, 2)), "1", dims=("a",))}, "'x': 1 dimension names"),
    ({"x": Dataset(np.zeros(3), "1", dims=("a",)), "y": Dataset(np.zeros(2), "1", dims=("a",))},
     "'y': dimension 'a' of length 2, 3 elsewhere"),
])
def test_write_h5_refuses_arrays_without_their_dimensions(tmp_path, items, match):
    """Dimensions are the writer's to name: an array without them, or one name with two lengths in a
    group, is refused before anything is written."""
    with pytest.raises(ValueError, match=match):
        write_h5(tmp_path / "a.h5", items, "name: x\n")
    assert list(tmp_path.iterdir()) == []


def test_write_h5_writes_the_items_as_given(tmp_path):
    """The base converts nothing and reads no config key: a product converts its items first
    (acmm: :func:`acmm.io.units.convert_items`) and names its unit system in ``attrs``."""
    items = {"torque": Dataset(2.0, "ft*lbf"), "angle": Dataset(180.0, "deg")}
    plain = read_h5(write_h5(tmp_path / "plain.h5", items, "output: {units: SI}\n"))
    assert "unit_system" not in plain["attrs"] and plain["torque"] == 2.0 and plain["angle"] == 180.0


def test_h5_text_reads_every_form_a_string_attribute_takes(tmp_path):
    """bytes (a fixed-length string), str, and numpy scalars of either, as h5py returns them."""
    with h5py.File(tmp_path / "t.h5", "w") as f:
        f.attrs["fixed"] = np.bytes_(b"mb3")
        f.attrs["variable"] = "ac"
        f["names"] = np.array([b"roll", b"pitch"], dtype="S5")
    with h5py.File(tmp_path / "t.h5", "r") as f:
        assert h5_text(f.attrs["fixed"]) == "mb3" and h5_text(f.attrs["variable"]) == "ac"
        assert [h5_text(v) for v in f["names"][()]] == ["roll", "pitch"]
    assert h5_text(b"mb3") == "mb3" and h5_text("ac") == "ac" and h5_text(np.str_("x")) == "x"
