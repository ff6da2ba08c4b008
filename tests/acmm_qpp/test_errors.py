"""The error hierarchy (acmm_qpp.errors): an error carries the hint it was raised with, and the
command line prints it after the message, once."""
from __future__ import annotations

import pickle

from acmm_qpp.errors import ConfigError, ConvergenceError, OutputError, with_hint


def test_the_hint_is_the_one_the_error_was_raised_with():
    exc = ConvergenceError("Riccati solve (method='sign') failed", hint="try another design.riccati_method")
    assert str(exc) == "Riccati solve (method='sign') failed"
    assert with_hint(exc) == "Riccati solve (method='sign') failed; hint: try another design.riccati_method"
    assert with_hint(ConfigError("design.sector: residual_tol must be > 0")) == "design.sector: residual_tol must be > 0"
    assert with_hint(ConvergenceError("x; hint: y", hint="z")) == "x; hint: y"       # never twice
    assert with_hint(ValueError("plain")) == "plain"
    again = pickle.loads(pickle.dumps(exc))                 # across a process pool
    assert type(again) is ConvergenceError and again.hint == exc.hint


def test_an_output_error_is_still_an_oserror():
    exc = OutputError(2, "No such file or directory", "f.h5")
    assert exc.errno == 2 and exc.filename == "f.h5" and exc.hint == ""
