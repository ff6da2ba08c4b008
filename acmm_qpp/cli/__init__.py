"""Command-line apps (typer): parse arguments, call the libraries, print. No mathematics here."""

import os as _os

# Small dense problems (24 states) run 5-20x slower with multi-threaded BLAS on a loaded 2-core
# machine; one thread is the right default for the CLI.  Must be set before numpy is imported.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
_os.environ.setdefault("OMP_NUM_THREADS", "1")
