"""Every acmm figure kind renders and every axis names a quantity and a unit (issues 14, 16)."""
from __future__ import annotations

import re

import numpy as np
import pytest

from acmm.plots import base as plot_base
from acmm.plots import design as design_plots
from acmm.plots import simulation as sim_plots
from acmm_qpp import plot_style as plot_style_mod
from acmm.io.config import load_config
from acmm.model.linearize import STATE_NAMES

UNIT = re.compile(r"^(?P<quantity>.{3,}?)\s*\((?P<unit>[^()]*(\([^()]*\))?[^()]*)\)\s*$")


@pytest.fixture
def captured(monkeypatch):
    figs = []

    def fake_save(fig, path, vector=False, tight=True, rc=None):
        import matplotlib

        with matplotlib.rc_context(rc or {}):
            fig.canvas.draw()                  # renders: a figure that cannot draw fails here
        figs.append(fig)
        return [path]

    monkeypatch.setattr(plot_base, "_save", fake_save)         # acmm.sweep.output imports it from there
    monkeypatch.setattr(design_plots, "_save", fake_save)      # the figures live in these two
    monkeypatch.setattr(sim_plots, "_save", fake_save)
    return figs


def _same_column(fig, ax):
    x0 = ax.get_position().x0
    return [a for a in fig.axes if a.axison and abs(a.get_position().x0 - x0) < 1e-6]


def _check_panel_labels(grid):
    """A panel grid (acmm.plots.panel_grid): each panel's y label (or its title when it has none)
    names the quantity and its unit, each column has an x label with its unit."""
    for p in grid.panels:
        ylab = p.ylabel or p.title
        m = UNIT.match(ylab)
        assert m and m["unit"].strip(), f"panel y label (or title) without quantity and unit: {ylab!r}"
    for c in range(grid.cols):
        labels = [p.xlabel for p in grid.panels[c::grid.cols] if p.xlabel]
        assert labels, f"no x label in column {c}"
        for lab in labels:
            m = UNIT.match(lab)
            assert m and m["unit"].strip(), f"x label without quantity and unit: {lab!r}"


def _check_labels(fig):
    if hasattr(fig, "panel_grid"):
        _check_panel_labels(fig.panel_grid)
        return
    axes = [ax for ax in fig.axes if ax.axison]
    assert axes
    for ax in axes:
        # the y quantity and unit: the y label, or the panel title when there is no y label
        ylab = ax.get_ylabel() or ax.get_title()
        m = UNIT.match(ylab)
        assert m and m["unit"].strip(), f"y label (or title) without quantity and unit: {ylab!r}"
        siblings = set(ax.get_shared_x_axes().get_siblings(ax)) | set(_same_column(fig, ax))
        labelled = [a.get_xlabel() for a in siblings if a.get_xlabel()]
        assert labelled, f"no x label on the column of {ax.get_title()!r}"
        for lab in labelled:
            m = UNIT.match(lab)
            assert m and m["unit"].strip(), f"x label without quantity and unit: {lab!r}"
        for lab in (ax.get_xlabel(), ax.get_ylabel()):
            assert "[1]" not in lab


def test_design_and_simulation_figures_have_quantities_and_units(captured, tmp_path):
    from acmm.simulate import kernel as sm
    from acmm.simulate import scenario as scen
    from acmm.stages.design import compute_design

    cfg = load_config("staircase")
    r = compute_design(cfg)
    design_plots.gain_schedule_grid(r.table.tea[:, 1], r.table.gain, r.fit, STATE_NAMES, tmp_path / "g.png",
                             units=plot_base.state_units(cfg.design.drf_mode))
    design_plots.pole_map([p.lqr.poles for p in r.points], r.table.names, cfg.orbit_rate, 0.5, 45, tmp_path / "p.png")
    sc = scen.scenario_from_config(cfg, r.table, orbits=12)
    res = sm.simulate(sc)
    orbits = res.t * cfg.orbit_rate / (2 * np.pi)
    err = np.degrees(scen.attitude_error(sc, res))
    sim_plots.axis_histories(orbits, err, err, res.u, res.state[:, 6:9], "t", tmp_path / "a.png")
    sim_plots.inertia_histories(orbits, sc.inertia[res.level], tmp_path / "i.png")
    sim_plots.summary(orbits, err, res.state[:, 6:9], res.u, scen.level_statistics(sc, res), res.verdict, "x",
                  tmp_path / "s.png")
    assert len(captured) == 5
    for fig in captured:
        _check_labels(fig)
    # the gain panels carry the gain's unit: torque per unit of the state
    grid = captured[0].panel_grid
    assert "ft·lbf/(rad/s)" in grid.panels[0].title and "ft·lbf/rad)" in grid.panels[3].title
    _check_gain_grid(captured[0], r)
    _check_sim_figures(captured[2:], orbits, err, scen.level_statistics(sc, res))


