"""What every stage figure shares (report Figs 5.3–5.26, 6.2–6.30): saving a figure (PNG/PDF, in a
forked writer when :mod:`acmm.parallel_figures` is active), figure skeletons built ahead
(:func:`prebuild`), tick and line thinning, and the unit labels of the 24 states of eq 4.46.

Split from :mod:`acmm.plots` (issue 12), which re-exports these names; the figures themselves
are in :mod:`acmm.design_plots` and :mod:`acmm.sim_plots`.
"""
from __future__ import annotations

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
    import matplotlib.pyplot as plt  # no fig.clf(): clearing 12 axes cost ~0.15 s, close frees it

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

#: figure kind → skeleton builder; filled by :mod:`acmm.design_plots` and :mod:`acmm.sim_plots`
_BUILDERS: dict = {}


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


