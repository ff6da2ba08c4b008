"""One matplotlib style for every figure of ``acmm report`` (publication quality).

The rcParams live in the style sheet ``report/figures.mplstyle`` (package data).

Labelled axes with units, legends, a colour-blind-safe cycle (Okabe–Ito), light grids, vector
PDF plus a PNG for the HTML page.  Figures are drawn with the non-interactive Agg backend and
closed after saving; nothing is shown on screen.
"""
from __future__ import annotations

from importlib import resources
from pathlib import Path

from acmm.results import save_figure

#: Okabe–Ito colour-blind-safe palette (roll, pitch, yaw first).
COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000")
AXIS_COLORS = dict(zip(("roll", "pitch", "yaw"), COLORS))

def _read_style() -> dict[str, str]:
    """``report/figures.mplstyle`` (package data) as {rcParam: text}; matplotlib validates the
    text values when they are applied."""
    text = resources.files("report").joinpath("figures.mplstyle").read_text(encoding="utf-8")
    out = {}
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            key, value = (s.strip() for s in line.split(":", 1))
            out[key] = value
    return out


#: rcParams of the report's figures (from ``report/figures.mplstyle``)
RC = _read_style()


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend with the report style applied."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    from cycler import cycler

    plt.rcParams.update(RC)
    plt.rcParams["axes.prop_cycle"] = cycler(color=list(COLORS))
    return plt


def save(fig, directory: Path, stem: str) -> dict[str, Path]:
    """Save ``fig`` as ``<directory>/<stem>.pdf`` (vector) and ``.png``; close it.

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
