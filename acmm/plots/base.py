"""What every stage figure shares (report Figs 5.3–5.26, 6.2–6.30): saving a figure (PNG/PDF,
atomically), texts rendered ahead, tick and line thinning, and the unit labels of the 24 states of
eq 4.46; the figures themselves are in :mod:`acmm.plots.design` and :mod:`acmm.plots.simulation`.

Drawing cost (issue 16): a figure function first builds everything that does not depend on the
data (axes, empty lines, legend, tick artists) with its fixed texts rasterized (:func:`bake_texts`),
then sets the data and the limits (:func:`data_limits`, no autoscaling bookkeeping) and saves.
Grids of panels are drawn without an Axes each (:mod:`acmm.plots.panel_grid`), tick labels are few
and short (:func:`in_view_ticks`, :func:`compact_formatter`) and text is unhinted while these
figures are drawn (:data:`FAST_TEXT_RC`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from acmm_qpp.plot_style import agg_pyplot
from acmm_qpp.results import save_figure
import re
import itertools
from acmm.model.linearize import state_units as units
import matplotlib
from matplotlib.backends.backend_agg import RendererAgg
from matplotlib.artist import Artist
from matplotlib.ticker import Formatter, MaxNLocator

#: rcParams of the stage figures (``acmm design|simulate``, the sweep); saved at the figure's own
#: resolution also in a process that drew the report's figures (:data:`acmm.report.figure_style.RC` sets
#: ``savefig.dpi``)
STAGE_RC = {"figure.dpi": 110, "savefig.dpi": "figure", "axes.grid": True, "grid.alpha": 0.3, "font.size": 9,
            "axes.titley": 1.0}


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

AXES = ("roll", "pitch", "yaw")


#: rcParams of the cost-cut stage figures (issue 16), applied only while they are laid out and
#: drawn (:func:`write_figure` with ``rc``, :func:`bake_texts`), never set globally (the report draws
#: its own figures, and two of these, in the same process): unhinted glyphs render ~40 % faster
FAST_TEXT_RC = {"text.hinting": "none"}

#: PNG deflate level: 1 encodes ~1.7x faster than PIL's default 6 for ~10 % larger files (issue 16)
PNG_COMPRESS_LEVEL = 1


def write_figure(fig, path: Path, vector: bool = False, tight: bool = True, rc: dict | None = None) -> list[Path]:
    """Write ``fig`` as PNG (and PDF with ``vector``) beside ``path``'s stem, atomically, and
    close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : pathlib.Path
        The file; its suffix is replaced by ``.png`` (and ``.pdf``).
    vector : bool, optional
        Also write a PDF.
    tight : bool, optional
        Save with a tight bounding box.
    rc : dict, optional
        rcParams in effect while saving.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    path = Path(path)
    out = [path.with_suffix(".png")]
    bbox = "tight" if tight else None
    with matplotlib.rc_context(rc or {}):
        save_figure(fig, out[0], bbox_inches=bbox, pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
        if vector:
            out.append(path.with_suffix(".pdf"))
            save_figure(fig, out[1], bbox_inches=bbox)
    stage_pyplot().close(fig)       # no fig.clf(): clearing 12 axes cost ~0.15 s, close frees it
    return out


def bake_texts(fig, texts) -> None:
    """Render data-independent ``texts`` (titles, axis labels, a legend: artists already placed
    by a fixed layout) now, into small transparent images at the figure's resolution that take
    their place; the texts themselves are hidden.

    Laying out and rasterizing text is the costliest part of drawing a stage figure (each glyph
    is rendered on its own).  The PNG differs from drawing the texts at save time only by rounding of the
    anti-aliased edges.  Drawn on any other canvas (a PDF, another size or resolution, a
    'tight' bounding box) the texts are drawn as texts instead.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    texts : iterable of matplotlib.artist.Artist
        The texts (and legends) to render now.
    """
    w, h = (round(float(v)) for v in fig.bbox.size)
    renderer = RendererAgg(w, h, fig.dpi)
    texts = [t for t in texts if t.get_visible()]
    with matplotlib.rc_context(FAST_TEXT_RC):
        for t in texts:
            t.draw(renderer)
            t.set_visible(False)
    rgba = np.asarray(renderer.buffer_rgba())
    ink = rgba[..., 3] > 0
    tiles = [(c0, h - r1, rgba[r0:r1, c0:c1][::-1].copy())             # rows bottom first
             for r0, r1 in _runs(ink.any(axis=1), 0) for c0, c1 in _runs(ink[r0:r1].any(axis=0), 8)]
    fig.add_artist(_tiles_artist(tiles, texts, (w, h, fig.dpi)))


def _tiles_artist(tiles: list, texts: list, canvas: tuple):
    """An artist blending pre-rendered RGBA ``tiles`` ``(x, y, array)`` (pixels from the lower
    left, rows bottom first) onto an Agg renderer of ``canvas`` (width, height, dpi) as they
    are, without resampling; on any other renderer it draws the hidden ``texts`` instead."""
    class Tiles(Artist):
        zorder = 3

        def draw(self, renderer) -> None:
            if not self.get_visible():
                return
            if not (isinstance(renderer, RendererAgg) and (renderer.width, renderer.height, renderer.dpi) == canvas):
                for t in texts:
                    t.set_visible(True)
                    t.draw(renderer)
                    t.set_visible(False)
                return
            gc = renderer.new_gc()
            for x, y, im in tiles:
                renderer.draw_image(gc, x, y, im)
            gc.restore()
            self.stale = False

    return Tiles()


def _runs(mask, gap: int) -> list:
    """(start, stop) of the runs of True in ``mask``, runs closer than ``gap`` merged."""
    idx = np.flatnonzero(mask)
    if idx.size == 0:
        return []
    cut = np.flatnonzero(np.diff(idx) > gap + 1)
    starts = np.concatenate([[idx[0]], idx[cut + 1]])
    stops = np.concatenate([idx[cut], [idx[-1]]]) + 1
    return list(zip(starts.tolist(), stops.tolist()))


def premake_ticks(axes, nx: int = 9, ny: int = 8) -> None:
    """Create the tick artists now (the costly part of an axis): at draw time the axis reuses
    the first ones it needs and makes more only if the locator asks for more.

    Parameters
    ----------
    axes : iterable of matplotlib.axes.Axes
        The axes.
    nx, ny : int, optional
        Ticks to make on the x and y axis.
    """
    for ax in axes:
        ax.xaxis.get_major_ticks(nx)
        ax.yaxis.get_major_ticks(ny)


#: lines longer than this are drawn as a min/max envelope per pixel column (issue 16)
MAX_LINE_POINTS = 4000


def decimate(x, y, max_points: int = MAX_LINE_POINTS):
    """(x, y) reduced to at most ~``max_points`` points keeping each bucket's min and max.

    At figure resolution (a few hundred pixels per axes) the drawn envelope is identical to the
    full line; shorter lines are returned unchanged.

    Parameters
    ----------
    x : (N,) array
        Abscissae, any unit (kept).
    y : (N,) array
        Ordinates, any unit (kept).
    max_points : int, optional
        Most points kept (about).

    Returns
    -------
    tuple
        (x, y) subsets, in the units given.
    """
    x = np.asarray(x)
    y = np.asarray(y)
    n = x.shape[0]
    if n <= max_points:
        return x, y
    buckets = max_points // 2
    edges = np.linspace(0, n, buckets + 1).astype(int)
    idx = []
    for a, b in zip(edges[:-1], edges[1:]):          # n > 2·buckets: every bucket has ≥ 2 points
        seg = y[a:b]
        if not np.isfinite(seg).any():
            idx.append(a)
            continue
        i, j = a + int(np.nanargmin(seg)), a + int(np.nanargmax(seg))
        idx.extend(sorted({i, j}))
    idx = np.asarray(idx)
    return x[idx], y[idx]


def state_units(drf_mode: str = "attitude_hold") -> list[str]:
    """:func:`acmm.model.linearize.state_units` written for labels (ft·lbf·s², rad·s).

    Parameters
    ----------
    drf_mode : str, optional
        DRF mode of the 24 states.

    Returns
    -------
    list of str
        The 24 unit labels.
    """

    def pretty(u: str) -> str:
        if "/" in u:
            return u
        u = u.replace("*", "·")
        # combine repeated s factors: ft·lbf·s·s^2 -> ft·lbf·s³
        m = re.fullmatch(r"(.*?)((?:·?s(?:\^\d)?)+)", u)
        if m and m.group(2).strip("·"):
            p = sum(int(f[2:]) if "^" in f else 1 for f in m.group(2).strip("·").split("·"))
            head = m.group(1)
            u = (head + "·" if head else "") + "s" + ("" if p == 1 else "⁰¹²³⁴⁵⁶⁷⁸⁹"[p])
        return u

    return [pretty(u) for u in units(drf_mode)]


def compact_formatter():
    """A tick formatter writing each value in full and short (``−7.5e6``, ``0.0045``, ``−1.5e-5``)
    with the fewest significant digits that keep the labels distinct and exact: no offset or
    ×10ⁿ text above the axes (it collides with the panel titles and is one more text per axis).

    Returns
    -------
    matplotlib.ticker.Formatter
        The formatter.
    """
    class Compact(Formatter):
        @staticmethod
        def _label(v: float, d: int, sci: bool) -> str:
            if v == 0:
                return "0"
            if sci:
                m, e = f"{v:.{d}e}".split("e")
                s = f"{m.rstrip('0').rstrip('.') if '.' in m else m}e{int(e)}"
            else:
                s = f"{v:.{d}f}"
            return s.replace("-", "\N{MINUS SIGN}")

        def format_ticks(self, values):
            values = [float(v) for v in values]
            big = max((abs(v) for v in values), default=0.0)
            sci = big >= 1e5 or 0 < big < 1e-3
            step = min((abs(b - a) for a, b in itertools.pairwise(values) if b != a), default=0.0)
            for d in range(10):
                labels = [self._label(v, d, sci) for v in values]
                if all(abs(float(lab.replace("\N{MINUS SIGN}", "-")) - v) <= 1e-6 * step
                       for lab, v in zip(labels, values)):
                    return labels
            return labels

        def __call__(self, x, pos=None):
            return self.format_ticks([x])[0]

    return Compact()


def in_view_ticks(lo: float, hi: float, nbins: int) -> list:
    """At most ``nbins`` + 1 "nice" tick values inside [lo, hi] (at least three): matplotlib's
    :class:`~matplotlib.ticker.MaxNLocator` also returns the ticks just outside the view, and an
    axis makes (five artists) and updates a tick for each before dropping them.

    Parameters
    ----------
    lo, hi : float
        The view, units of the data.
    nbins : int
        Most intervals between ticks.

    Returns
    -------
    list of float
        The tick values, units of the data.
    """
    lo, hi = sorted((lo, hi))
    tol = 1e-10 * (hi - lo)              # as an axis keeps a tick (relative to the view's span)
    return [v for v in MaxNLocator(nbins, min_n_ticks=3).tick_values(lo, hi) if lo - tol <= v <= hi + tol]


def data_limits(*arrays, margin: float = 0.05):
    """(lo, hi) of the finite values of ``arrays`` widened by ``margin`` of the span on each side
    (matplotlib's autoscale margins), or None when there is none; set on an axis directly this
    replaces the data-limit bookkeeping of the plotting calls.

    Parameters
    ----------
    *arrays : array_like
        The data (in the units of the axis).
    margin : float, optional
        Fraction of the span added on each side (dimensionless).

    Returns
    -------
    tuple of float or None
        (lo, hi) in the units of the data; None when no value is finite.
    """
    a = np.concatenate([np.empty(0), *(np.asarray(x, dtype=float).ravel() for x in arrays)])
    a = a[np.isfinite(a)]
    if a.size == 0:
        return None
    lo, hi = float(a.min()), float(a.max())
    pad = (hi - lo) * margin
    if pad <= 1e-12 * max(abs(lo), abs(hi)):         # one value: ±5 % of it (or ±0.05 about 0)
        pad = 0.05 * abs(lo) if lo else 0.05
    lo, hi = lo - pad, hi + pad
    # values below ~2e-287, or a span lost to underflow: ±0.05, as an Axes widens such a view
    return (lo, hi) if hi > lo and max(abs(lo), abs(hi)) >= 1e21 * np.finfo(float).tiny else (-0.05, 0.05)
