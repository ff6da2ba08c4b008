"""The figure machinery of acmm (acmm.plots.base): decimation keeps the envelope, the baked texts
of a figure skeleton are text in a PDF."""
from __future__ import annotations

import numpy as np

from acmm.plots import base as plot_base
from acmm.model.linearize import STATE_NAMES


def test_decimate_keeps_the_envelope():
    x = np.linspace(0, 1, 100_001)
    y = np.sin(200 * x) + (x > 0.5) * 3
    xd, yd = plot_base.decimate(x, y, 2000)
    assert len(xd) <= 2000 and np.all(np.diff(xd) > 0)
    assert yd.max() == y.max() and yd.min() == y.min()
    short = np.arange(10.0)
    assert plot_base.decimate(short, short)[0] is short or np.array_equal(plot_base.decimate(short, short)[0], short)


def test_baked_texts_are_text_in_a_pdf(captured, tmp_path):
    import io

    from acmm.plots import base as plot_base
    from acmm.plots import design as design_plots

    theta2 = np.radians(np.linspace(-45, -5, 5))
    gains = np.cos(np.arange(5 * 3 * 24)).reshape(5, 3, 24)
    design_plots.gain_schedule_grid(theta2, gains, design_plots.SampledSchedule("polynomial", theta2, gains),
                                    STATE_NAMES, tmp_path / "g.png")
    fig = captured[0]
    title = fig.panel_grid.titles[0]
    drawn, draw = [], title.draw
    title.draw = lambda renderer: (title.get_visible() and drawn.append(type(renderer).__name__), draw(renderer))
    fig.savefig(io.BytesIO(), format="png")
    assert drawn == [] and not title.get_visible()          # the PNG blends the baked tile
    fig.savefig(io.BytesIO(), format="pdf")
    assert drawn == ["MixedModeRenderer"] and not title.get_visible()   # the PDF draws the text
    plot_base.stage_pyplot().close(fig)
