"""The simulation figures (acmm.plots.simulation) — with the design figures of the same run, every
acmm figure kind renders and every axis names a quantity and a unit (issues 14, 16); the panel
grids draw exactly their data, a diverged or nearly constant history included."""
from __future__ import annotations

import numpy as np
import pytest

from acmm.plots import base as plot_base
from acmm.plots import design as design_plots
from acmm.plots import simulation as sim_plots
from acmm.io.config import load_config
from acmm.model.linearize import STATE_NAMES

from tests.acmm.conftest import _check_labels

from tests.conftest import LQR_ROUTE


def test_design_and_simulation_figures_have_quantities_and_units(captured, tmp_path):
    from acmm.simulate import kernel as sm
    from acmm.simulate import scenario as scen
    from acmm.stages.design import compute_design

    cfg = load_config("staircase", [*LQR_ROUTE])
    r = compute_design(cfg)
    design_plots.gain_schedule_grid(r.table.tea[:, 1], r.table.gain, r.fit, STATE_NAMES, tmp_path / "g.png",
                             units=plot_base.state_units(cfg.design.drf_mode))
    design_plots.pole_map([p.gain.poles for p in r.points], r.table.names, cfg.orbit_rate, 0.5, 45, tmp_path / "p.png")
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
