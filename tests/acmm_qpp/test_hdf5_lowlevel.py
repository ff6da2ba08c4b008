"""acmm_qpp.hdf5_lowlevel makes exactly the HDF5 objects h5py's high-level calls make (issue 16).

Each case is written twice, once with h5py's high-level API (``create_dataset``, ``attrs[...] =``,
the reference) and once with :class:`acmm_qpp.hdf5_lowlevel.Writer`; the stored type and dataspace
(HDF5's own serialisation), the creation properties and the values must be the same.
"""
from __future__ import annotations

import h5py
import numpy as np
import pytest

from acmm_qpp.hdf5_lowlevel import Writer

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