def _check_sim_figures(figs, orbits, err, stats):
    """Every state drawn over the whole run, one legend, one table row per level."""
    axes_fig, inertia_fig, summary_fig = figs
    grid = axes_fig.panel_grid
    assert len(grid.panels) == 12 and [p.title for p in grid.panels[:3]] == ["roll", "pitch", "yaw"]
    for p in grid.panels:
        ((x, y),) = p.data.values()
        assert x[0] == orbits[0] and x[-1] == orbits[-1]
        lo, hi = p.ylim
        assert lo <= np.nanmin(y) and np.nanmax(y) <= hi
    np.testing.assert_array_equal(grid.panels[1].data[0][1], err[:, 1])                # pitch error
    _check_drawn(grid)
    inertia = inertia_fig.panel_grid
    assert len(inertia.panels) == 6 and all(len(p.data) == 1 for p in inertia.panels)
    _check_drawn(inertia)
    top, *mid, table = summary_fig.axes
    assert [len(ax.lines) for ax in (top, *mid)] == [3, 3, 3]
    (legend,) = summary_fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["roll", "pitch", "yaw"]
    assert "verdict" in top.get_title()
    columns = [t.get_text().split("\n") for t in table.texts if t.get_position()[1] < 0.95]   # below the header
    assert len(columns) == 5 and all(len(c) == len(stats) for c in columns)
    assert columns[0] == [str(s["level"]) for s in stats]


def _check_drawn(grid):
    """What a panel grid draws: each series of each panel mapped onto the panel's box, inside
    it, NaN-separated per panel, in panel order; a y tick label per y tick."""
    for s, line in enumerate(grid.lines):
        fx, fy = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        cut = np.flatnonzero(np.isnan(fx))
        drawn = [p for p in grid.panels if s in p.data]
        assert len(cut) == len(drawn)
        for p, a, b in zip(drawn, np.r_[0, cut[:-1] + 1], cut):
            x0, y0, w, h = p.box                 # the data's limits mapped onto the panel's box
            (xlo, xhi), (ylo, yhi) = p.xlim, p.ylim
            x, y = p.data[s]
            ex, ey = x0 + (x - xlo) / (xhi - xlo) * w, y0 + (y - ylo) / (yhi - ylo) * h
            np.testing.assert_allclose(fx[a:b], ex)
            np.testing.assert_allclose(fy[a:b], ey)
            ok = np.isfinite(ey)
            assert x0 <= ex.min() and ex.max() <= x0 + w
            assert not ok.any() or (y0 <= ey[ok].min() and ey[ok].max() <= y0 + h)
    labels = {t.get_text() for t in grid.tick_labels}
    assert all(len(p.yticks) >= 3 for p in grid.panels) and len(labels) >= 3
    for p in grid.panels:                  # every tick (mark, grid line, label) inside its panel
        assert all(p.ylim[0] <= v <= p.ylim[1] for v in p.yticks)
        assert all(p.xlim[0] <= v <= p.xlim[1] for v in p.xticks)
    x0s = [p.box[0] for p in grid.panels]
    for t in grid.tick_labels:
        x, y = t.get_position()
        assert any(p.box[1] - 0.05 <= y <= p.box[1] + p.box[3] + 1e-9 for p in grid.panels)
        assert min(x0s) - 0.06 <= x


