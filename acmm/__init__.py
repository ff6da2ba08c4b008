"""acmm — attitude control / momentum management of Space Station Freedom.

Implements Part II of NASA CR-185644 (Parlos & Jayasuriya, 1990): the nonlinear
rigid-body model (eqs 3.1–3.9), the torque-equilibrium attitude (eqs 4.1–4.3),
the 24-state linearization (eqs 4.4–4.50), sector-constrained LQR (ch. 5.2),
quadratic gain schedules (ch. 5.3) and the nonlinear stair-case simulation (ch. 6).
"""
__version__ = "0.1.0"

from acmm.errors import AcmmError, ConfigError, ConvergenceError, NoEquilibriumError  # noqa: F401
