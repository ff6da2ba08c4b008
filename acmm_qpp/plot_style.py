"""The matplotlib set-up of the project: figures into files only, on the Agg backend.

Every figure gets ``matplotlib.pyplot`` from here (:func:`agg_pyplot`), on the non-interactive
Agg backend; nothing is shown on screen (:func:`files_only_backend`).  The rcParams are each
product's own.
"""
from __future__ import annotations

import os
import stat
import sys
import tempfile
from pathlib import Path


def files_only_backend() -> None:
    """The commands draw figures into files only: matplotlib's backend is Agg whatever
    ``MPLBACKEND`` says.  An invalid or an interactive one (Jupyter's
    ``module://matplotlib_inline.backend_inline``) made ``import matplotlib`` itself fail, a
    traceback in ``acmm report``/``sweep`` (a review).  Call it before anything imports
    matplotlib or starts a process that will; the variable is inherited by those processes."""
    os.environ["MPLBACKEND"] = "Agg"
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg", force=True)
    elif "MPLCONFIGDIR" not in os.environ and not _writable_dir(_default_config_dir()):
        # no writable home: matplotlib made a new /tmp/matplotlib-* folder in every process and
        # warned twice; one folder per user, kept, holds its font cache across runs
        own = os.path.join(tempfile.gettempdir(), f"acmm-matplotlib-{os.getuid() if hasattr(os, 'getuid') else 0}")
        if _writable_dir(own, private=True):
            os.environ["MPLCONFIGDIR"] = own


def _default_config_dir() -> str:
    """matplotlib's configuration folder on this machine when ``MPLCONFIGDIR`` is not set."""
    try:
        home = Path.home()
    except (KeyError, RuntimeError):                  # no home in the password database
        return ""
    if sys.platform.startswith(("linux", "freebsd")):
        return os.path.join(os.environ.get("XDG_CONFIG_HOME") or str(home / ".config"), "matplotlib")
    return str(home / ".matplotlib")


def _writable_dir(path: str, private: bool = False) -> bool:
    """Whether ``path`` is (made) a writable folder; ``private``: made with mode 0700 and owned
    by this user (a shared temporary folder)."""
    if not path:
        return False
    try:
        os.makedirs(path, mode=0o700 if private else 0o777, exist_ok=True)
        st = os.lstat(path)
    except OSError:
        return False
    if private and (not stat.S_ISDIR(st.st_mode) or (hasattr(os, "getuid") and st.st_uid != os.getuid())):
        return False
    return os.access(path, os.W_OK)


def agg_pyplot(force: bool = False):
    """``matplotlib.pyplot`` on the Agg backend, rcParams untouched (the qpp stage figures).

    Parameters
    ----------
    force : bool
        Switch to Agg even if another backend is already selected.

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    import matplotlib  # deferred: matplotlib start-up

    matplotlib.use("Agg", force=force)
    import matplotlib.pyplot as plt  # deferred: matplotlib start-up

    return plt