def _check_gain_grid(fig, r):
    """Every design point and the schedule's curve, per gain row, in each of the 24 panels, and
    the artists draw exactly that, inside the panel's frame."""
    grid = fig.panel_grid
    theta2_deg = np.degrees(r.table.tea[:, 1])
    assert len(grid.panels) == 24 and len(grid.lines) == 6
    n_labels = 0
    for j, p in enumerate(grid.panels):
        assert p.title.startswith(f"K(i,{j + 1}) — {STATE_NAMES[j]} (")
        lo, hi = p.ylim
        for i in range(3):
            x, y = p.data[i]                                  # the LQR gains: dots
            assert np.array_equal(x, theta2_deg) and np.array_equal(y, r.table.gain[:, i, j])
            assert lo <= y.min() and y.max() <= hi
            xc, yc = p.data[3 + i]                            # the schedule: a line
            assert len(xc) >= 50 and p.xlim[0] <= xc.min() and xc.max() <= p.xlim[1]
            assert lo <= yc.min() and yc.max() <= hi
        # tick labels on the y axis of every panel, on the x axis of the bottom row
        assert len(p.yticks) >= 3 and all(lo <= v <= hi for v in p.yticks)
        assert j < 20 or len(p.xticks) >= 3
        n_labels += len(p.yticks) + (len(p.xticks) if j >= 20 else 0)
    assert len(grid.tick_labels) == n_labels
    _check_drawn(grid)
    # the dots at the design points' TEAs: the extreme TEAs sit at 1/22 and 21/22 of the first
    # panel's width (5 % margins each side of the TEA range)
    fx = np.asarray(grid.lines[0].get_xdata(), float)
    x0, _, w, _ = grid.panels[0].box
    first = (fx[:np.flatnonzero(np.isnan(fx))[0]] - x0) / w
    np.testing.assert_allclose([first.min(), first.max()], [1 / 22, 21 / 22], atol=1e-9)
    assert [p.xlabel for p in grid.panels[20:]] == ["pitch TEA θ2* (deg)"] * 4
    (legend,) = fig.legends
    assert [t.get_text()[:6] for t in legend.get_texts()] == ["K(1,·)", "K(2,·)", "K(3,·)"]


def test_sweep_figures_have_quantities_and_units(captured, tmp_path):
    import yaml

    from acmm.sweep.run import run_sweep

    from tests.conftest import CONFIGS

    p = tmp_path / "s.yaml"
    p.write_text(yaml.safe_dump({"name": "figs", "sweep": {
        "base": str(CONFIGS / "ac.yaml"), "grid": {"dI22": [-0.1, 0.1], "bias_pitch": [0.0, 0.2]},
        "orbits": 0.5}, "output": {"root": str(tmp_path / "runs"), "figures": True}}))
    run_sweep(p, workers=1)
    assert len(captured) == 2
    for fig in captured:
        _check_labels(fig)
    assert "relative change of I22" in captured[0].axes[0].get_xlabel()


def test_decimate_keeps_the_envelope():
    x = np.linspace(0, 1, 100_001)
    y = np.sin(200 * x) + (x > 0.5) * 3
    xd, yd = plot_base.decimate(x, y, 2000)
    assert len(xd) <= 2000 and np.all(np.diff(xd) > 0)
    assert yd.max() == y.max() and yd.min() == y.min()
    short = np.arange(10.0)
    assert plot_base.decimate(short, short)[0] is short or np.array_equal(plot_base.decimate(short, short)[0], short)


def _small_histories(n=300):
    t = np.linspace(0.0, 3.0, n)
    x = np.column_stack([np.sin(5 * t), np.cos(3 * t), t]) * 2.0
    return t, x


def _killed_mid_write(path):
    """A figure writer killed (SIGKILL) after it opened its temporary file."""
    import os
    import signal
    from pathlib import Path

    path = Path(path)
    (path.parent / f".{path.name}.x1y2z3.tmp").write_bytes(b"half a PNG")
    os.kill(os.getpid(), signal.SIGKILL)


def test_draw_figures_draws_every_figure_and_raises_the_first_failure(tmp_path):
    """A stage's figures are drawn in order in this process after its results; all of them even
    if one fails, and that first failure is raised then, as a FigureError (exit 4)."""
    from functools import partial

    from acmm_qpp.errors import FigureError
    from acmm_qpp.results import draw_figures

    t, x = _small_histories()
    (tmp_path / "file").write_text("")
    calls = [partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "file" / "bad.png"),
             partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "after.png"),
             lambda: (_ for _ in ()).throw(ValueError("Axis limits cannot be NaN or Inf"))]
    with pytest.raises(FigureError, match="bad.png") as got:
        draw_figures(calls)
    assert got.value.exit_code == 4
    assert (tmp_path / "after.png").stat().st_size > 10_000 and not (tmp_path / "file" / "bad.png").exists()
    with pytest.raises(FigureError, match="Axis limits"):
        draw_figures(calls[2:])
    draw_figures([])


def _interrupting_figure():
    raise KeyboardInterrupt


