"""Moved to :mod:`common.outputs` (the base shared by acmm and qpp); this old path stays importable.

``acmm.outputs`` is the very same module object as ``common.outputs`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.outputs as _module

sys.modules[__name__] = _module
