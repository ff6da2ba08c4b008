"""Moved to :mod:`common.overrides` (the base shared by acmm and qpp); this old path stays importable.

``acmm.overrides`` is the very same module object as ``common.overrides`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.overrides as _module

sys.modules[__name__] = _module
