"""Small multiples without an Axes each: a grid of panels drawn by a handful of figure artists.

The gain-schedule figure of ch. 5.3 has 24 panels (cf. Figs 5.3–5.26).  As 24 matplotlib Axes it is ~1 500
artists (each Axes has two Axis objects, each tick five artists), and building and drawing them
was the costliest figure of the design stage (issue 16); the simulation's 12 histories per axis
(ch. 6, Figs 6.2–6.13) and 6 inertia panels are drawn the same way.  A :class:`PanelGrid` draws the same
picture — frames, tick marks, grid lines, tick labels, titles and the data — with one line
collection for all frames, one for all tick marks, one for all grid lines, one line (or marker
set) per series for all panels, and the texts: ~130 artists.  Everything lives in figure
coordinates; each panel maps its data limits onto its box, and the data are drawn inside the
limits (no clipping is needed: the limits are set from the data).

What a test or a reader of the figure needs is kept as data (:class:`Panel`): each panel's
title, limits, ticks and the (x, y) of every series; the grid is ``fig.panel_grid``, where a
figure of Axes would be read through ``fig.axes``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acmm.plots.base import data_limits, in_view_ticks
import matplotlib as mpl
from matplotlib.collections import LineCollection
from matplotlib.gridspec import GridSpec
from matplotlib.lines import Line2D


@dataclass
class Panel:
    """One panel of a :class:`PanelGrid`.

    Attributes
    ----------
    box : tuple of float
        (left, bottom, width, height), units of the figure's width and height.
    title : str
        Panel title.
    xlim, ylim : tuple of float
        Data limits mapped onto the box, units of the data's x and y.
    xticks, yticks : list of float
        Tick values, units of the data; x ticks are labelled on the bottom row only, and drawn as grid
        lines everywhere.
    xlabel, ylabel : str
        Label under the panel (bottom row) and left of it, or "".
    data : dict
        Series index → (x, y) arrays drawn in this panel, units of the data.
    """

    box: tuple
    title: str = ""
    xlim: tuple = (0.0, 1.0)
    ylim: tuple = (0.0, 1.0)
    xticks: list = field(default_factory=list)
    yticks: list = field(default_factory=list)
    xlabel: str = ""
    ylabel: str = ""
    data: dict = field(default_factory=dict)

    def _to_figure(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Data (x, y) → figure coordinates (units of the figure's width and height), through the
        panel's limits and box."""
        x0, y0, w, h = self.box
        fx = x0 + (np.asarray(x, float) - self.xlim[0]) / (self.xlim[1] - self.xlim[0]) * w
        fy = y0 + (np.asarray(y, float) - self.ylim[0]) / (self.ylim[1] - self.ylim[0]) * h
        return fx, fy


