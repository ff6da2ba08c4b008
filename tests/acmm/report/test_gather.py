"""The report's one-line failures (acmm.report.gather): a user-facing error of a stage or a
part becomes its message on one line and its exit code; a bug, or a report that cannot write,
propagates."""
from __future__ import annotations

import numpy as np

from acmm.report.gather import Failed, failed
from acmm_qpp.errors import (EXIT_INPUT, EXIT_NUMERICAL, EXIT_OUTPUT, ConfigError, ConvergenceError,
                             OutputError)


def test_a_user_facing_error_is_one_line_with_its_exit_code():
    assert failed("t", ConfigError("bad\n   value")) == Failed("t", "bad value", EXIT_INPUT)
    assert failed("t", ConvergenceError("")) == Failed("t", "ConvergenceError", EXIT_NUMERICAL)
    assert failed("t", np.linalg.LinAlgError("singular")) == Failed("t", "numerical failure: LinAlgError: singular",
                                                                    EXIT_NUMERICAL)
    assert failed("t", MemoryError()).exit_code == EXIT_OUTPUT
    assert failed("t", KeyError("a bug")) is None


def test_a_failed_task_is_shown_unless_a_bug_or_the_report_cannot_write():
    assert failed("design mb3", ConfigError("bad")) == Failed("design mb3", "bad", EXIT_INPUT)
    assert failed("design mb3", KeyError("a bug")) is None
    assert failed("design mb3", OutputError("disk full")) is None
    assert failed("design mb3", KeyboardInterrupt()) is None
