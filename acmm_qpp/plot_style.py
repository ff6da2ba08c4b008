"""The one matplotlib style module of the project: backend, rcParams and colour cycle.

Every figure (the stage figures of :mod:`acmm.plots` and :mod:`qpp.plots`, the sweep's, the
report's through :mod:`acmm.report.figure_style`) gets ``matplotlib.pyplot`` from here, on the
non-interactive Agg backend; nothing is shown on screen.  Two sets of rcParams exist so the
existing figures stay as they were: :data:`RC` (publication style of ``acmm report``: Okabe–Ito
colour-blind-safe cycle, light grids, no top/right spines) and :data:`STAGE_RC` (the stage
figures: grid, 110 dpi, 9 pt).
"""
from __future__ import annotations

#: Okabe–Ito colour-blind-safe palette (roll, pitch, yaw first).
COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000")
AXIS_COLORS = dict(zip(("roll", "pitch", "yaw"), COLORS))

#: rcParams of the report's figures.
RC = {
    "figure.dpi": 100,
    "savefig.dpi": 120,
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 7.5,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "lines.linewidth": 1.0,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.frameon": False,
    "pdf.fonttype": 3,           # subsetted Type 3 fonts: small, fast, still vector text
}

#: rcParams of the stage figures (``acmm design|simulate``, the sweep).
STAGE_RC = {"figure.dpi": 110, "axes.grid": True, "grid.alpha": 0.3, "font.size": 9,
            "axes.titley": 1.0}


def files_only_backend() -> None:
    """The commands draw figures into files only: matplotlib's backend is Agg whatever
    ``MPLBACKEND`` says.  An invalid or an interactive one (Jupyter's
    ``module://matplotlib_inline.backend_inline``) made ``import matplotlib`` itself fail, a
    traceback in ``acmm report``/``sweep`` (a review).  Call it before anything imports
    matplotlib or forks a process that will; the variable is inherited by those processes."""
    import os
    import sys

    os.environ["MPLBACKEND"] = "Agg"
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg", force=True)
    elif "MPLCONFIGDIR" not in os.environ and not _writable_dir(_default_config_dir()):
        # no writable home: matplotlib made a new /tmp/matplotlib-* folder in every process
        # (never removed: the forked figure processes leave through os._exit) and warned twice;
        # one folder per user, kept, holds its font cache across runs
        import tempfile

        own = os.path.join(tempfile.gettempdir(), f"acmm-matplotlib-{os.getuid() if hasattr(os, 'getuid') else 0}")
        if _writable_dir(own, private=True):
            os.environ["MPLCONFIGDIR"] = own


def _default_config_dir() -> str:
    """matplotlib's configuration folder on this machine when ``MPLCONFIGDIR`` is not set."""
    import os
    import sys
    from pathlib import Path

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
    import os

    if not path:
        return False
    try:
        os.makedirs(path, mode=0o700 if private else 0o777, exist_ok=True)
        st = os.lstat(path)
    except OSError:
        return False
    import stat

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
    import matplotlib

    matplotlib.use("Agg", force=force)
    import matplotlib.pyplot as plt

    return plt


def stage_pyplot():
    """``matplotlib.pyplot`` on the Agg backend with :data:`STAGE_RC` applied.

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    plt = agg_pyplot(force=True)
    plt.rcParams.update(STAGE_RC)
    return plt


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend with the report style (:data:`RC`, :data:`COLORS`).

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    from cycler import cycler

    plt = agg_pyplot(force=True)
    plt.rcParams.update(RC)
    plt.rcParams["axes.prop_cycle"] = cycler(color=list(COLORS))
    return plt


def draw_warm_up_figure(plt, title: str = "warm-up (deg)", xlabel: str = "time") -> None:
    """Draw one small figure to memory with ``plt`` (a figure process's warm-up: fonts and glyph
    caches loaded before its first real figure); nothing is written, no rcParam is changed.

    Parameters
    ----------
    plt : module
        ``matplotlib.pyplot`` as the caller set it up (backend, style).
    title : str, optional
        Title text (its glyphs are cached).
    xlabel : str, optional
        Axis label text (its glyphs are cached).
    """
    import io

    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0.0, 1.0], [0.0, 1.0], lw=0.7)
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    fig.savefig(io.BytesIO(), format="png", dpi=30)
    plt.close(fig)


def _no_property_table(artist) -> str:
    """Stand-in for ``matplotlib.artist.kwdoc`` while a drawing-only process imports matplotlib."""
    return "Properties: (not listed in this figure process)"


def import_pyplot_to_draw_only() -> bool:
    """Import ``matplotlib.pyplot`` on Agg in a process that exists only to draw figures (a
    forked figure worker), without the property tables matplotlib writes into docstrings.

    When an Artist class is created, matplotlib writes the table of all its settable properties
    into the docstring of its ``set`` method, and several modules interpolate the same tables
    into others (``matplotlib.artist.kwdoc``, called ~120 times at import).  That text is for
    ``help()`` and the documentation only, yet it is ~0.7 G of the ~2 G instructions of
    importing pyplot (valgrind; ~0.15 s of CPU).  Here ``kwdoc`` returns one short line while
    pyplot and the modules it imports are loaded, and is restored afterwards; the signatures of
    the ``set`` methods, the property aliases and everything that draws are untouched.  The
    short line also stays in matplotlib's docstring-interpolation cache (``%(Line2D:kwdoc)s``
    and the like), so a module imported later in this process gets it in its docstrings too.
    Only for a process whose docstrings nobody reads: the stage's own process (or a user's)
    never calls this.

    Returns
    -------
    bool
        True when pyplot was imported here with the short docstrings; False when matplotlib
        was already imported (nothing is changed) or ``kwdoc`` is not there (a plain import).
    """
    import sys

    if "matplotlib.artist" not in sys.modules:   # (else its classes exist already: nothing to gain)
        from matplotlib import artist

        kwdoc = getattr(artist, "kwdoc", None)
        if callable(kwdoc):
            artist.kwdoc = _no_property_table
            try:
                agg_pyplot(force=True)
                import matplotlib.backends.backend_agg  # noqa: F401  (what every figure saves with)
            finally:
                artist.kwdoc = kwdoc
            return True
    agg_pyplot(force=True)
    return False
