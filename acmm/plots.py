"""Matplotlib figures for the design and simulation stages (report Figs 5.3–5.26, 6.2–6.30).

Each function takes arrays, draws one figure and saves it as PNG (and PDF when asked) under the
given path; nothing is shown on screen.  The sector LQR and schedule of ch. 5.2–5.3, the
stair-case simulation of ch. 6.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.plot_style import stage_pyplot as _plt  # noqa: F401 (acmm.sweep uses plots._plt)
from common.results import save_figure

AXES = ("roll", "pitch", "yaw")


def _save(fig, path: Path, vector: bool = False, tight: bool = True) -> list[Path]:
    path = Path(path)
    out = [path.with_suffix(".png")]
    from acmm import parallel_figures

    if parallel_figures.active():
        if vector:
            out.append(path.with_suffix(".pdf"))
        parallel_figures.run(lambda: _save_now(fig, path, [out[0]], vector, tight), str(out[0]))
        from common.outputs import record_written

        for p in out:               # written by the child: recorded here, or the stage prunes them
            record_written(p)
        import matplotlib.pyplot as plt

        plt.close(fig)
        return out
    _save_now(fig, path, out, vector, tight)
    import matplotlib.pyplot as plt         # no fig.clf(): clearing 12 axes cost ~0.15 s, close frees it

    plt.close(fig)
    return out


#: PNG deflate level: 3 encodes ~1.5x faster than PIL's default 6 for ~8 % larger files (issue 16)
PNG_COMPRESS_LEVEL = 3


def _save_now(fig, path: Path, out: list, vector: bool, tight: bool) -> None:
    bbox = "tight" if tight else None
    save_figure(fig, out[0], bbox_inches=bbox, pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    if vector:
        out.append(path.with_suffix(".pdf"))
        save_figure(fig, out[1], bbox_inches=bbox)


#: figure skeletons built ahead (:func:`prebuild`): (kind, parameters) → (figure, axes)
_LAYOUTS: dict = {}


def prebuild(kind: str, *params) -> None:
    """Build the skeleton of a figure ``kind`` (axes, labels, titles, tick locators and tick
    artists: everything that does not depend on the data) for the figure function called later
    with the same parameters.

    The figure worker (:mod:`acmm.figure_worker`) calls this while the stage still computes, so
    the figure function then only draws the data; without it the skeleton is built on the spot.
    The result is identical either way.

    Parameters
    ----------
    kind : str
        The figure: ``"axis_histories"``, ``"inertia_histories"``, ``"summary"`` or
        ``"gain_schedule_grid"``.
    *params : str or tuple
        The parameters of its skeleton, as the figure function passes them (the unit system
        ``"imperial"``/``"SI"``; for the gain grid the state names, state unit labels and torque
        unit label).
    """
    _LAYOUTS[(kind, params)] = _BUILDERS[kind](*params)


def _layout(kind: str, *params):
    got = _LAYOUTS.pop((kind, params), None)
    return got if got is not None else _BUILDERS[kind](*params)


def _premake_ticks(axes, nx: int = 9, ny: int = 8) -> None:
    """Create the tick artists now (the costly part of an axis): at draw time the axis reuses
    the first ones it needs and makes more only if the locator asks for more."""
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
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        seg = y[a:b]
        if not np.isfinite(seg).any():
            idx.append(a)
            continue
        i, j = a + int(np.nanargmin(seg)), a + int(np.nanargmax(seg))
        idx.extend(sorted({i, j}))
    idx = np.asarray(idx)
    return x[idx], y[idx]


def state_units(drf_mode: str = "attitude_hold") -> list[str]:
    """:func:`acmm.linearize.state_units` written for labels (ft·lbf·s², rad·s).

    Parameters
    ----------
    drf_mode : str, optional
        DRF mode of the 24 states.

    Returns
    -------
    list of str
        The 24 unit labels.
    """
    import re

    from acmm.linearize import state_units as units

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


def _few_ticks(ax, nx: int = 4, ny: int = 4) -> None:
    """At most ~``nx``/``ny`` major ticks: every tick is four artists to create and draw."""
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(nx))
    ax.yaxis.set_major_locator(MaxNLocator(ny))


def gain_unit(state_unit: str, torque_unit: str = "ft·lbf") -> str:
    """Unit of a gain column K(i, j): torque (``torque_unit``) per unit of state j.

    Parameters
    ----------
    state_unit : str
        Unit of state j.
    torque_unit : str, optional
        Torque unit.

    Returns
    -------
    str
        The label, e.g. ``ft·lbf/rad``.
    """
    return f"{torque_unit}/({state_unit})" if any(ch in state_unit for ch in "/·") else f"{torque_unit}/{state_unit}"


def _gain_grid_layout(state_names: tuple, units: tuple, torque_unit: str):
    plt = _plt()
    fig, axs = plt.subplots(6, 4, figsize=(13, 15), sharex=True, dpi=80)
    for j, ax in enumerate(axs.flat):
        ax.set_title(f"K(i,{j + 1}) — {state_names[j]}", fontsize=8)
        ax.set_ylabel(f"K(i,{j + 1}) ({gain_unit(units[j], torque_unit)})", fontsize=6)
        ax.tick_params(labelsize=7)
        _few_ticks(ax)
    for ax in axs[-1]:
        ax.set_xlabel("pitch TEA θ2* (deg)")
    # a fixed layout: tight_layout/bbox 'tight' on 24 panels costs seconds
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.04, top=0.95, wspace=0.45, hspace=0.35)
    _premake_ticks(axs.flat, 7, 7)
    return fig, axs


@dataclass
class SampledSchedule:
    """A gain schedule sampled for drawing: ``gains[k]`` (3, 24) at pitch TEA ``theta2[k]`` (rad).

    What :func:`gain_schedule_grid` draws of a schedule; plain arrays, so a figure writer
    process needs neither the schedule's class nor its imports.

    Attributes
    ----------
    form : str
        The schedule's form (:attr:`acmm.schedule.ScheduleFit.form`), named in the figure title.
    theta2 : (n,) array
        Pitch TEAs of the samples, rad.
    gains : (n, 3, 24) array
        Scheduled gain at each sample, torque per state unit (the units of the fitted gains).
    """

    form: str
    theta2: np.ndarray
    gains: np.ndarray


def sample_schedule(fit, theta2, n: int = 60) -> SampledSchedule:
    """``fit`` (an :class:`acmm.schedule.ScheduleFit`) at ``n`` pitch TEAs spanning ``theta2`` (rad).

    Parameters
    ----------
    fit : acmm.schedule.ScheduleFit
        The gain schedule of ch. 5.3.
    theta2 : (P,) array
        Pitch TEAs of the design points, rad (their range is sampled).
    n : int, optional
        Number of evenly spaced samples.

    Returns
    -------
    SampledSchedule
        The schedule's gains at the samples (the units of ``fit``'s gains).
    """
    fine = np.linspace(theta2.min(), theta2.max(), n)
    return SampledSchedule(fit.form, fine, np.array([fit.gain(t) for t in fine]))


def gain_schedule_grid(theta2, gains, fit, state_names, path, vector=False, units=None,
                       torque_unit="ft·lbf"):
    """K(i, j) versus pitch TEA for all 24 columns (3 rows each), with the fitted curves.

    Parameters
    ----------
    theta2 : (P,) array
        Pitch TEA of the design points, rad.
    gains : (P, 3, 24) array
        LQR gains, ``torque_unit`` per state unit.
    fit : acmm.schedule.ScheduleFit or SampledSchedule
        The schedule, or its samples from :func:`sample_schedule` (same units as ``gains``).
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
    curve = fit if isinstance(fit, SampledSchedule) else sample_schedule(fit, theta2)
    fine, kf = curve.theta2, curve.gains
    units = units or state_units()
    fig, axs = _layout("gain_schedule_grid", tuple(state_names), tuple(units), torque_unit)
    for j, ax in enumerate(axs.flat):
        for i, color in zip(range(3), ("C0", "C1", "C2")):
            ax.plot(theta2_deg, gains[:, i, j], "o", ms=3, color=color, label=f"K({i + 1},·) LQR")
            ax.plot(np.degrees(fine), kf[:, i, j], "-", lw=1, color=color)
    axs[0, 0].legend(fontsize=6)
    fig.suptitle(f"Gain schedule: LQR gains (dots) and the {curve.form} schedule (lines) vs TEA "
                 "(cf. Figs 5.3–5.26)")
    return _save(fig, path, vector, tight=False)


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
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    allp = np.concatenate([np.asarray(p) for p in poles_per_point]) / n
    rmin = min(allp.real.min() * 1.1, -2 * sigma)
    x = np.linspace(rmin, -sigma, 10)
    t = np.tan(np.radians(half_angle_deg))
    ax.fill_between(x, t * x, -t * x, color="0.9", label="sector")
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.8)
    ax.plot(x, t * x, "k-", lw=0.8)
    ax.plot(x, -t * x, "k-", lw=0.8)
    cmap = plt.get_cmap("viridis")
    for k, (p, name) in enumerate(zip(poles_per_point, names)):
        p = np.asarray(p) / n
        ax.plot(p.real, p.imag, "x", ms=4, color=cmap(k / max(1, len(names) - 1)),
                label=name if len(names) <= 12 else None)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("real part Re λ (units of n, the orbit rate)")
    ax.set_ylabel("imaginary part Im λ (units of n)")
    ax.set_title(f"Closed-loop poles and the sector (Re λ ≤ −{sigma}n, |Im λ| ≤ tan {half_angle_deg:g}°·|Re λ|)")
    ax.legend(fontsize=6, ncol=2)
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.1, top=0.92)
    return _save(fig, path, vector, tight=False)


