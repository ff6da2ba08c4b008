"""Figures of the design stage: the LQR gains of the design points with the gain schedule of
ch. 5.3 (cf. Figs 5.3–5.26), the closed-loop poles with the sector of ch. 5.2 (Fig 5.2), and the
scheduled gain checked along the path.  Each function takes arrays, draws one figure and saves it
as PNG (and PDF when asked) under the given path.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acmm.plots.base import (FAST_TEXT_RC, bake_texts, compact_formatter, data_limits,
    premake_ticks, write_figure, in_view_ticks, state_units, stage_pyplot)
from acmm.plots.panel_grid import PanelGrid
from matplotlib.ticker import MaxNLocator


@dataclass
class SampledSchedule:
    """A gain schedule sampled for drawing: ``gains[k]`` (3, 24) at pitch TEA ``theta2[k]`` (rad).

    What :func:`gain_schedule_grid` draws of a schedule; plain arrays, so a figure writer
    process needs neither the schedule's class nor its imports.

    Attributes
    ----------
    form : str
        The schedule's form (:attr:`acmm.design.schedule.ScheduleFit.form`), named in the figure title.
    theta2 : (n,) array
        Pitch TEAs of the samples, rad.
    gains : (n, 3, 24) array
        Scheduled gain at each sample, torque per state unit (the units of the fitted gains).
    """

    form: str
    theta2: np.ndarray
    gains: np.ndarray


def gain_schedule_grid(theta2, gains, fit, state_names, path, vector=False, units=None,
                       torque_unit="ft·lbf"):
    """K(i, j) versus pitch TEA for all 24 columns (3 rows each), with the fitted curves.

    Parameters
    ----------
    theta2 : (P,) array
        Pitch TEA of the design points, rad.
    gains : (P, 3, 24) array
        LQR gains, ``torque_unit`` per state unit.
    fit : acmm.design.schedule.ScheduleFit or SampledSchedule
        The schedule (drawn at 60 pitch TEAs spanning ``theta2``), or its samples (same units as
        ``gains``).
    state_names : list of str
        The 24 state names.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.
    units : list of str, optional
        The 24 state unit labels (default :func:`state_units`).
    torque_unit : str, optional
        Torque unit label of the gains.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    theta2_deg = np.degrees(theta2)
    if isinstance(fit, SampledSchedule):
        curve = fit
    else:
        fine = np.linspace(theta2.min(), theta2.max(), 60)
        curve = SampledSchedule(fit.form, fine, np.array([fit.gain(t) for t in fine]))
    fine, kf = np.degrees(curve.theta2), curve.gains
    units = units or state_units()
    # 24 panels without an Axes each (24 Axes with their axis and tick artists took ~0.65 s to build
    # and draw; issue 16), a fixed layout (tight_layout/bbox 'tight' on 24 panels costs seconds), the
    # legend at a fixed place and the fixed texts pre-rendered (bake_texts); six series: the LQR gains
    # as dots and the schedule as a line, per gain row
    fig = stage_pyplot().figure(figsize=(13, 15), dpi=80)
    colors = ("C0", "C1", "C2")
    series = ([{"marker": "o", "ls": "none", "ms": 3, "color": c,
                "label": f"K({i + 1},·): point gain (dots), schedule (line)"} for i, c in enumerate(colors)]
              + [{"lw": 1, "color": c} for c in colors])
    grid = PanelGrid(fig, 6, 4, series, {"left": 0.06, "right": 0.98, "bottom": 0.04, "top": 0.95,
                                         "wspace": 0.38, "hspace": 0.3})
    for j in range(24):
        unit = units[j]         # the gain's unit: torque per unit of state j (ft·lbf/rad, ft·lbf/(ft·lbf·s))
        gain_unit = f"{torque_unit}/({unit})" if any(ch in unit for ch in "/·") else f"{torque_unit}/{unit}"
        grid.set_title(j, f"K(i,{j + 1}) — {state_names[j]} ({gain_unit})")
    for j in range(20, 24):
        grid.set_label(j, "pitch TEA θ2* (deg)", "below")
    fig.legend(handles=grid.lines[:3], loc="upper center", bbox_to_anchor=(0.5, 0.978),
               ncol=3, fontsize=7, frameon=False)
    bake_texts(fig, [*grid.titles, *grid.labels, *fig.legends])
    xlim = data_limits(theta2_deg, fine) or (0.0, 1.0)
    xticks = in_view_ticks(*xlim, 4)
    for j in range(24):
        grid.show(j, xlim, [(i, theta2_deg, gains[:, i, j]) for i in range(3)]
                  + [(3 + i, fine, kf[:, i, j]) for i in range(3)], xticks)
    grid.draw_data(compact_formatter().format_ticks)
    fig.suptitle(f"Gain schedule: the design points' gains (dots) and the {curve.form} schedule (lines) vs TEA "
                 "(cf. Figs 5.3–5.26)", y=0.995)
    return write_figure(fig, path, vector, tight=False, rc=FAST_TEXT_RC)


