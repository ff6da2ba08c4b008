"""The package's small exception hierarchy.

Every error a user can trigger with a config or a file derives from :class:`AcmmError`;
the command-line apps catch it, print its message on one line and exit with code 2.
"""


class AcmmError(Exception):
    """Base class of every error the tool reports to a user (exit code 2)."""


class ConfigError(AcmmError, ValueError):
    """A config file is missing, unreadable, malformed or physically impossible."""


class ConvergenceError(AcmmError, ArithmeticError):
    """A numerical solver did not converge or its result failed verification."""


class NoEquilibriumError(AcmmError):
    """No torque-equilibrium attitude exists for the given inertia and bias (eqs 4.1–4.3)."""


class DesignError(AcmmError):
    """A control design cannot meet its specification (e.g. poles outside the sector)."""


class OutputError(AcmmError, OSError):
    """A results file or figure cannot be written (e.g. the output root is not a directory)."""
