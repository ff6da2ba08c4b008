"""Moved to :mod:`common.hints` (the base shared by acmm and qpp); this old path stays importable.

``acmm.hints`` is the very same module object as ``common.hints`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.hints as _module

sys.modules[__name__] = _module
