"""The matplotlib style of the commands (acmm_qpp.plot_style): any MPLBACKEND still writes the
figures, and without a writable home one private folder per user is used."""
from __future__ import annotations

import pytest

from tests.conftest import REPO


@pytest.mark.parametrize("backend", ["nonexistent", "module://matplotlib_inline.backend_inline", "TkAgg"])
def test_any_mplbackend_still_writes_the_figures(tmp_path, backend):
    """The commands draw into files only: an invalid or interactive MPLBACKEND (Jupyter's) made
    ``import matplotlib`` fail, a traceback in the sweep and the report (a review)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": backend,
           "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-m", "acmm.cli.app", "sweep", "sweep_smoke", "sweep.n_runs=2",
                           "sweep.orbits=0.5"], cwd=tmp_path, capture_output=True, text=True, env=env,
                          timeout=300, check=False)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
    assert list((tmp_path / "runs").glob("*/sweep_*.png")), sorted((tmp_path / "runs").rglob("*"))


def test_without_a_writable_home_matplotlib_leaves_no_folder_per_run(tmp_path):
    """matplotlib made a /tmp/matplotlib-* folder in every run (the forked figure processes
    leave without its cleanup) and warned twice; one private folder per user is used instead."""
    import os
    import subprocess
    import sys

    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env.update({"PYTHONPATH": str(REPO), "HOME": "/proc/nonexistent",
                "TMPDIR": str(tmp), "OPENBLAS_NUM_THREADS": "1"})
    for name in ("a", "b"):
        done = subprocess.run([sys.executable, "-m", "acmm.cli.app", "design", "mb3", f"name={name}"], cwd=tmp_path,
                              capture_output=True, text=True, env=env, timeout=300, check=False)
        assert done.returncode == 0 and done.stderr == "", done.stderr
        assert (tmp_path / "runs" / name / "design_poles.png").exists()
    assert [p.name for p in tmp.iterdir()] == [f"acmm-matplotlib-{os.getuid()}"]
