"""HDF5 objects written through h5py's low-level API: the very objects its high-level calls make.

:func:`acmm_qpp.results.write_h5` and :mod:`acmm_qpp.netcdf_layout` write hundreds of small datasets
and a thousand attributes per file (``design.h5``: every design point's matrices, each with
``units``, ``description``, ``long_name``, dimension scales).  h5py's high-level layer costs
some 40–80 µs of Python per dataset, attribute or name lookup on top of the HDF5 call, which made
writing such a file take several times longer than the HDF5 library itself.  These helpers call
the low-level functions h5py's high-level ``create_dataset``, ``attrs[...] =``, ``make_scale``
and ``dims[i].attach_scale`` call, with the same types, dataspaces and creation properties, so
the file holds exactly the same objects; any value outside the plain cases (numbers, byte strings
and text) goes through the high-level call itself.
"""
from __future__ import annotations

from types import SimpleNamespace

import h5py
import numpy as np
from h5py import h5a, h5d, h5ds, h5p, h5s, h5t

#: Kinds of numpy arrays written directly: bool, integers, floats, complex, fixed-length bytes.
_PLAIN_KINDS = "biufcS"


class Writer:
    """Creates datasets and attributes of one open file as h5py's high-level calls would.

    Parameters
    ----------
    track_order : bool or None, optional
        Track the creation order of the attributes (h5py's ``track_order``; default: h5py's
        global setting, as ``Group.create_dataset`` uses).
    """

    def __init__(self, track_order: bool | None = None):
        self.text = h5py.string_dtype()                   # variable-length UTF-8
        self._text_type = h5t.py_create(self.text, logical=True)
        self._text_mem = h5t.py_create(self.text)
        self._scalar = h5s.create_simple(())
        if track_order is None:
            track_order = h5py.get_config().track_order
        dcpl = h5p.create(h5p.DATASET_CREATE)              # make_new_dset's defaults
        dcpl.set_obj_track_times(False)
        dcpl.set_attr_creation_order(h5p.CRT_ORDER_TRACKED | h5p.CRT_ORDER_INDEXED
                                     if track_order else 0)
        self._dcpl = dcpl
        self._types: dict = {}

    def _file_type(self, dtype):
        t = self._types.get(dtype)
        if t is None:
            t = h5t.py_create(dtype, logical=1)
            if dtype.kind == "S":       # fixed-length text is UTF-8 (a sweep's reasons say ft·lbf);
                t = t.copy()            # declared ASCII, asstr() and netCDF readers refuse it
                t.set_cset(h5t.CSET_UTF8)
            self._types[dtype] = t
        return t

    def dataset(self, parent, name: str, data=None, shape: tuple | None = None,
                dtype=None):
        """Create dataset ``name`` in ``parent`` (an open group) from ``data`` or, without data,
        of ``shape`` and ``dtype``; like ``parent.create_dataset(name, shape, dtype, data)``.

        Parameters
        ----------
        parent : h5py.Group
            The group.
        name : str
            Name of the new dataset.
        data : str or numpy.ndarray, optional
            The values (any unit: written as they are); a text array is given as an object
            array of str with ``dtype=`` :attr:`text` (any variable-length UTF-8 string type).
        shape : tuple of int, optional
            Shape of a dataset without data (dimensionless).
        dtype : numpy.dtype, optional
            Type of a dataset without data, or :attr:`text` for a text array.

        Returns
        -------
        h5py.h5d.DatasetID
            The new dataset (low-level identifier; ``h5py.Dataset(id)`` gives the high-level one).
        """
        if not name or "/" in name:          # a path: h5py creates the groups on the way
            return parent.create_dataset(name, shape, dtype, data).id
        if data is not None:
            arr = self._plain(data, dtype)
            if arr is None:                  # anything else: h5py decides, as it always did
                return parent.create_dataset(name, data=data, dtype=dtype).id
            data, shape = arr, arr.shape
            dtype = self.text if arr.dtype.kind == "O" else arr.dtype
        else:
            dtype = np.dtype(dtype)
        space = h5s.create_simple(tuple(shape))
        ftype = self._text_type if dtype.kind == "O" else self._file_type(dtype)
        dsid = h5d.create(parent.id, name.encode(), ftype, space, dcpl=self._dcpl)
        if data is not None:
            dsid.write(h5s.ALL, h5s.ALL, data, mtype=ftype if dtype.kind == "S" else None)
        return dsid

    def _plain(self, data, dtype):
        """``data`` as the array h5py would write, when it is a plain case; else None."""
        if isinstance(data, str):
            return np.array(data, dtype=self.text) if dtype is None else None
        if not isinstance(data, np.ndarray):
            return None
        if dtype is not None:
            info = h5py.check_string_dtype(dtype)
            if (info is not None and info.encoding == "utf-8" and info.length is None
                    and data.dtype.kind == "O" and data.size and all(type(x) is str for x in data.flat)):
                return np.asarray(data, order="C").view(self.text)
            return None
        dt = data.dtype
        if dtype is None and dt.kind in _PLAIN_KINDS and dt.fields is None and dt.metadata is None:
            return np.asarray(data, order="C")
        return None

    def attr(self, obj, name: str, value, new: bool = False) -> None:
        """Set attribute ``name`` of ``obj`` to ``value``, replacing one of that name; like
        ``obj.attrs[name] = value``.

        Parameters
        ----------
        obj : h5py.h5o.ObjectID
            The dataset or group (low-level identifier, e.g. ``ds.id``).
        name : str
            Attribute name.
        value : object
            Its value: a str is written as a scalar variable-length UTF-8 string, a bool as int8
            0/1 (the flags of every file alike), anything else through ``h5py.AttributeManager``
            (in any unit: written as it is).
        new : bool, optional
            The caller knows ``obj`` has no attribute ``name`` yet (spares looking for it).
        """
        bname = name.encode()
        if isinstance(value, (bool, np.bool_)):      # one kind of flag in every file: int8 0/1
            value = np.int8(value)
        if type(value) is not str:
            h5py.AttributeManager(SimpleNamespace(id=obj))[name] = value
            return
        if not new and h5a.exists(obj, bname):
            h5a.delete(obj, bname)
        aid = h5a.create(obj, bname, self._text_type, self._scalar)
        try:
            aid.write(np.array(value, dtype=self.text), mtype=self._text_mem)
        except BaseException:
            aid.close()
            h5a.delete(obj, bname)
            raise
        aid.close()

    @staticmethod
    def has_attr(obj, name: str) -> bool:
        """Whether ``obj`` has attribute ``name`` (``name in obj.attrs``).

        Parameters
        ----------
        obj : h5py.h5o.ObjectID
            The dataset or group.
        name : str
            Attribute name.

        Returns
        -------
        bool
            It has.
        """
        return h5a.exists(obj, name.encode())

    @staticmethod
    def make_scale(dsid, name: str) -> None:
        """Make a dataset an HDF5 dimension scale named ``name`` (``Dataset.make_scale``).

        Parameters
        ----------
        dsid : h5py.h5d.DatasetID
            The dataset.
        name : str
            The scale's name.
        """
        h5ds.set_scale(dsid, name.encode())

    @staticmethod
    def attach_scale(dsid, scale, axis: int) -> None:
        """Attach ``scale`` to axis ``axis`` of a dataset (``ds.dims[axis].attach_scale``).

        Parameters
        ----------
        dsid : h5py.h5d.DatasetID
            The dataset.
        scale : h5py.h5d.DatasetID
            The dimension scale.
        axis : int
            The axis (dimensionless index, 0 first).
        """
        h5ds.attach_scale(dsid, scale, axis)
