"""The figures fixed in issue 34, drawn from small data: labels present, no empty axes, the pole
map's zoomed panel of the sector edge, the blend parameter named in its legend, readable
disk-margin ticks, no blank third under a one-level summary, legends off the data, the qpp
figures' titles and legend entries that match what is drawn, the sweep map's ticks."""
from __future__ import annotations

import types
from pathlib import Path

import numpy as np
import pytest


@pytest.fixture
def figs(monkeypatch):
    """The figures the plot functions draw (rendered, not written)."""
    from acmm.plots import base, design, simulation
    import qpp.plots as qplots

    out = []

    def keep(fig, path, *a, **k):
        fig.canvas.draw()
        out.append(fig)
        return [Path(path)]

    for mod in (base, design, simulation):
        monkeypatch.setattr(mod, "write_figure", keep)
    monkeypatch.setattr(qplots, "save_figure", keep)
    plt = qplots._plt()
    monkeypatch.setattr(plt, "close", lambda fig=None: None)
    yield out
    monkeypatch.undo()
    for fig in out:
        plt.close(fig)


def _has_artists(ax) -> bool:
    return bool(ax.lines or ax.collections or ax.patches or ax.images or ax.texts or ax.tables)


def _no_empty_axes(fig):
    for ax in fig.axes:
        if ax.axison:
            assert _has_artists(ax), f"empty axes {ax.get_title()!r}"


def _legend_off_the_data(fig, ax, legend):
    """No data point of ``ax`` lies under ``legend`` (display coordinates)."""
    r = fig.canvas.get_renderer()
    box = legend.get_window_extent(r)
    for line in ax.lines:
        xy = ax.transData.transform(np.column_stack(line.get_data()).astype(float))
        inside = (xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1)
        assert not inside.any(), f"legend over the data of {line.get_label()!r}"


def test_pole_map_has_a_zoom_of_the_sector_edge_and_names_the_blend_parameter(figs, tmp_path):
    from acmm.plots.design import pole_map

    n = 1.1e-3
    poles = [np.array([-17.5, -1.2 + 0.8j, -1.2 - 0.8j, -0.9]) * n,
             np.array([-3.4, -1.1 + 1.2j, -1.1 - 1.2j, -0.7]) * n]
    pole_map(poles, ["staircase", "blend_0.017"], n, 0.5, 45.0, tmp_path / "p.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    main, zoom = [ax for ax in fig.axes if ax.axison]
    assert "zoom" in zoom.get_title()
    assert zoom.get_xlim()[0] > -17.5 / 2 and zoom.get_xlim()[1] > -0.5       # the edge, not the far pole
    labels = [t.get_text() for lg in fig.legends for t in lg.get_texts()]
    assert "blend parameter s = 0.017" in labels and not any(x.startswith("blend_") for x in labels)
    for ax in (main, zoom):
        assert ax.get_xlabel() and ax.get_ylabel()
    # the legend beside the panels, over no data
    r = fig.canvas.get_renderer()
    box = fig.legends[0].get_window_extent(r)
    assert all(box.x0 >= ax.get_window_extent(r).x1 for ax in (main, zoom))


def test_disk_margin_axis_is_linear_with_readable_ticks(figs, tmp_path):
    from acmm.plots.design import schedule_path_check

    th = np.radians(np.linspace(-44.7, -5.0, 51))
    schedule_path_check(th, -0.6 + 0.1 * np.sin(th), 0.1 + 0.05 * np.cos(th), 0.62 + 0.2 * (th - th[0]),
                        tmp_path / "m.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    disk = fig.axes[1]
    assert disk.get_yscale() == "linear"
    lo, hi = disk.get_ylim()
    shown = [t for t, v in zip(disk.get_yticklabels(), disk.get_yticks()) if lo <= v <= hi and t.get_text()]
    assert len(shown) >= 3


def test_a_one_level_summary_leaves_no_blank_third(figs, tmp_path):
    from acmm.plots.simulation import summary

    t = np.linspace(0, 1, 97)
    data = np.column_stack([np.sin(t), np.cos(t), t])
    stats = [{"level": 0, "start_orbit": 0.0, "theta2_deg": -44.7, "steady_error_deg": np.array([1.0, 2.0, 3.0]),
              "peak_momentum": 2700.0}]
    summary(t, data, data * 1000, data, stats, "bounded", "mb3", tmp_path / "s.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    table = [ax for ax in fig.axes if not ax.axison][0]
    plots = [ax for ax in fig.axes if ax.axison]
    # the table's panel is a small part of the page: no third left blank under one row
    assert table.get_position().height < 0.2 * plots[0].get_position().height * 3
    assert fig.get_figheight() < 8.5


def _sim(name="sin10", p=1, m=1):
    t = np.linspace(0, 2, 201)
    y = np.vstack([np.sin(5 * t + k) for k in range(p)])
    return types.SimpleNamespace(name=name, t=t, r=y, r_o=y, y=y * 1.01, y_o=y, u=np.vstack([np.cos(t)] * m),
                                 error_per_output=np.full(p, 0.05), error_inf=0.05, beta_o=0.2, passed=True,
                                 parameters=None, gamma=10.0)


def test_qpp_response_legends_are_beside_the_panels(figs, tmp_path):
    from qpp.plots import plot_scenario

    plot_scenario(_sim(), tmp_path / "q.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    for ax in fig.axes:
        assert ax.get_ylabel()
        legend = ax.get_legend()
        assert legend is not None
        _legend_off_the_data(fig, ax, legend)
    assert fig.get_layout_engine() is not None          # constrained: no gap under the title


def test_qpp_iterations_legend_names_only_what_is_drawn(figs, tmp_path):
    from qpp.plots import plot_iterations

    its = [{"beta1": 0.08, "m": 0.1, "circle": True, "certified": False},
           {"beta1": 0.05, "m": 0.1, "circle": True, "certified": True}]
    res = types.SimpleNamespace(iterations=its, certified=True, beta1_ref=0.05, m_ref=0.1)
    plot_iterations(res, tmp_path / "i.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    ax = fig.axes[0]
    for handle, text in zip(ax.get_legend().legend_handles, ax.get_legend().get_texts()):
        drawn = [ln for ln in ax.lines if ln.get_label() == text.get_text()]
        assert drawn and len(drawn[0].get_xdata()) > 0, text.get_text()
    assert "circle criterion fails" not in [t.get_text() for t in ax.get_legend().get_texts()]
    assert ax.get_xlim()[0] < 1 and ax.get_xlim()[1] > 2        # two evaluations, not at the edges


def test_cartesian_plot_has_a_title(figs, tmp_path):
    from qpp.plots import plot_cartesian

    plot_cartesian([_sim("m45", p=2, m=2), _sim("m55", p=2, m=2)], 1.5, tmp_path / "c.png")
    fig = figs[-1]
    _no_empty_axes(fig)
    assert fig.axes[0].get_title() and fig.axes[0].get_xlabel() and fig.axes[0].get_ylabel()
