"""Moved to :mod:`common.runlock` (the base shared by acmm and qpp); this old path stays importable.

``acmm.runlock`` is the very same module object as ``common.runlock`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.runlock as _module

sys.modules[__name__] = _module
