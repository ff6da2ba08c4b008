"""Figures of the simulation stage (ch. 6): attitude error, rate, torque and CMG momentum per axis
(Figs 6.2–6.13, 6.20–6.30), the inertia steps of the stair-case (Figs 6.14–6.19) and a one-page
summary with the per-level statistics.  Each function takes arrays, draws one figure and saves it
as PNG (and PDF when asked) under the given path.
"""
from __future__ import annotations

import numpy as np

from acmm.plots.base import (AXES, FAST_TEXT_RC, bake_texts, compact_formatter, data_limits,
    premake_ticks, write_figure, decimate, in_view_ticks, stage_pyplot)
from acmm.plots.panel_grid import PanelGrid
from acmm.model.unit_systems import pretty, shown
import matplotlib as mpl
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator


def _in_view_locator(nbins: int):
    """An axis locator placing :func:`acmm.plots.base.in_view_ticks` (at most ``nbins`` + 1) in the axis' view."""
    class InView(MaxNLocator):
        def __call__(self):
            return in_view_ticks(*self.axis.get_view_interval(), nbins)

    return InView(nbins, min_n_ticks=3)


def axis_histories(orbits, err_deg, rate, u, h, title, path, vector=False, units="imperial"):
    """Angle error, rate, delivered torque and CMG momentum per axis vs orbit (Figs 6.2–6.13, 6.20–6.30).

    ``u`` (ft·lbf) and ``h`` (ft·lbf·s) are shown in the unit system ``units``.

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    err_deg : (N, 3) array
        Attitude error θ − θ̂*, deg.
    rate : (N, 3) array
        Body rate relative to LVLH, deg/s.
    u : (N, 3) array
        Delivered torque, ft·lbf.
    h : (N, 3) array
        CMG momentum, ft·lbf·s.
    title : str
        Figure title.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    u, uu = shown(np.asarray(u), "ft*lbf", units)
    h, hu = shown(np.asarray(h), "ft*lbf*s", units)
    # 12 panels without an Axes each, the axis names over the top row, the quantity left of each
    # row, the time under the bottom row (pre-rendered: bake_texts), one line series for all panels
    fig = stage_pyplot().figure(figsize=(13, 10))
    labels = ["attitude error θ−θ̂* (deg)", "body rate rel. LVLH (deg/s)",
              f"control torque ({pretty(uu)})", f"CMG momentum ({pretty(hu)})"]
    # a fixed layout: tight_layout plus bbox 'tight' draw the 12 panels three times
    grid = PanelGrid(fig, 4, 3, [{"lw": 0.7, "color": "C0"}],
                     {"left": 0.07, "right": 0.98, "bottom": 0.06, "top": 0.93, "wspace": 0.25, "hspace": 0.12},
                     title_size=mpl.rcParams["axes.titlesize"], tick_size=8)
    for r, label in enumerate(labels):
        for a in range(3):
            grid.set_label(3 * r + a, label, "left", fontsize=8 if a == 0 else 7)
    for a in range(3):
        grid.set_title(a, AXES[a])
        grid.set_label(9 + a, "time (orbits)", "below", offset=0.12)
    bake_texts(fig, [*grid.titles, *grid.labels])
    xlim = data_limits(orbits) or (0.0, 1.0)
    xticks = in_view_ticks(*xlim, 5)
    for r, data in enumerate((err_deg, rate, u, h)):
        for a in range(3):
            grid.show(3 * r + a, xlim, [(0, *decimate(orbits, data[:, a]))], xticks)
    grid.draw_data(compact_formatter().format_ticks)
    fig.suptitle(title)
    return write_figure(fig, path, vector, tight=False, rc=FAST_TEXT_RC)


_INERTIA_ELEMENTS = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]


def inertia_histories(orbits, inertia, path, vector=False, units="imperial"):
    """The six inertia elements vs orbit (Figs 6.14–6.19), in the unit system ``units``.

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    inertia : (N, 3, 3) array
        Inertia in force, slug·ft².
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    inertia, iu = shown(np.asarray(inertia), "slug*ft^2", units)
    # six panels with titles and labels (pre-rendered), one step-line series for all panels
    fig = stage_pyplot().figure(figsize=(12, 6))
    grid = PanelGrid(fig, 2, 3, [{"drawstyle": "steps-post", "color": "C0"}],
                     {"left": 0.07, "right": 0.98, "bottom": 0.09, "top": 0.9, "wspace": 0.3, "hspace": 0.25},
                     title_size=mpl.rcParams["axes.titlesize"], tick_size=8)
    for k, (i, j) in enumerate(_INERTIA_ELEMENTS):
        grid.set_title(k, f"I({i + 1},{j + 1})")
        grid.set_label(k, f"inertia I{i + 1}{j + 1} (10⁶ {pretty(iu)})", "left")
    for k in range(3, 6):
        grid.set_label(k, "time (orbits)", "below", offset=0.12)
    title = fig.suptitle("Inertia variation MB3 → AC (cf. Figs 6.14–6.19)")
    bake_texts(fig, [title, *grid.titles, *grid.labels])
    xlim = data_limits(orbits) or (0.0, 1.0)
    xticks = in_view_ticks(*xlim, 5)
    for k, (i, j) in enumerate(_INERTIA_ELEMENTS):
        grid.show(k, xlim, [(0, orbits, inertia[:, i, j] / 1e6)], xticks)
    grid.draw_data(compact_formatter().format_ticks)
    return write_figure(fig, path, vector, tight=False, rc=FAST_TEXT_RC)


#: the per-level table of the summary: column headers (the last takes the momentum unit)
_TABLE_HEADER = ("level", "start (orbit)", "θ2* est (deg)", "steady |err| max (deg) r/p/y", "peak |h| ({})")