def pole_map(poles_per_point, names, n, sigma, half_angle_deg, path, vector=False):
    """Closed-loop poles (units of n) of every design point with the sector drawn.

    Parameters
    ----------
    poles_per_point : list of (24,) complex array
        Closed-loop poles per design point, rad/s.
    names : list of str
        Design point names.
    n : float
        Orbit rate, rad/s.
    sigma : float
        Sector shift σ, units of n (Re λ ≤ −σ n).
    half_angle_deg : float
        Sector half-angle, deg.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    plt = stage_pyplot()
    fig, (ax, zoom) = plt.subplots(1, 2, figsize=(11, 5.2), gridspec_kw={"width_ratios": [1.0, 1.0]})
    allp = np.concatenate([np.asarray(p) for p in poles_per_point]) / n
    rmin = min(allp.real.min() * 1.1, -2 * sigma)
    t = np.tan(np.radians(half_angle_deg))
    # the zoomed panel: the sector's edge and the poles near it (within 4σ, or the slowest
    # third of the poles when they lie further in)
    edge = max(4 * sigma, float(np.quantile(-allp.real, 1 / 3)) * 1.3)
    cmap = plt.get_cmap("viridis")
    for a in (ax, zoom):
        x = np.linspace(rmin, -sigma, 10)
        a.fill_between(x, t * x, -t * x, color="0.9", label="sector" if a is ax else None)
        a.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.8)
        a.plot(x, t * x, "k-", lw=0.8)
        a.plot(x, -t * x, "k-", lw=0.8)
        for k, (p, name) in enumerate(zip(poles_per_point, names)):
            p = np.asarray(p) / n
            # a point of the blend of eq 5.3 (blend_0.017) is named by its parameter
            label = name.replace("blend_", "blend parameter s = ", 1) if name.startswith("blend_") else name
            a.plot(p.real, p.imag, "x", ms=4, color=cmap(k / max(1, len(names) - 1)),
                   label=label if len(names) <= 12 and a is ax else None)
        a.axvline(0, color="k", lw=0.5)
        a.set_xlabel("real part Re λ (units of n, the orbit rate)")
        a.set_ylabel("imaginary part Im λ (units of n)")
    near = allp[allp.real >= -edge]
    ylim = max(t * edge, float(np.abs(near.imag).max()) * 1.1 if near.size else 0.0) * 1.05
    zoom.set_xlim(-edge, 0.25 * edge)
    zoom.set_ylim(-ylim, ylim)
    zoom.set_title(f"zoom: the sector edge (Re λ ≥ −{edge:.3g}n)", fontsize=9)
    ax.indicate_inset_zoom(zoom, edgecolor="C3")
    ax.set_title("all poles", fontsize=9)
    fig.suptitle(f"Closed-loop poles and the sector (Re λ ≤ −{sigma}n, |Im λ| ≤ tan {half_angle_deg:g}°·|Re λ|)")
    # outside the data: to the right of the panels
    if len(names) <= 12:
        fig.legend(*ax.get_legend_handles_labels(), fontsize=7, loc="center right", frameon=False)
    fig.subplots_adjust(left=0.07, right=0.8, bottom=0.1, top=0.88, wspace=0.25)
    return write_figure(fig, path, vector, tight=False, rc=FAST_TEXT_RC)


def schedule_path_check(theta2, max_real, margin, disk_margin, path, vector=False):
    """The scheduled gain on the local model along the path: largest Re λ and worst sector
    margin (units of n) and the plant-input disk margin α versus pitch TEA.

    Parameters
    ----------
    theta2 : (M,) array
        Pitch TEA along the path, rad.
    max_real : (M,) array
        Largest Re λ of the scheduled local loop, units of n.
    margin : (M,) array
        Worst sector margin, units of n.
    disk_margin : (M,) array
        Disk margin α at the plant input, dimensionless.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    th = np.degrees(theta2)
    fig, (a1, a2) = stage_pyplot().subplots(2, 1, figsize=(7.5, 6), sharex=True)
    a1.set_ylabel("units of n")
    # a linear axis (a log axis over less than a decade showed two tick labels): α is between
    # 0 and 2 for a skew-0 disk margin
    a2.set_ylabel("disk margin α at u, skew 0 (1)")
    a2.set_xlabel("pitch TEA θ2* (deg)")
    # a fixed layout: bbox 'tight' draws the figure twice
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.09, top=0.94, hspace=0.1)
    premake_ticks([a1, a2], 10, 11)
    a1.plot(th, max_real, "-", color="C3", label="largest Re λ / n")
    a1.plot(th, margin, "-", color="C0", label="worst sector margin / n")
    a1.axhline(0.0, color="k", lw=0.8)
    a1.axhline(-0.25, color="C3", lw=0.8, ls="--", label="Re λ = −0.25n")
    a1.legend(fontsize=7)
    a1.set_title(f"Scheduled gain on the local model at {th.size} TEAs")
    a2.plot(th, disk_margin, "-", color="C2", label="disk margin α")
    fin = np.asarray(disk_margin, float)[np.isfinite(disk_margin)]
    if fin.size:
        lo, hi = float(fin.min()), float(fin.max())
        pad = max(0.05 * (hi - lo), 0.02 * max(abs(hi), 1e-3))
        a2.set_ylim(max(0.0, lo - pad), hi + pad)
    a2.yaxis.set_major_locator(MaxNLocator(6))
    return write_figure(fig, path, vector, tight=False)


