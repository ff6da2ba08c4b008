"""Moved to :mod:`common.limits` (the base shared by acmm and qpp); this old path stays importable.

``acmm.limits`` is the very same module object as ``common.limits`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.limits as _module

sys.modules[__name__] = _module
