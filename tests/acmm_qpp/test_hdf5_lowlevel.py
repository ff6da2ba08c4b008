"""acmm_qpp.hdf5_lowlevel makes exactly the HDF5 objects h5py's high-level calls make (issue 16).

Each case is written twice, once with h5py's high-level API (``create_dataset``, ``attrs[...] =``,
the reference) and once with :class:`acmm_qpp.hdf5_lowlevel.Writer`; the stored type and dataspace
(HDF5's own serialisation), the creation properties and the values must be the same.  Also the
other savings of ``write_h5``: ``output.units`` read with libyaml's loader, the git commit asked
once per process.
"""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from acmm_qpp.hdf5_lowlevel import Writer
from acmm_qpp.results import Dataset, write_h5

from tests.conftest import REPO

TEXT = h5py.string_dtype()

#: (name, data, dtype, shape): the plain cases and ones h5py is left to decide.
DATASETS = [
    ("text", "héllo", None, None),
    ("scalar", 2.5, None, None),
    ("int", np.asarray(7), None, None),
    ("flag", np.asarray([True, False]), None, None),
    ("complex", np.array([1 + 2j, 3 - 1j]), None, None),
    ("f4", np.arange(6, dtype="f4").reshape(2, 3), None, None),
    ("big_endian", np.arange(3, dtype=">f8"), None, None),
    ("strided", np.arange(12.0).reshape(3, 4).T, None, None),
    ("empty", np.zeros((0,)), None, None),
    ("bytes", np.array([b"ab", b"cde"], dtype="S"), None, None),
    ("names", np.array(["roll", "pítch"], dtype=object), TEXT, None),
    ("mixed", np.array([b"x", "y"], dtype=object), TEXT, None),
    ("empty_text", np.array([], dtype=object), TEXT, None),
    ("bare", None, "f4", (5,)),
]

#: Attribute values: str fast, the rest through h5py.
ATTRS = [("units", "ft*lbf"), ("ünit", "grad"), ("n", 12), ("x", 0.5), ("v", np.arange(3.0)),
         ("list", ["a", "b"]), ("raw", b"r"), ("ok", True)]


def _describe(obj):
    out = {}
    if isinstance(obj, h5py.Dataset):
        out.update(type=obj.id.get_type().encode(), space=obj.id.get_space().encode())
        p = obj.id.get_create_plist()
        out.update(layout=p.get_layout(), fill_time=p.get_fill_time(), alloc=p.get_alloc_time(),
                   times=p.get_obj_track_times(), order=p.get_attr_creation_order(),
                   filters=p.get_nfilters(), value=repr(obj[()]) if obj.shape != (0,) else "")
    for name in sorted(obj.attrs):
        a = h5py.h5a.open(obj.id, name.encode())
        out[f"@{name}"] = (a.get_type().encode(), a.get_space().encode(), repr(obj.attrs[name]))
    return out


@pytest.mark.parametrize("name,data,dtype,shape", DATASETS, ids=[c[0] for c in DATASETS])
def test_dataset_is_what_h5py_high_level_writes(tmp_path, name, data, dtype, shape):
    with h5py.File(tmp_path / "ref.h5", "w") as ref, h5py.File(tmp_path / "low.h5", "w") as low:
        if isinstance(data, np.ndarray) and data.dtype.kind == "S":
            # fixed-length text is declared UTF-8: h5py's string_dtype("utf-8", length), its bytes as they are
            a = ref.create_dataset(name, data.shape, h5py.string_dtype("utf-8", data.dtype.itemsize))
            a.id.write(h5py.h5s.ALL, h5py.h5s.ALL, data, mtype=a.id.get_type())
        else:
            a = ref.create_dataset(name, shape, dtype, data)
        b = h5py.Dataset(Writer().dataset(low, name, data, shape, dtype))
        assert b.name == f"/{name}"
        assert _describe(b) == _describe(a)


def test_attributes_and_overwrites_are_what_h5py_high_level_writes(tmp_path):
    with h5py.File(tmp_path / "ref.h5", "w") as ref, h5py.File(tmp_path / "low.h5", "w") as low:
        w = Writer()
        a, b = ref.create_dataset("d", data=[1.0]), h5py.Dataset(w.dataset(low, "d", np.asarray([1.0])))
        for obj_ref, obj_low in ((a, b.id), (ref, low.id)):
            for k, v in ATTRS + [("units", 3), ("n", "twelve")]:     # the last two replace
                # a flag is int8 0/1 in every results file (h5py would write an HDF5 enum)
                obj_ref.attrs[k] = np.int8(v) if isinstance(v, (bool, np.bool_)) else v
                w.attr(obj_low, k, v)
        assert _describe(b) == _describe(a)
        assert _describe(low) == _describe(ref)
        assert b.attrs["units"] == 3 and low.attrs["n"] == "twelve"
        assert w.has_attr(b.id, "ünit") and not w.has_attr(b.id, "long_name")


def test_path_names_and_failures_as_h5py(tmp_path):
    """A name with a slash makes the groups on the way; an existing name is refused (as h5py)."""
    with h5py.File(tmp_path / "low.h5", "w") as low:
        w = Writer()
        w.dataset(low, "g/x", np.asarray([1.0]))
        assert low["g/x"][()].tolist() == [1.0]
        w.dataset(low, "y", np.asarray([2.0]))
        with pytest.raises(ValueError):
            w.dataset(low, "y", np.asarray([3.0]))


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


def test_git_commit_asked_once_per_process(monkeypatch):
    import subprocess

    from acmm_qpp import provenance

    calls = []
    real = subprocess.run

    def counting(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)

    provenance._git_state.cache_clear()
    monkeypatch.setattr(subprocess, "run", counting)
    try:
        first = provenance.git_commit()
        assert provenance.git_commit() == first and len(calls) == 1
        prov = provenance.provenance("a: 1\n")
        assert prov["git_commit"] == first and prov["git_dirty"] in ("yes", "no") and len(calls) == 1
        assert provenance.source_unchanged() == (prov["git_dirty"] == "no") and len(calls) == 1
    finally:
        provenance._git_state.cache_clear()


def test_provenance_flags_uncommitted_changes(tmp_path):
    """A results file written by an edited checkout says so (git_dirty = yes): the commit alone
    does not say what code ran.  A git repository of its own holds a copy of this package."""
    import os
    import shutil
    import subprocess
    import sys

    if shutil.which("git") is None:
        pytest.skip("no git")
    repo = tmp_path / "repo"
    shutil.copytree(REPO / "acmm_qpp", repo / "acmm_qpp",
                    ignore=shutil.ignore_patterns("__pycache__"))
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "init.defaultBranch=main"]
    subprocess.run(git + ["init", "-q"], cwd=repo, check=True)
    subprocess.run(git + ["add", "-A"], cwd=repo, check=True)
    subprocess.run(git + ["commit", "-q", "-m", "x"], cwd=repo, check=True)
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True).stdout.strip()
    probe = "from acmm_qpp import provenance as p; print(p.git_commit(), p.git_dirty(), p.source_unchanged())"
    env = {**os.environ, "PYTHONPATH": str(repo)}

    def state():
        r = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r.stdout.split()

    assert state() == [head, "no", "True"]
    with open(repo / "acmm_qpp" / "units.py", "a") as f:
        f.write("# edited\n")
    assert state() == [head, "yes", "False"]