def summary(orbits, err_deg, h, u, level_stats, verdict, title, path, vector=False, units="imperial"):
    """One-page summary: errors, momentum, torque and per-level statistics (``units``: imperial | SI).

    Parameters
    ----------
    orbits : (N,) array
        Time, orbits.
    err_deg : (N, 3) array
        Attitude error, deg.
    h : (N, 3) array
        CMG momentum, ft·lbf·s.
    u : (N, 3) array
        Delivered torque, ft·lbf.
    level_stats : list of dict
        Per-level statistics (:func:`acmm.simulate.scenario.level_statistics`).
    verdict : str
        The run's verdict.
    title : str
        Figure title.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : str, optional
        Unit system of the figure, ``"imperial"`` or ``"SI"``.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    h, hu = shown(np.asarray(h), "ft*lbf*s", units)
    u, uu = shown(np.asarray(u), "ft*lbf", units)
    k_h = shown(1.0, "ft*lbf*s", units)[0]
    # the three panels with their (empty) lines, one legend, the table's header and empty columns;
    # titles, labels, legend and header pre-rendered (bake_texts).  The table's height follows its rows
    # (at most 12 lines of full height): a one-level run leaves no blank third of the page
    table_ratio = min(1.0, 0.25 + 0.0625 * max(1, min(len(level_stats), 12)))
    k = 1.0 / table_ratio           # the header's and rules' offsets from the top stay the same in points
    fig = stage_pyplot().figure(figsize=(11, 8.5 * (2 + table_ratio) / 3))
    gs = fig.add_gridspec(3, 2, height_ratios=(1.0, 1.0, table_ratio))
    top = fig.add_subplot(gs[0, :])
    top.set_ylabel("attitude error (deg)")
    mid = [fig.add_subplot(gs[1, col]) for col in range(2)]
    for ax, label in zip(mid, (f"CMG momentum ({pretty(hu)})", f"delivered torque ({pretty(uu)})")):
        ax.set_ylabel(label)
    lines = []
    for ax in (top, *mid):
        # few y ticks written short, at most six x ticks
        ax.yaxis.set_major_locator(_in_view_locator(3))
        ax.yaxis.set_major_formatter(compact_formatter())
        ax.tick_params(labelsize=8)
        ax.xaxis.set_major_locator(_in_view_locator(5))
        ax.set_xlabel("time (orbits)")
        # the labels at fixed axes coordinates: the automatic placement measures every tick label again
        ax.xaxis.set_label_coords(0.5, -0.1 if ax is top else -0.12)
        ax.yaxis.set_label_coords(-0.06 if ax is top else -0.12, 0.5)
        # empty lines, their data set later (~40 % cheaper than ax.plot's argument handling)
        lines.append([ax.add_line(Line2D([], [], lw=0.7, color=f"C{a}", label=AXES[a])) for a in range(3)])
    # one legend for the three panels, above them: no 'best' placement search over the data
    fig.legend(handles=lines[0], loc="upper right", bbox_to_anchor=(0.98, 0.995), ncol=3, fontsize=8,
               frameon=False)
    table = fig.add_subplot(gs[2, :])
    table.axis("off")
    head = [table.text((c + 0.5) / 5, 1.0, text.format(pretty(hu)), ha="center", va="top", fontsize=8,
                       transform=table.transAxes) for c, text in enumerate(_TABLE_HEADER)]
    rules = [table.plot([0, 1], [y, y], transform=table.transAxes, color="k", lw=lw, clip_on=False)[0]
             for y, lw in ((1 + 0.02 * k, 0.9), (1 - 0.07 * k, 0.6))]
    body = [table.text((c + 0.5) / 5, 1 - 0.09 * k, "", ha="center", va="top", fontsize=8, linespacing=1.45,
                       transform=table.transAxes) for c in range(5)]
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.02, top=0.95, wspace=0.25, hspace=0.35)
    premake_ticks([top, *mid], 6, 4)
    bake_texts(fig, [*head, *rules, *fig.legends,
                      *(t for ax in (top, *mid) for t in (ax.xaxis.label, ax.yaxis.label))])
    xlim = data_limits(orbits)
    for ax, panel, data in zip((top, *mid), lines, (err_deg, h, u)):
        for a in range(3):
            panel[a].set_data(*decimate(orbits, data[:, a]))
        for lim, set_lim in ((xlim, ax.set_xlim), (data_limits(data), ax.set_ylim)):
            if lim is not None:     # no finite value: the limits stay
                set_lim(lim)
    top.set_title(f"{title} — verdict: {verdict}")
    rows = [(str(s["level"]), f"{s['start_orbit']:.1f}", f"{s['theta2_deg']:.2f}",
             " / ".join(f"{v:.3f}" for v in s["steady_error_deg"]), f"{s['peak_momentum'] * k_h:.0f}")
            for s in level_stats]
    if rows:     # the columns, each one text; the font shrinks to fit many levels (down to 6 pt)
        px = body[0].axes.bbox.height * (body[0].get_position()[1] - 0.01)
        fit = max(2, int(px / (6.0 * fig.dpi / 72 * 1.45)))
        if len(rows) > fit:
            rows = rows[:fit - 1] + [("…", f"{len(rows) - fit + 1} more levels", "in sim.h5", "", "")]
        size = min(8.0, px / len(rows) / 1.45 * 72 / fig.dpi)
        for text, column in zip(body, zip(*rows)):
            text.set_text("\n".join(column))
            text.set_fontsize(size)
    return write_figure(fig, path, vector, tight=False, rc=FAST_TEXT_RC)
