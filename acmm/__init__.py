"""acmm — attitude control / momentum management of Space Station Freedom.

Implements Part II of NASA CR-185644 (Parlos & Jayasuriya, 1990): the nonlinear
rigid-body model (eqs 3.1–3.9), the torque-equilibrium attitude (eqs 4.1–4.3),
the 24-state linearization (eqs 4.4–4.50), sector-constrained LQR (ch. 5.2),
quadratic gain schedules (ch. 5.3) and the nonlinear stair-case simulation (ch. 6).
"""
__version__ = "0.1.0"

from common.errors import AcmmError, ConfigError, ConvergenceError, NoEquilibriumError  # noqa: F401
from common.netcdf_layout import register_state_names as _register_state_names


def _state_names():
    from acmm.linearize import STATE_NAMES

    return STATE_NAMES


#: the ``state`` dimension of every results file holds the 24 states of eq 4.47
_register_state_names(_state_names)

#: The Python API (acmm/api.py), imported on first use.  ``acmm.linearize`` and
#: ``acmm.simulate`` are submodules, so the API's functions of those names are re-exported
#: as ``acmm.linear_model`` and ``acmm.simulation``.
_API = {"load_config": "load_config", "design": "design", "Design": "Design",
        "linear_model": "linearize", "simulation": "simulate"}


def __getattr__(name):
    if name in _API:
        from acmm import api

        return getattr(api, _API[name])
    raise AttributeError(f"module 'acmm' has no attribute {name!r}")
