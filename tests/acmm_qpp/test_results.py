"""Self-describing HDF5 results written atomically (acmm_qpp.results), and a stage's figures drawn
after its results (acmm_qpp.results.draw_figures)."""
from __future__ import annotations

import hashlib
import json
import re

import h5py
import numpy as np
import pytest

import acmm
from acmm_qpp.results import Dataset, read_h5, write_h5
from acmm.plots import simulation as sim_plots

CONFIG_TEXT = "name: demo\ninertia: {I11: 1.0, I22: 1.0, I33: 1.0}\n"


def _all_datasets(path):
    """Datasets other than the netCDF dimension scales added by acmm_qpp.netcdf_layout."""
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
        "x": Dataset(np.arange(3.0), "rad", "angles", ["roll", "pitch", "yaw"]),
        "scalar": Dataset(2.5, "s"),
        "label": Dataset("hello", "1"),
        "group": {"y": Dataset(np.eye(2), "ft*lbf", attrs={"extra": 7})},
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
        write_h5(target, {"ok": Dataset([1.0], "s"), "bad": [1, 2, 3]}, CONFIG_TEXT)
    assert list(tmp_path.iterdir()) == []
    write_h5(target, {"v": Dataset([1.0], "s")}, CONFIG_TEXT)
    before = target.read_bytes()
    with pytest.raises(TypeError):
        write_h5(target, {"v": Dataset([2.0], "s"), "bad": object()}, CONFIG_TEXT)
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
    from acmm_qpp.atomic_write import write_text

    old = os.umask(0o022)
    try:
        h5 = write_h5(tmp_path / "x.h5", {"x": Dataset([1.0], "1")}, "c: 1")
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
