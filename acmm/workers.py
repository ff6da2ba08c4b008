"""Moved to :mod:`common.workers` (the base shared by acmm and qpp); this old path stays importable.

``acmm.workers`` is the very same module object as ``common.workers`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.workers as _module

sys.modules[__name__] = _module
