"""The package's small exception hierarchy and the exit code of each kind of failure.

Every error a user can trigger with a config, a file or a numerical problem derives from
:class:`AcmmError`; the command-line apps catch it, print its message on one line on stderr (with
the ``hint`` it was raised with, :func:`with_hint`) and exit with the class's ``exit_code``:

====  =====================================================================================
code  meaning
====  =====================================================================================
0     success (a failing verdict is a *result*: 0 unless ``--strict``)
1     ``--strict``: the run finished but its verdict is a failure (e.g. a diverged
      simulation, a design without its certificate)
2     bad input: config missing, unreadable, malformed, inconsistent or physically impossible;
      a bad command-line value
3     numerical failure: a solver did not converge, a design cannot meet its specification
4     output / I/O: the results cannot be written (not a directory, read-only, disk full),
      or another run holds the lock on ``runs/<name>``
64    command-line usage (unknown option, missing argument) — EX_USAGE of sysexits.h
130   interrupted (Ctrl-C)
143   terminated (SIGTERM; 129 for SIGHUP): cleaned up like Ctrl-C
====  =====================================================================================
"""

EXIT_VERDICT = 1
EXIT_INPUT = 2
EXIT_NUMERICAL = 3
EXIT_OUTPUT = 4
EXIT_USAGE = 64
EXIT_INTERRUPTED = 130


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP received by a command (:func:`acmm_qpp.signals.terminate_like_ctrl_c`): it
    unwinds like Ctrl-C (rollback of the stage's outputs, its helper processes killed) and exits
    with 128 + the signal number.

    Parameters
    ----------
    signum : int
        The signal received; ``exit_code`` is 128 + it (143 for SIGTERM, 129 for SIGHUP).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)
        self.exit_code = 128 + self.signum


class AcmmError(Exception):
    """Base class of every error the tool reports to a user.

    Parameters
    ----------
    *args : object
        The message (and anything else the built-in exception takes).
    hint : str, optional
        Which setting to change, in the words of the product that raises it (empty: none).
    """

    exit_code = EXIT_INPUT
    hint = ""

    def __init__(self, *args, hint: str = "") -> None:
        super().__init__(*args)
        if hint:
            self.hint = hint


def with_hint(exc: BaseException) -> str:
    """The message of an error followed by ``; hint: ...`` when it was raised with one.

    Parameters
    ----------
    exc : BaseException
        The error.

    Returns
    -------
    str
        ``str(exc)``, and its ``hint`` when it has one and the message carries none yet.
    """
    msg, hint = str(exc), getattr(exc, "hint", "")
    return f"{msg}; hint: {hint}" if hint and "hint:" not in msg.lower() else msg


class ConfigError(AcmmError, ValueError):
    """A config file is missing, unreadable, malformed or physically impossible (exit 2, the
    :class:`AcmmError` default)."""


class ConvergenceError(AcmmError, ArithmeticError):
    """A numerical solver did not converge or its result failed verification (exit 3)."""

    exit_code = EXIT_NUMERICAL


class DesignError(AcmmError):
    """A control design cannot meet its specification (exit 3)."""

    exit_code = EXIT_NUMERICAL


class OutputError(AcmmError, OSError):
    """A results file or figure cannot be written (e.g. the output root is not a directory),
    or the run folder is locked by another run (exit 4)."""

    exit_code = EXIT_OUTPUT


class FigureError(OutputError):
    """A stage's figure cannot be written, its results were (exit 4; the run keeps its results
    and its ``config.yaml``, :mod:`acmm_qpp.outputs`)."""

    @classmethod
    def of(cls, exc: BaseException) -> "FigureError":
        """``exc`` (raised while drawing a figure) as a FigureError, with its message.

        Parameters
        ----------
        exc : BaseException
            What the figure function raised.

        Returns
        -------
        FigureError
            ``exc`` itself when it is one.
        """
        return exc if isinstance(exc, cls) else cls(str(exc) or type(exc).__name__)


def plain_failure(exc: BaseException):
    """(one-line message, exit code) of an exception that is not an :class:`AcmmError` but still a
    user-facing failure (out of memory, a numerical error, an I/O error); None for a genuine bug.

    Parameters
    ----------
    exc : BaseException
        The exception caught.

    Returns
    -------
    tuple of (str, int) or None
        The message and the exit code (:data:`EXIT_INPUT`, :data:`EXIT_NUMERICAL` or
        :data:`EXIT_OUTPUT`), or None: a bug, to be left to propagate.
    """
    import numpy as np  # deferred: the CLI sets the BLAS thread defaults before numpy's first import

    if isinstance(exc, RecursionError):
        return "input nested too deeply to process", EXIT_INPUT
    if isinstance(exc, MemoryError):
        return "out of memory (reduce the problem size)", EXIT_OUTPUT
    if isinstance(exc, (FloatingPointError, OverflowError, ZeroDivisionError, np.linalg.LinAlgError)):
        return f"numerical failure: {type(exc).__name__}: {exc}", EXIT_NUMERICAL
    if isinstance(exc, OSError):
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        return f"I/O error: {exc.strerror or exc}{where}", EXIT_OUTPUT
    return None
