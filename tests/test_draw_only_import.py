"""The figure worker imports matplotlib without the property tables of its docstrings (issue 16):
``acmm_qpp.plot_style.import_pyplot_to_draw_only``.  Each check runs in a fresh interpreter, as the
stage commands do (the test process has matplotlib imported already)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(code: str, tmp_path: Path, **env) -> list[str]:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=tmp_path, capture_output=True, check=False,
                         text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT), **env})
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


def test_the_draw_only_import_skips_the_property_tables_and_restores_kwdoc(tmp_path):
    got = _run("""
        import inspect
        from acmm_qpp.plot_style import import_pyplot_to_draw_only
        first = import_pyplot_to_draw_only()
        import matplotlib, matplotlib.artist as a, matplotlib.lines as l, matplotlib.pyplot as plt
        print(first, import_pyplot_to_draw_only(), matplotlib.get_backend().lower())
        print(a.kwdoc.__module__ == "matplotlib.artist" and a.kwdoc.__name__ == "kwdoc")
        print("not listed in this figure process" in l.Line2D.set.__doc__)
        print("linewidth" in inspect.signature(l.Line2D.set).parameters)
        print("linewidth" in a.kwdoc(l.Line2D))          # the restored kwdoc lists them again
        fig, ax = plt.subplots()
        ax.plot([0, 1], [1, 0]).pop().set(linewidth=3, color="r")
        print(ax.lines[0].get_linewidth())
    """, tmp_path)
    assert got == ["True", "False", "agg", "True", "True", "True", "True", "3.0"]


def test_kwdoc_is_restored_when_the_import_fails(tmp_path):
    got = _run("""
        import sys

        class Refuse:                                   # matplotlib.legend cannot be imported
            def find_spec(self, name, path=None, target=None):
                if name == "matplotlib.legend":
                    raise ImportError("refused")

        sys.meta_path.insert(0, Refuse())
        from acmm_qpp.plot_style import import_pyplot_to_draw_only
        try:
            import_pyplot_to_draw_only()
        except ImportError as exc:
            print("raised", exc)
        import matplotlib.artist as a
        print(a.kwdoc.__module__ == "matplotlib.artist" and a.kwdoc.__name__ == "kwdoc")
    """, tmp_path)
    assert got == ["raised", "refused", "True"]


def test_an_imported_matplotlib_is_left_alone(tmp_path):
    got = _run("""
        import matplotlib.lines as l
        from acmm_qpp.plot_style import import_pyplot_to_draw_only
        print(import_pyplot_to_draw_only(), "linewidth" in l.Line2D.set.__doc__,
              "not listed" in l.Line2D.set.__doc__)
    """, tmp_path)
    assert got == ["False", "True", "False"]


def test_the_figure_worker_draws_the_same_pixels_with_it(tmp_path):
    """A stage's figure drawn by the figure worker (which imports matplotlib this way) is the
    figure drawn in place after a plain import, byte for byte; and the worker did use it."""
    code = """
        import sys
        import numpy as np
        from pathlib import Path
        from acmm_qpp import figure_worker

        def docs(path):
            import matplotlib.lines as l
            Path(path).write_text(str("not listed in this figure process" in l.Line2D.set.__doc__))
            return path

        if __name__ == "__main__":
            from acmm.plots import design as design_plots
            poles = [np.array([-1 + 1j, -1 - 1j, -2.0, -3 + 0.5j, -3 - 0.5j]) * 1e-3] * 2
            with figure_worker.session():
                print(figure_worker.active())
                figure_worker.submit(design_plots.pole_map, poles, ["a", "b"], 1e-3, 0.5, 45.0, Path(sys.argv[1]))
                figure_worker.submit(docs, sys.argv[1] + ".txt")
    """
    if sys.platform == "win32" or (os.cpu_count() or 1) < 2:
        pytest.skip("the figure worker needs fork and two CPUs")
    script = tmp_path / "draw.py"
    script.write_text(textwrap.dedent(code))
    for name, env in (("worker", {"ACMM_FIGURE_WORKER": "1", "ACMM_FORK": "1"}),
                      ("in_place", {"ACMM_FIGURE_WORKER": "0"})):
        out = subprocess.run([sys.executable, str(script), str(tmp_path / f"{name}.png")], cwd=tmp_path,
                             capture_output=True, check=False, text=True, timeout=120,
                             env={**os.environ, "PYTHONPATH": str(ROOT), **env})
        assert out.returncode == 0, out.stderr
        assert out.stdout.split() == [str(name == "worker")]
        assert (tmp_path / f"{name}.png.txt").read_text() == str(name == "worker")
    assert (tmp_path / "worker.png").read_bytes() == (tmp_path / "in_place.png").read_bytes()
