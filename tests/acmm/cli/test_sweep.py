"""``acmm sweep`` (acmm.cli.sweep): a smoke sweep end to end, its --help, and the refusals of
--scheduler and --workers."""
from __future__ import annotations

import json
import sys

from acmm_qpp.results import read_h5

from tests.conftest import CONFIGS, invoke
from tests.acmm.conftest import _sweep_yaml


def acmm(*args):
    from acmm.cli.app import app

    return invoke(app, *args)


def test_help_renders_extras_literally():
    r = acmm("sweep", "--help")
    assert r.exit_code == 0 and "acmm-qpp[dask]" in r.stdout


def test_scheduler_without_distributed_is_a_one_line_error(tmp_path, run_acmm, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)      # import distributed -> ImportError
    cfg = _sweep_yaml(tmp_path, "nosched", n_runs=1)
    r = run_acmm("sweep", cfg, "--scheduler", "tcp://127.0.0.1:8786")
    assert r.exit_code == 2 and "acmm-qpp[dask]" in r.stderr and r.stderr.count("\n") == 1


# --------------------------------------------------------------------------------------------
# command line
# --------------------------------------------------------------------------------------------
def test_cli_smoke_sweep(tmp_runs, run_acmm):
    r = run_acmm("sweep", CONFIGS / "sweep_smoke.yaml", "--workers", "2")
    assert r.exit_code == 0, r.output
    d = tmp_runs / "runs" / "sweep_smoke"
    for f in ("sweep.h5", "sweep.csv", "sweep_map.png", "sweep_peak_error.png"):
        assert (d / f).is_file(), f
    lines = (d / "sweep.csv").read_text().splitlines()
    assert len(lines) == 1 + 8
    h = read_h5(d / "sweep.h5")
    assert h["peak_momentum"].shape == (8, 3)
    assert h["attrs"]["complete"]
    counts = json.loads(h["attrs"]["summary"])["ac"]
    assert sum(counts.values()) == 8
    assert f"ac: {counts['bounded']}/8 bounded" in r.stdout


def test_an_empty_scheduler_address_is_refused_not_run_locally(tmp_runs, run_acmm):
    """`--scheduler ""` ran the sweep on local processes without a word (a review)."""
    r = run_acmm("sweep", "sweep_smoke", "--scheduler", "", "sweep.n_runs=2")
    assert r.exit_code == 2 and r.output.strip().startswith("error: --scheduler: an empty address"), r.output
    assert not (tmp_runs / "runs").exists()


def test_workers_and_a_scheduler_together_are_refused(tmp_runs, run_acmm):
    """-j was silently ignored beside --scheduler (a review)."""
    r = run_acmm("sweep", "sweep_smoke", "-j", "2", "--scheduler", "tcp://127.0.0.1:1", "sweep.n_runs=2")
    assert r.exit_code == 2 and r.output.strip().startswith("error: --workers and --scheduler: give one"), r.output


def test_plot_redraws_the_sweep_figures_pixel_for_pixel(tmp_runs):
    """Issue 34: ``acmm plot`` draws the stability map and the peak errors from sweep.h5 alone."""
    import matplotlib.image as mpimg
    import numpy as np

    from acmm.cli.app import app
    from tests.conftest import invoke

    r = invoke(app, "sweep", "sweep_smoke", "sweep.n_runs=3", "sweep.orbits=0.3", "~sweep.margin", "-j", "1",
               "--figures")
    assert r.exit_code == 0, r.output
    run = tmp_runs / "runs" / "sweep_smoke"
    assert invoke(app, "plot", run, "--out", tmp_runs / "re").exit_code == 0
    for name in ("sweep_map.png", "sweep_peak_error.png"):
        a, b = mpimg.imread(run / name), mpimg.imread(tmp_runs / "re" / name)
        assert a.shape == b.shape and np.abs(a - b).max() == 0.0, name
