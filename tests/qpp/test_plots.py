"""The qpp figures (qpp.plots): a scenario of many outputs keeps a short legend."""
import numpy as np


def test_scenario_figure_of_many_outputs_keeps_a_short_legend(monkeypatch, tmp_path):
    """Twelve outputs: the legend names the line styles and the output with the largest error
    (not 48 + 12 + 12 entries), and the title the scenario's parameters by name."""
    from qpp import plots
    from qpp.simulate.closed_loop import SimResult

    figs = []
    monkeypatch.setattr(plots, "save_figure", lambda fig, path, **kw: figs.append(fig))
    p, N = 12, 50
    t = np.linspace(0, 1, N)
    y = np.outer(np.arange(1, p + 1), t) * 0.01
    y_o = np.zeros((p, N))
    err = np.abs(y - y_o).max(axis=1)
    sim = SimResult("a", t, y, y, y, y_o, y, y, y, y, 0.9, float(err.max()), err, 0.3, {"c": 0.9})
    plots.plot_scenario(sim, tmp_path / "s.png")
    (fig,) = figs
    texts = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes]
    assert len(texts[0]) == 4 and all("all outputs" in s for s in texts[0])
    assert texts[1] == ["other outputs", "|y12 − y_o12| (largest)", "β_o = 0.3"]
    assert texts[2] == ["u1 … u12"]
    assert fig._suptitle.get_text() == "scenario a (c = 0.9)"