def test_ctrl_c_while_a_figure_is_drawn_is_an_interrupt_not_a_figure_error(tmp_path):
    from acmm_qpp.results import draw_figures

    t, x = _small_histories()
    from functools import partial

    with pytest.raises(KeyboardInterrupt):
        draw_figures([_interrupting_figure, partial(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "a.png")])
    assert not (tmp_path / "a.png").exists()


def test_design_figures_of_a_finished_design(tmp_path):
    # the four figures of a finished design, drawn by the stage after design.h5
    from acmm.io.config import load_config
    from acmm.stages.design_output import design_figures
    from acmm_qpp.results import draw_figures
    from acmm.design.settings import design_settings
    from acmm.stages.design import compute_design

    cfg = load_config("staircase")
    r = compute_design(cfg)
    draw_figures(design_figures(r, design_settings(cfg), tmp_path, "imperial"))
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["design_gains.png", "design_path_margins.png", "design_path_poles.png", "design_poles.png"]
    assert all((tmp_path / n).stat().st_size > 10_000 for n in names)


def test_baked_texts_draw_as_the_live_texts(tmp_path, monkeypatch):
    """The skeleton's pre-rendered titles, labels and legend (plot_base._bake_texts) give the PNG
    the live texts give, to anti-aliasing rounding; a PDF gets them as text."""
    from PIL import Image

    names, units = list(STATE_NAMES), plot_base.state_units()
    theta2 = np.radians(np.linspace(-45, -5, 12))
    gains = np.sin(np.arange(12 * 3 * 24).reshape(12, 3, 24)) * np.logspace(-8, 6, 24)
    sched = design_plots.SampledSchedule("polynomial", np.linspace(theta2[0], theta2[-1], 60),
                                         np.cos(np.arange(60 * 3 * 24).reshape(60, 3, 24)))
    baked = design_plots.gain_schedule_grid(theta2, gains, sched, names, tmp_path / "b.png", units=units, vector=True)
    assert [p.name for p in baked] == ["b.png", "b.pdf"]
    monkeypatch.setattr(design_plots, "_bake_texts", lambda fig, texts: None)
    design_plots.gain_schedule_grid(theta2, gains, sched, names, tmp_path / "l.png", units=units)
    a, b = (np.asarray(Image.open(tmp_path / n), dtype=int) for n in ("b.png", "l.png"))
    assert a.shape == b.shape and np.abs(a - b).max() <= 2
    # the baked text is there: the title band is not blank
    assert (a[:40, :, :3] < 100).any()


def test_baked_texts_are_text_in_a_pdf():
    import io

    from acmm.plots import base as plot_base
    from acmm_qpp import plot_style as plot_style_mod

    fig, grid = plot_base._BUILDERS["gain_schedule_grid"](tuple(STATE_NAMES), tuple(plot_base.state_units()),
                                                          "ft·lbf")
    title = grid.titles[0]
    drawn, draw = [], title.draw
    title.draw = lambda renderer: (title.get_visible() and drawn.append(type(renderer).__name__), draw(renderer))
    fig.savefig(io.BytesIO(), format="png")
    assert drawn == [] and not title.get_visible()          # the PNG blends the baked tile
    fig.savefig(io.BytesIO(), format="pdf")
    assert drawn == ["MixedModeRenderer"] and not title.get_visible()   # the PDF draws the text
    plot_style_mod.stage_pyplot().close(fig)


def test_log_axis_labels_are_plain_text_of_the_tick_values():
    """The path check's log axis labels its ticks as matplotlib does, in plain text (no mathtext
    parser in the figure writers): each label read back is the tick's value."""
    from matplotlib.ticker import LogFormatterSciNotation

    sup = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")

    def value(label):
        coeff, _, power = label.replace("\N{MINUS SIGN}", "-").rpartition("10")
        if not power:                                     # a plain number (min_exponent)
            return float(label)
        return float(coeff.rstrip("×") or 1) * 10.0 ** int(power.translate(sup))

    fig, (_, a2) = plot_style_mod.stage_pyplot().subplots(2, 1)
    a2.set_yscale("log")
    a2.set_ylim(0.3, 3.0)                                 # one decade: minor ticks labelled too
    fig.canvas.draw()
    ticks = [v for v in a2.get_yticks(minor=True) if 0.3 <= v <= 3.0]
    for labelled_only_base in (True, False):
        plain = design_plots._plain_log_formatter(base=10, labelOnlyBase=labelled_only_base)
        mathtext = LogFormatterSciNotation(base=10, labelOnlyBase=labelled_only_base)
        for f in (plain, mathtext):
            f.set_axis(a2.yaxis)
            f.set_locs(ticks)
        for v in [*ticks, 1e-12, 1e-3, 0.01, 10.0, 2e3]:
            want, got = mathtext(v), plain(v)
            assert (want == "") == (got == "") and "$" not in got
            if got:
                assert value(got) == pytest.approx(v, rel=1e-12), (v, got)
    assert design_plots._plain_math(r"$\mathdefault{6\times10^{-1}}$") == "6×10⁻¹"
    plot_style_mod.stage_pyplot().close(fig)


