"""Moved to :mod:`common.results` (the base shared by acmm and qpp); this old path stays importable.

``acmm.results`` is the very same module object as ``common.results`` (all names, private ones
included, and any module state are shared).
"""
import sys

import common.results as _module

sys.modules[__name__] = _module
