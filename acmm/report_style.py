"""Compatibility shim: the report's figure style moved to :mod:`report.figure_style` (issue 12)."""
from report.figure_style import AXIS_COLORS, COLORS, RC, pyplot, save  # noqa: F401
