"""Compatibility shim: the report moved to the top-level package :mod:`report` (issue 12).

``from acmm.report import build_report`` keeps working; new code imports :mod:`report`.
"""
from report import *  # noqa: F401,F403
from report import _Report  # noqa: F401
from report import __all__  # noqa: F401
