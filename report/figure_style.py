"""One matplotlib style for every figure of ``acmm report`` (publication quality).

The colours, rcParams and ``pyplot()`` come from :mod:`common.plot_style`, the project's one
style module; this module adds the report's PDF + PNG writer.

Labelled axes with units, legends, a colour-blind-safe cycle (Okabe–Ito), light grids, vector
PDF plus a PNG for the HTML page.  Figures are drawn with the non-interactive Agg backend and
closed after saving; nothing is shown on screen.
"""
from __future__ import annotations

from pathlib import Path

from common.plot_style import AXIS_COLORS, COLORS, RC, pyplot  # noqa: F401 (the one style module)
from common.results import save_figure


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
    import matplotlib.pyplot as plt

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    out = {"pdf": directory / f"{stem}.pdf", "png": directory / f"{stem}.png"}
    # layouts are fixed by tight_layout (no bbox_inches="tight": it costs a second draw);
    # fixed metadata: the same data give byte-identical PDFs (no creation date)
    from acmm import parallel_figures

    def write():
        save_figure(fig, out["pdf"], metadata={"CreationDate": None, "Creator": "acmm report"})
        save_figure(fig, out["png"], metadata={"Software": "acmm report"})

    # in a forked writer when the report enabled it (acmm.parallel_figures), else here
    parallel_figures.run(write, str(out["png"]))
    plt.close(fig)
    return out
