"""Compatibility shim: the sweep configuration moved to :mod:`acmm.sweep.config` (issue 12).

Every name of :mod:`acmm.sweep.config` (private ones included) is available here.
"""
from acmm.sweep import config as _config

globals().update({k: v for k, v in vars(_config).items() if not k.startswith("__")})
