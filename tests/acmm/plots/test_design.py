"""The design figures (acmm.plots.design): baked texts draw as the live ones, pole-map colours,
byte-identical vector files."""
from __future__ import annotations

import numpy as np

from acmm.plots import base as plot_base
from acmm.plots import design as design_plots
from acmm.model.linearize import STATE_NAMES


def test_baked_texts_draw_as_the_live_texts(tmp_path, monkeypatch):
    """The skeleton's pre-rendered titles, labels and legend (plot_base.bake_texts) give the PNG
    the live texts give, to anti-aliasing rounding; a PDF gets them as text."""
    from PIL import Image

    names, units = list(STATE_NAMES), plot_base.state_units()
    theta2 = np.radians(np.linspace(-45, -5, 12))
    gains = np.sin(np.arange(12 * 3 * 24).reshape(12, 3, 24)) * np.logspace(-8, 6, 24)
    sched = design_plots.SampledSchedule("polynomial", np.linspace(theta2[0], theta2[-1], 60),
                                         np.cos(np.arange(60 * 3 * 24).reshape(60, 3, 24)))
    baked = design_plots.gain_schedule_grid(theta2, gains, sched, names, tmp_path / "b.png", units=units, vector=True)
    assert [p.name for p in baked] == ["b.png", "b.pdf"]
    monkeypatch.setattr(design_plots, "bake_texts", lambda fig, texts: None)
    design_plots.gain_schedule_grid(theta2, gains, sched, names, tmp_path / "l.png", units=units)
    a, b = (np.asarray(Image.open(tmp_path / n), dtype=int) for n in ("b.png", "l.png"))
    assert a.shape == b.shape and np.abs(a - b).max() <= 2
    # the baked text is there: the title band is not blank
    assert (a[:40, :, :3] < 100).any()


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
