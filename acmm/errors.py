"""Moved to :mod:`common.errors` (the base shared by acmm and qpp); this old path stays importable.

``acmm.errors`` is the very same module object as ``common.errors`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.errors as _module

sys.modules[__name__] = _module