class PanelGrid:
    """A ``rows`` × ``cols`` grid of panels on ``fig``, placed like ``fig.subplots`` with the
    given ``subplots_adjust`` parameters.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (its size and dpi are final).
    rows, cols : int
        Grid shape; panels are numbered row by row.
    series : list of dict
        One :class:`~matplotlib.lines.Line2D` style per series (e.g. dots of one colour, a line
        of one colour); each series is one artist across all panels.
    adjust : dict
        ``left``, ``right``, ``bottom``, ``top``, ``wspace``, ``hspace`` (units of the figure's
        size and of the mean panel size, as :meth:`matplotlib.figure.Figure.subplots_adjust`).
    title_size, tick_size : float
        Font sizes, units of points (1/72 in); ``title_size`` may also be a matplotlib size name
        (``"large"``).
    """

    def __init__(self, fig, rows: int, cols: int, series: list, adjust: dict,
                 title_size: float | str = 8.0, tick_size: float = 7.0) -> None:
        self.fig, self.rows, self.cols = fig, rows, cols
        self.tick_size = tick_size
        bottoms, tops, lefts, rights = GridSpec(rows, cols, **adjust).get_grid_positions(fig)
        self.panels = [Panel((lefts[c], bottoms[r], rights[c] - lefts[c], tops[r] - bottoms[r]))
                       for r in range(rows) for c in range(cols)]
        rc, tf = mpl.rcParams, fig.transFigure
        boxes = [p.box for p in self.panels]
        pad = rc["axes.titlepad"] / 72 * fig.dpi / fig.bbox.height
        self.titles = [fig.text(x0 + w / 2, y0 + h + pad, "", ha="center", va="baseline", fontsize=title_size)
                       for x0, y0, w, h in boxes]
        self.frames = fig.add_artist(LineCollection(
            [[(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h), (x0, y0)] for x0, y0, w, h in boxes],
            colors=rc["axes.edgecolor"], linewidths=rc["axes.linewidth"], transform=tf, zorder=2.5))
        self.grid = fig.add_artist(LineCollection([], colors=rc["grid.color"], linewidths=rc["grid.linewidth"],
                                                  alpha=rc["grid.alpha"], transform=tf, zorder=1.5))
        self.ticks = fig.add_artist(LineCollection([], colors=rc["ytick.color"],
                                                   linewidths=rc["ytick.major.width"], transform=tf, zorder=2.5))
        self.lines = [fig.add_artist(Line2D([], [], transform=tf, zorder=2, **style)) for style in series]
        self.tick_labels: list = []
        self.labels: list = []
        fig.panel_grid = self

    def set_title(self, k: int, text: str) -> None:
        """Set the title of a panel.

        Parameters
        ----------
        k : int
            Panel index (row by row).
        text : str
            The title.
        """
        self.panels[k].title = text
        self.titles[k].set_text(text)

    def set_label(self, k: int, text: str, side: str, offset: float | None = None,
                  fontsize: float | None = None) -> None:
        """Put a label under a panel (``side="below"``: its top ``offset`` below the frame) or
        left of it (``side="left"``: vertical, its baseline ``offset`` left of the frame, as an
        Axes' y label placed with ``set_label_coords(-offset, 0.5)``).

        Parameters
        ----------
        k : int
            Panel index (row by row).
        text : str
            The label.
        side : {"below", "left"}
            Where it goes.
        offset : float, optional
            Distance from the frame, units of the panel's height (below, default 0.13) or width
            (left, default 0.18).
        fontsize : float, optional
            Font size, units of points (default: the axes label size).

        Raises
        ------
        ValueError
            ``side`` is neither "below" nor "left".
        """
        p = self.panels[k]
        x0, y0, w, h = p.box
        if side == "below":
            p.xlabel = text
            kw = {"x": x0 + w / 2, "y": y0 - (0.13 if offset is None else offset) * h, "va": "top"}
        elif side == "left":
            p.ylabel = text
            kw = {"x": x0 - (0.18 if offset is None else offset) * w, "y": y0 + h / 2, "va": "bottom",
                  "rotation": 90, "rotation_mode": "anchor"}
        else:
            raise ValueError(f"side must be 'below' or 'left', not {side!r}")
        self.labels.append(self.fig.text(s=text, ha="center", fontsize=fontsize, **kw))

    def show(self, k: int, xlim, data: list, xticks, nbins: int = 3) -> None:
        """Set a panel from its data: series ``s`` of ``data`` as (s, x, y), the y limits the
        data's finite range with 5 % margins (0 to 1 when there is none), at most ``nbins`` + 1
        y ticks inside them.

        Parameters
        ----------
        k : int
            Panel index (row by row).
        xlim : tuple of float
            (low, high) of x, units of the data.
        data : list of tuple
            (series index, x, y) of each series drawn in the panel, units of the data.
        xticks : sequence of float
            x tick values, units of the data.
        nbins : int, optional
            Most intervals between y ticks.
        """
        p = self.panels[k]
        for s, x, y in data:
            p.data[s] = (np.asarray(x, float), np.asarray(y, float))
        ylim = data_limits(*(y for _, _, y in data)) or (0.0, 1.0)
        p.xlim, p.ylim = tuple(map(float, xlim)), tuple(map(float, ylim))
        p.xticks, p.yticks = [float(v) for v in xticks], [float(v) for v in in_view_ticks(*ylim, nbins)]

    def draw_data(self, formatter) -> None:
        """Put every panel's series, grid lines, tick marks and tick labels (x: the bottom row's) in place.

        Parameters
        ----------
        formatter : callable
            Tick values → their label strings (``Formatter.format_ticks``).
        """
        fig = self.fig
        tick = 3.5 / 72 * fig.dpi                 # tick length and label pad, px (matplotlib's)
        tw, th = tick / fig.bbox.width, tick / fig.bbox.height
        grid, marks = [], []
        for t in self.tick_labels:
            t.remove()
        self.tick_labels = []
        for k, p in enumerate(self.panels):
            x0, y0, w, h = p.box
            gx, _ = p._to_figure(p.xticks, np.zeros(len(p.xticks)))
            _, gy = p._to_figure(np.zeros(len(p.yticks)), p.yticks)
            grid += [[(x, y0), (x, y0 + h)] for x in gx] + [[(x0, y), (x0 + w, y)] for y in gy]
            marks += [[(x0 - tw, y), (x0, y)] for y in gy]
            self._labels(formatter(p.yticks), x0 - 2 * tw, gy, {"ha": "right", "va": "center_baseline"})
            if k >= (self.rows - 1) * self.cols:
                marks += [[(x, y0 - th), (x, y0)] for x in gx]
                self._labels(formatter(p.xticks), gx, y0 - 2 * th, {"ha": "center", "va": "top"})
        self.grid.set_segments(grid)
        self.ticks.set_segments(marks)
        for s, line in enumerate(self.lines):
            xs, ys = [], []
            for p in self.panels:
                if s in p.data:
                    fx, fy = p._to_figure(*p.data[s])
                    xs += [fx, [np.nan]]
                    ys += [fy, [np.nan]]
            line.set_data(np.concatenate(xs) if xs else [], np.concatenate(ys) if ys else [])

    def _labels(self, labels, x, y, align: dict) -> None:
        xs, ys = np.broadcast_to(x, (len(labels),)), np.broadcast_to(y, (len(labels),))
        self.tick_labels += [self.fig.text(xi, yi, lab, fontsize=self.tick_size, **align)
                             for lab, xi, yi in zip(labels, xs, ys)]

