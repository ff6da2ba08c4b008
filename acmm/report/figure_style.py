"""One matplotlib style for every figure of ``acmm report`` (publication quality): a colour-blind
safe cycle (:data:`COLORS`, Okabe–Ito), light grids (:data:`RC`, :data:`SPEED_RC`), the Agg backend
of :func:`acmm_qpp.plot_style.agg_pyplot` (nothing shown on screen) and a vector PDF plus a PNG
per figure for the HTML page.
"""
from __future__ import annotations

from pathlib import Path

from acmm_qpp.plot_style import agg_pyplot
from acmm_qpp.results import save_figure
import io
import matplotlib
import matplotlib.pyplot as plt
from cycler import cycler
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: Okabe–Ito colour-blind-safe palette.
COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000")

#: rcParams of the report's figures (publication style: light grids, no top/right spines).
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

#: rcParams of the report's figures on top of :data:`RC` that change no pixel but
#: save drawing time (issue 16): an axes title at the top edge of the axes, where matplotlib's
#: automatic placement puts it anyway when nothing is drawn above the axes, so that the search for
#: overlapping tick labels (a quarter of a 24-panel figure's drawing time) is skipped.
SPEED_RC = {"axes.titley": 1.0}


#: resolution of the report's PNG figures (a PDF beside each is the vector form): readable on a
#: high-density screen and in print
PNG_DPI = 160


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend with the report style (:data:`RC`, the
    :data:`COLORS` cycle, :data:`SPEED_RC`).

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    plt = agg_pyplot(force=True)
    plt.rcParams.update({**RC, "axes.prop_cycle": cycler(color=list(COLORS)), **SPEED_RC})
    return plt


def warm() -> None:
    """Draw one small figure to PDF and PNG (in memory) so that a process forked afterwards finds
    the fonts loaded, the glyph caches filled and the mathtext parser of the log-axis tick labels
    built (issue 16): each report worker would otherwise pay 0.2–0.5 s of CPU for them in its first
    figure.  Nothing is written, and this process's rcParams are left as they were.
    """
    with matplotlib.rc_context({**RC, **SPEED_RC}):   # no pyplot: the backend is left alone too
        fig = Figure(figsize=(2.0, 1.5))
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ax.plot([1.0, 2.0], [1e-5, 1.0], "o-", label="θ − θ*")
        ax.set_yscale("log")
        ax.set_xlabel("time (orbits)")
        ax.set_title("warm-up")
        ax.legend()
        fig.suptitle("warm-up")
        for fmt in ("pdf", "png"):
            fig.savefig(io.BytesIO(), format=fmt)


def fixed_layout(fig, left: float, bottom: float, top: float, right: float = 0.14, wspace: float = 0.2,
                 hspace: float = 0.2) -> None:
    """Place the axes with fixed margins instead of ``fig.tight_layout()`` (issue 16: the tight
    layout measures every tick label once more, a quarter to a third of a figure's drawing time).

    The margins are in inches, so they hold for a figure whose width grows with its number of
    panels; they leave room for the axis labels and tick labels of up to about seven characters.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    left, bottom, top, right : float
        Margins between the figure's edges and the axes grid, in inches (the unit of the figure
        size).
    wspace, hspace : float
        Space between the columns / rows, dimensionless: a fraction of the mean axes width /
        height.
    """
    w, h = fig.get_size_inches()
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wspace, hspace=hspace)


#: PNG deflate level: 3 encodes ~1.5x faster than PIL's default 6 for ~2 % larger files (issue 16)
PNG_COMPRESS_LEVEL = 3


def save(fig, directory: Path, stem: str) -> dict[str, Path]:
    """Save ``fig`` as ``<directory>/<stem>.pdf`` (vector) and ``.png``; close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    directory : pathlib.Path
        Output folder (created).
    stem : str
        File name without suffix.

    Returns
    -------
    dict
        ``{"pdf": path, "png": path}``.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    out = {"pdf": directory / f"{stem}.pdf", "png": directory / f"{stem}.png"}
    # layouts are fixed (fixed_layout, no bbox_inches="tight": it costs a second draw);
    # fixed metadata: the same data give byte-identical PDFs (no creation date)
    save_figure(fig, out["pdf"], metadata={"CreationDate": None, "Creator": "acmm report"})
    save_figure(fig, out["png"], metadata={"Software": "acmm report"}, dpi=PNG_DPI,
                pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    plt.close(fig)
    return out