def test_history_panels_of_a_diverged_run(captured, tmp_path):
    """NaN and ±inf states (a run that diverged) draw as gaps: a panel with no finite value has
    the limits 0 to 1 and draws nothing; the others' limits cover their finite values."""
    t = np.linspace(0.0, 3.0, 300)
    x = np.column_stack([np.sin(t), np.full(300, np.nan), t])
    x[100:, 2] = np.inf
    sim_plots.axis_histories(t, x, x, x, x, "t", tmp_path / "a.png")
    grid = captured[0].panel_grid
    _check_labels(captured[0])
    _check_drawn(grid)
    for r in range(4):
        roll, pitch, yaw = grid.panels[3 * r:3 * r + 3]
        assert pitch.ylim == (0.0, 1.0) and np.isnan(pitch.data[0][1]).all()
        lo, hi = yaw.ylim
        assert lo <= 0.0 and t[99] <= hi < 1.2 * t[99]          # the finite part only
        assert roll.ylim[0] <= np.sin(t).min() and np.sin(t).max() <= roll.ylim[1]
    fy = np.asarray(grid.lines[0].get_ydata(), float)
    assert np.isinf(fy).sum() == 4 * 200                       # the inf samples: gaps, not clipped


@pytest.mark.parametrize("offset, spread", [(1e6, 1e-4), (0.0, 1e-295), (5e-324, 0.0), (-3.0, 0.0)])
def test_history_panels_of_nearly_constant_series(captured, tmp_path, offset, spread):
    """A series whose spread is lost beside its size, values below ~1e-287 and constants: the
    ticks stay inside the panel (as an Axes keeps them), three of them at least."""
    t = np.linspace(0.0, 3.0, 300)
    x = offset + spread * np.column_stack([np.sin(t), np.cos(t), t])
    sim_plots.axis_histories(t, x, x, x, x, "t", tmp_path / "a.png")
    grid = captured[0].panel_grid
    _check_drawn(grid)
    for p in grid.panels:
        assert p.ylim[0] < p.ylim[1] and len(p.yticks) >= 3


def test_scheduled_pole_map_colours_ignore_a_nan_tea(captured, tmp_path):
    theta2 = np.radians(np.linspace(-45.0, -5.0, 41))
    theta2[7] = np.nan
    poles = (-1.0 - np.arange(24.0) + 1j * np.sin(np.arange(24.0)))[None, :] * (1 + theta2[:, None] ** 2)
    design_plots.scheduled_pole_map(poles * 1e-3, theta2, 1e-3, 0.5, 45.0, tmp_path / "p.png")
    (sc,) = [c for c in captured[0].axes[0].collections if c.get_array() is not None]
    np.testing.assert_allclose(sc.get_clim(), [-45.0, -5.0])
    assert len(sc.get_offsets()) == 41 * 24


def test_a_vector_figure_drawn_twice_is_the_same_file(tmp_path):
    """No creation date in the PDFs (the report's path-check figures differed between runs)."""
    import time

    th = np.linspace(-20.0, -5.0, 9)
    args = (th, -0.1 + 0.01 * np.sin(th), 0.2 + 0.01 * th, 0.5 + 0.0 * th)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    first = design_plots.schedule_path_check(*args, tmp_path / "a" / "f", vector=True)
    time.sleep(1.1)                         # a PDF date has a resolution of one second
    second = design_plots.schedule_path_check(*args, tmp_path / "b" / "f", vector=True)
    pdfs = [p for p in (*first, *second) if p.suffix == ".pdf"]
    assert len(pdfs) == 2 and b"CreationDate" not in pdfs[0].read_bytes()
    assert pdfs[0].read_bytes() == pdfs[1].read_bytes()
