"""Moved to :mod:`common.netcdf_layout` (the base shared by acmm and qpp); this old path stays importable.

``acmm.netcdf_layout`` is the very same module object as ``common.netcdf_layout`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.netcdf_layout as _module

sys.modules[__name__] = _module