def _axis_histories_layout(units: str):
    from common.units import pretty, shown

    plt = _plt()
    fig, axs = plt.subplots(4, 3, figsize=(13, 10), sharex=True)
    uu, hu = shown(1.0, "ft*lbf", units)[1], shown(1.0, "ft*lbf*s", units)[1]
    labels = ["attitude error θ−θ̂* (deg)", "body rate rel. LVLH (deg/s)",
              f"control torque ({pretty(uu)})", f"CMG momentum ({pretty(hu)})"]
    for r, label in enumerate(labels):
        for a in range(3):
            ax = axs[r, a]
            _few_ticks(ax, 6, 4)
            if r == 0:
                ax.set_title(AXES[a])
            ax.set_ylabel(label, fontsize=8 if a == 0 else 7)
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    # a fixed layout: tight_layout plus bbox 'tight' draw the 12 panels three times
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.06, top=0.93, wspace=0.25, hspace=0.12)
    _premake_ticks(axs.flat)
    return fig, axs


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
    from common.units import shown

    fig, axs = _layout("axis_histories", units)
    u = shown(np.asarray(u), "ft*lbf", units)[0]
    h = shown(np.asarray(h), "ft*lbf*s", units)[0]
    for r, data in enumerate((err_deg, rate, u, h)):
        for a in range(3):
            axs[r, a].plot(*decimate(orbits, data[:, a]), lw=0.7)
    fig.suptitle(title)
    return _save(fig, path, vector, tight=False)