def scheduled_pole_map(poles, theta2, n, sigma, half_angle_deg, path, vector=False):
    """Closed-loop poles (units of n) of the scheduled loop at every path TEA, coloured by θ2*,
    with the sector of Fig 5.2.

    Parameters
    ----------
    poles : (M, 24) complex array
        Closed-loop poles at each path TEA, rad/s.
    theta2 : (M,) array
        Pitch TEA along the path, rad.
    n : float
        Orbit rate, rad/s.
    sigma : float
        Sector shift σ, units of n.
    half_angle_deg : float
        Sector half-angle, deg.
    path : path-like
        Figure path (suffix replaced).
    vector : bool, optional
        Also write a PDF.

    Returns
    -------
    list of pathlib.Path
        The files written (``.png``, and ``.pdf`` with ``vector``).
    """
    p = np.asarray(poles) / n
    fig, ax = stage_pyplot().subplots(figsize=(6.5, 5.5))
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.1, top=0.93)    # fixed: no bbox 'tight' pass
    ax.set_xlabel("Re λ / n")
    ax.set_ylabel("Im λ / n")
    ax.set_title("Scheduled-loop poles along the path (sector of Fig 5.2 shaded)")
    # an empty scatter above the sector's fill (1), below its boundary lines (2), and the colour bar
    # before the data (its axes and ticks were the costliest part of drawing them after the data)
    sc = ax.scatter(np.empty(0), np.empty(0), c=np.empty(0), s=3, cmap="viridis", zorder=1.5)
    cbar = fig.colorbar(sc, ax=ax, label="pitch TEA θ2* (deg)")
    premake_ticks([ax], 10, 10)
    cbar.ax.yaxis.get_major_ticks(10)
    t = np.tan(np.radians(half_angle_deg))
    fin = p[np.isfinite(p)]                  # limits from the finite poles (a failed eig: NaN)
    fin = fin if fin.size else np.zeros(1, complex)
    lo = max(min(fin.real.min() * 1.05, -2 * sigma), -60.0)
    x = np.linspace(lo, -sigma, 10)
    ax.fill_between(x, t * x, -t * x, color="0.9", label="sector")
    ax.plot(x, t * x, "k-", lw=0.8)
    ax.plot(x, -t * x, "k-", lw=0.8)
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.8)
    c = np.repeat(np.degrees(theta2), p.shape[1])
    sc.set_offsets(np.column_stack([p.real.ravel(), p.imag.ravel()]))
    sc.set_array(c)
    sc.autoscale()                       # the colour limits of the finite TEAs, as scatter(c=...) sets them
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_xlim(lo, max(1.0, fin.real.max() * 1.1))
    ylim = min(max(3.0, np.abs(fin.imag).max() * 1.05), 60.0)
    ax.set_ylim(-ylim, ylim)
    ax.legend(fontsize=7, loc="upper left")
    return write_figure(fig, path, vector, tight=False)