def _inertia_layout(units: str):
    from common.units import pretty, shown

    iu = shown(1.0, "slug*ft^2", units)[1]
    plt = _plt()
    fig, axs = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    for ax, (i, j) in zip(axs.flat, _INERTIA_ELEMENTS):
        ax.set_title(f"I({i + 1},{j + 1})")
        ax.set_ylabel(f"inertia I{i + 1}{j + 1} (10⁶ {pretty(iu)})")
    for ax in axs[-1]:
        ax.set_xlabel("time (orbits)")
    fig.suptitle("Inertia variation MB3 → AC (cf. Figs 6.14–6.19)")
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.09, top=0.9, wspace=0.3, hspace=0.25)
    _premake_ticks(axs.flat)
    return fig, axs


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
    from common.units import shown

    inertia = shown(np.asarray(inertia), "slug*ft^2", units)[0]
    fig, axs = _layout("inertia_histories", units)
    for ax, (i, j) in zip(axs.flat, _INERTIA_ELEMENTS):
        ax.step(orbits, inertia[:, i, j] / 1e6, where="post")
    return _save(fig, path, vector, tight=False)


def _summary_layout(units: str):
    from common.units import pretty, shown

    hu, uu = shown(1.0, "ft*lbf*s", units)[1], shown(1.0, "ft*lbf", units)[1]
    plt = _plt()
    fig = plt.figure(figsize=(11, 8.5))
    gs = fig.add_gridspec(3, 2)
    top = fig.add_subplot(gs[0, :])
    top.set_ylabel("attitude error (deg)")
    top.set_xlabel("time (orbits)")
    mid = []
    for col, label in enumerate((f"CMG momentum ({pretty(hu)})", f"delivered torque ({pretty(uu)})")):
        ax = fig.add_subplot(gs[1, col])
        ax.set_ylabel(label)
        ax.set_xlabel("time (orbits)")
        mid.append(ax)
    table = fig.add_subplot(gs[2, :])
    table.axis("off")
    _premake_ticks([top, *mid])
    return fig, (top, mid, table)


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
        Per-level statistics (:func:`acmm.scenario.level_statistics`).
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
    from common.units import pretty, shown

    h, hu = shown(np.asarray(h), "ft*lbf*s", units)
    u = shown(np.asarray(u), "ft*lbf", units)[0]
    k_h = shown(1.0, "ft*lbf*s", units)[0]
    fig, (ax, mid, tab_ax) = _layout("summary", units)
    for a in range(3):
        ax.plot(*decimate(orbits, err_deg[:, a]), lw=0.7, label=AXES[a])
    ax.legend(fontsize=7)
    ax.set_title(f"{title} — verdict: {verdict}")
    for ax, data in zip(mid, (h, u)):
        for a in range(3):
            ax.plot(*decimate(orbits, data[:, a]), lw=0.7, label=AXES[a])
        ax.legend(fontsize=7)
    if level_stats:
        header = ["level", "start (orbit)", "θ2* est (deg)", "steady |err| max (deg) r/p/y", f"peak |h| ({pretty(hu)})"]
        rows = [[str(s["level"]), f"{s['start_orbit']:.1f}", f"{s['theta2_deg']:.2f}",
                 " / ".join(f"{v:.3f}" for v in s["steady_error_deg"]), f"{s['peak_momentum'] * k_h:.0f}"]
                for s in level_stats]
        tab = tab_ax.table(cellText=rows, colLabels=header, loc="center", cellLoc="center")
        tab.auto_set_font_size(False)
        tab.set_fontsize(7)
    # after the table: its cells are sized on the axes as placed by the default parameters
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.02, top=0.95, wspace=0.25, hspace=0.35)
    return _save(fig, path, vector, tight=False)


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
    plt = _plt()
    th = np.degrees(theta2)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    a1.plot(th, max_real, "-", color="C3", label="largest Re λ / n")
    a1.plot(th, margin, "-", color="C0", label="worst sector margin / n")
    a1.axhline(0.0, color="k", lw=0.8)
    a1.axhline(-0.25, color="C3", lw=0.8, ls="--", label="Re λ = −0.25n")
    a1.set_ylabel("units of n")
    a1.legend(fontsize=7)
    a1.set_title(f"Scheduled gain on the local model at {th.size} TEAs")
    a2.semilogy(th, np.maximum(disk_margin, 1e-6), "-", color="C2")
    a2.set_ylabel("disk margin α at u (skew 0)")
    a2.set_xlabel("pitch TEA θ2* (deg)")
    # a fixed layout: bbox 'tight' draws the figure twice
    fig.subplots_adjust(left=0.12, right=0.97, bottom=0.09, top=0.94, hspace=0.1)
    return _save(fig, path, vector, tight=False)


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
    plt = _plt()
    p = np.asarray(poles) / n
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.1, top=0.93)    # fixed: no bbox 'tight' pass
    t = np.tan(np.radians(half_angle_deg))
    lo = max(min(p.real.min() * 1.05, -2 * sigma), -60.0)
    x = np.linspace(lo, -sigma, 10)
    ax.fill_between(x, t * x, -t * x, color="0.9", label="sector")
    ax.plot(x, t * x, "k-", lw=0.8)
    ax.plot(x, -t * x, "k-", lw=0.8)
    ax.plot([-sigma, -sigma], [-t * sigma, t * sigma], "k-", lw=0.8)
    c = np.repeat(np.degrees(theta2), p.shape[1])
    sc = ax.scatter(p.real.ravel(), p.imag.ravel(), c=c, s=3, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="pitch TEA θ2* (deg)")
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set_xlim(lo, max(1.0, p.real.max() * 1.1))
    ylim = min(max(3.0, np.abs(p.imag).max() * 1.05), 60.0)
    ax.set_ylim(-ylim, ylim)
    ax.set_xlabel("Re λ / n")
    ax.set_ylabel("Im λ / n")
    ax.set_title("Scheduled-loop poles along the path (sector of Fig 5.2 shaded)")
    ax.legend(fontsize=7, loc="upper left")
    return _save(fig, path, vector, tight=False)


_BUILDERS = {"axis_histories": _axis_histories_layout, "inertia_histories": _inertia_layout,
             "summary": _summary_layout, "gain_schedule_grid": _gain_grid_layout}
