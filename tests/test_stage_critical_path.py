"""Reorderings that shorten the stair-case stages' critical path (issue 16) change no number:
the refit on its own models equals the refit on the whole path, and the figure worker forked
ahead by the command line is adopted by the stage's session or stopped."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from acmm.design import schedule as sch
from acmm.design import schedule_points as sp
from acmm.io.config import load_config
from acmm.design.design_core import _refit
from acmm.design.path_check import path_models
from acmm.design.schedule_refit import REFIT_DEFAULTS, refit_closed_loop
from acmm.design.settings import design_settings


@pytest.fixture(scope="module")
def points_and_fit():
    cfg = load_config("staircase")
    s = design_settings(cfg)
    pts = [sch.design_one(sp, s) for sp in sp.point_specs(cfg)]
    gains = np.array([p.lqr.K for p in pts])
    teas = np.array([p.tea.theta for p in pts])
    return pts, s, sch.fit_schedule(teas[:, 1], gains, 2, "polynomial")


@pytest.mark.parametrize("n_check", [37, 12, 2])
def test_path_models_at_indices_are_the_whole_paths_rows(points_and_fit, n_check):
    pts, s, _ = points_and_fit
    full = path_models(pts, s, n_check)
    idx = [n_check - 1, 0] + list(range(1, n_check - 1, 5))
    sub = path_models(pts, s, n_check, indices=idx)
    for name in ("theta2", "s", "A", "B"):
        assert np.array_equal(getattr(sub, name), getattr(full, name)[idx]), name
    assert np.array_equal(sub.scales, full.scales)


@pytest.mark.parametrize("n_check", [37, 31])
def test_refit_on_its_own_models_equals_the_refit_on_the_whole_path(points_and_fit, n_check):
    """37: the last TEA is not one of every 10th; 31: it is."""
    pts, s, fit = points_and_fit
    whole = refit_closed_loop(fit, path_models(pts, s, n_check), s.orbit_rate,
                              half_angle_deg=s.sector.half_angle_deg, **REFIT_DEFAULTS)
    early = _refit(fit, pts, s, n_check)
    assert early.method == whole.method
    assert np.array_equal(early.coef, whole.coef)
    assert early.refit_info == whole.refit_info
    assert early.refit_info["n_tea"] == len(set(range(0, n_check, REFIT_DEFAULTS["every"])) | {n_check - 1})


_EARLY = textwrap.dedent("""
    import os, sys, numpy as np
    from pathlib import Path
    from acmm.plots import base as plot_base
    from acmm.plots import simulation as sim_plots
    from acmm_qpp import figure_worker
    out = Path(sys.argv[1])
    if not figure_worker.usable():
        print("skip"); sys.exit(0)
    assert figure_worker.start_early()
    pid = figure_worker._WORKER.pid
    if sys.argv[2] == "adopt":
        t = np.linspace(0.0, 1.0, 50); x = np.zeros((50, 3))
        with figure_worker.session():
            figure_worker.submit(sim_plots.axis_histories, t, x, x, x, x, "t", out / "a.png")
        assert not figure_worker.active() and (out / "a.png").stat().st_size > 10_000
    else:
        figure_worker._drop_unowned()          # what the atexit handler does
        assert not figure_worker.active()
    try:
        os.kill(pid, 0); print("alive")
    except ProcessLookupError:
        print("gone")
""")


@pytest.mark.parametrize("mode", ["adopt", "drop"])
def test_early_figure_worker_is_adopted_or_stopped(tmp_path, mode):
    p = subprocess.run([sys.executable, "-c", _EARLY, str(tmp_path), mode], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    if p.stdout.strip() == "skip":
        pytest.skip("no fork or one CPU")
    assert p.stdout.strip() == "gone"


def test_usage_error_with_an_early_worker_leaves_no_process(tmp_path):
    """``acmm design --bogus`` with the worker forked ahead: exit 64, one line, no output (the
    worker holds stderr open, so ``run`` returning at all shows it stopped)."""
    code = ("import sys; from acmm.cli.app import main; sys.argv = ['acmm', 'design', 'staircase', "
            "'--bogus']; main()")
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 64
    assert p.stderr.count("\n") == 1 and "--bogus" in p.stderr
    assert not (tmp_path / "runs").exists()


def _square(x):
    return x * x


def _fail(x):
    raise ValueError(f"bad {x}")


def _die(x):
    import os

    if os.environ.get("ACMM_TEST_IN_CHILD") == "1":
        os._exit(3)                               # only the forked child dies
    return x + 1


def test_forked_call_returns_the_childs_result_or_computes_in_place(monkeypatch):
    from acmm_qpp import forked

    if not forked.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    c = forked.ForkedCall(_square, np.arange(5.0))
    assert c.forked
    assert np.array_equal(c.result(), np.arange(5.0) ** 2)
    assert not forked.ForkedCall(_square, 3, enabled=False).forked
    assert forked.ForkedCall(_square, 3, enabled=False).result() == 9
    with pytest.raises(ValueError, match="bad 7"):          # the error is the caller's own
        forked.ForkedCall(_fail, 7).result()
    monkeypatch.setenv("ACMM_TEST_IN_CHILD", "1")
    c = forked.ForkedCall(_die, 1)                           # the child dies: computed here
    monkeypatch.delenv("ACMM_TEST_IN_CHILD")
    assert c.forked and c.result() == 2
    assert not c.from_child
    monkeypatch.setenv("ACMM_FORK", "0")
    assert not forked.usable() and not forked.ForkedCall(_square, 2).forked


def _warn_twice(x):
    import warnings

    warnings.warn(f"first {x}", RuntimeWarning, stacklevel=1)
    warnings.warn(f"second {x}", UserWarning, stacklevel=1)
    return -x


def test_forked_call_raises_the_childs_warnings_here_and_falls_back_in_place():
    import warnings

    from acmm_qpp import forked

    if not forked.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    with warnings.catch_warnings(record=True) as here:
        warnings.simplefilter("always")
        assert _warn_twice(4) == -4
    with warnings.catch_warnings(record=True) as forked_warnings:
        warnings.simplefilter("always")
        c = forked.ForkedCall(_warn_twice, 4)
        assert c.result() == -4 and c.from_child
    assert [(type(w.message), str(w.message), w.lineno) for w in forked_warnings] == \
        [(type(w.message), str(w.message), w.lineno) for w in here]
    calls = []
    c = forked.ForkedCall(_fail, 5, in_place=lambda x: calls.append(x) or x * 10)   # the child fails
    assert c.result() == 50 and calls == [5] and not c.from_child


def _warn_once_here(x):
    import warnings

    warnings.warn("the same warning from the same line", RuntimeWarning, stacklevel=1)
    return x


class _TwoArgWarning(UserWarning):
    def __init__(self, a, b):
        super().__init__(f"{a} and {b}")


def _odd_warnings(x):
    import warnings

    class Local(UserWarning):
        pass

    warnings.warn(Local("a class defined in a function"), stacklevel=1)
    warnings.warn(_TwoArgWarning(1, 2), stacklevel=1)        # pickles, but cannot be rebuilt
    return x + 1


@pytest.mark.parametrize("action", ["default", "once"])
def test_forked_call_warnings_are_shown_as_often_as_in_place(action):
    """Under "default" or "once" a warning raised here and by the child from the same line is
    shown once, as in place; a warning that cannot travel as itself arrives as its text."""
    import warnings

    from acmm_qpp import forked

    if not forked.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    counts = []
    for fork in (False, True):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter(action)
            c = forked.ForkedCall(_warn_once_here, 1, enabled=fork)
            _warn_once_here(0)
            assert c.result() == 1 and c.from_child == fork
            _warn_once_here(2)
        counts.append(len(got))
    assert counts == [1, 1]
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        c = forked.ForkedCall(_odd_warnings, 1)
        assert c.result() == 2 and c.from_child                  # the child's value, not redone
    # each as itself when it survives a pickle (Dask's tblib, once imported, makes the second
    # one do so), else as its text with the nearest built-in category
    assert [str(w.message) for w in got] == ["a class defined in a function", "1 and 2"]
    assert got[0].category is UserWarning and got[1].category in (UserWarning, _TwoArgWarning)


def test_forked_call_cancel_kills_the_child():
    import os
    import time

    from acmm_qpp import forked

    if not forked.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    c = forked.ForkedCall(time.sleep, 60)
    pid = c._pid
    t0 = time.perf_counter()
    c.cancel()
    assert time.perf_counter() - t0 < 30
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)                         # reaped: no zombie left


def test_design_with_the_forked_path_equals_the_design_in_place():
    from acmm.stages.design import compute_design

    cfg = load_config("staircase", ["schedule.n_check=41"])
    seen = []
    a, b = compute_design(cfg, seen.append, fork=True), compute_design(cfg, fork=False)
    # the forked helper designed the second half of the points: the same points, in order
    assert seen == [p.spec.name for p in b.points] and [p.spec.name for p in a.points] == seen
    for pa, pb in zip(a.points, b.points):
        assert np.array_equal(pa.lqr.K, pb.lqr.K) and np.array_equal(pa.tea.theta, pb.tea.theta)
        assert np.array_equal(pa.lqr.poles, pb.lqr.poles)
    assert np.array_equal(a.fit.coef, b.fit.coef)
    for name in ("max_real", "margin", "disk_margin", "poles"):
        assert np.array_equal(getattr(a.path_check, name), getattr(b.path_check, name)), name


def test_forked_design_helper_failures_act_as_in_place(monkeypatch):
    """A point the helper designs fails: the same error as in place; the helper's path models
    fail: they are solved again here, and the design is the same."""
    from acmm.design import design_core
    from acmm.design import path_check as pc
    from acmm.design import schedule
    from acmm.stages.design import compute_design
    from acmm_qpp.errors import ConvergenceError

    cfg = load_config("staircase", ["schedule.n_check=21"])
    reference = compute_design(cfg, fork=False)
    last = reference.points[-1].spec.name
    design_one = schedule.design_one

    def failing(spec, s):
        if spec.name == last:
            raise ConvergenceError(f"sector LQR did not converge at {spec.name}")
        return design_one(spec, s)

    monkeypatch.setattr(schedule, "design_one", failing)
    seen = {}
    for fork in (True, False):
        seen[fork] = []
        with pytest.raises(ConvergenceError, match=f"at {last}$"):
            compute_design(cfg, seen[fork].append, fork=fork)
    assert seen[True] == seen[False] == [p.spec.name for p in reference.points[:-1]]

    def warning(spec, s):
        import warnings

        warnings.warn(f"ill-conditioned at {spec.name}", RuntimeWarning, stacklevel=1)
        return design_one(spec, s)

    monkeypatch.setattr(schedule, "design_one", warning)
    caught = {}
    for fork in (True, False):
        import warnings

        with warnings.catch_warnings(record=True) as caught[fork]:
            warnings.simplefilter("always")
            compute_design(cfg, fork=fork)
    assert sorted(str(w.message) for w in caught[True]) == sorted(str(w.message) for w in caught[False])
    assert len(caught[True]) >= len(reference.points)
    monkeypatch.setattr(schedule, "design_one", design_one)
    parent, models = os.getpid(), pc.path_models_from_specs

    def models_fail_in_the_child(*args, **kwargs):
        if os.getpid() != parent:
            raise RuntimeError("the helper's path models failed")
        return models(*args, **kwargs)

    monkeypatch.setattr(design_core, "path_models_from_specs", models_fail_in_the_child)
    again = compute_design(cfg, fork=True)
    assert np.array_equal(again.fit.coef, reference.fit.coef)
    assert np.array_equal(again.path_check.poles, reference.path_check.poles)


def _histories(n=300):
    t = np.linspace(0.0, 3.0, n)
    return t, np.column_stack([np.sin(5 * t), np.cos(3 * t), t]) * 2.0


def test_reserved_figure_writers_draw_the_same_png_and_never_hang(tmp_path):
    """A figure whose writer was forked ahead (``prepare(..., for_figure=...)``) is drawn by it,
    identical to the figure drawn in place; a reserved writer whose figure never comes, across a
    nested session's flush, ends with the session; a second figure of the same name gets its own
    writer."""
    from acmm.plots import base as plot_base
    from acmm.plots import simulation as sim_plots
    from acmm_qpp import figure_worker

    if not figure_worker.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    t, x = _histories()
    sim_plots.axis_histories(t, x, x, x, x, "t", tmp_path / "here.png")
    with figure_worker.session():
        figure_worker.prepare(plot_base.prebuild, "axis_histories", "imperial", for_figure="axis_histories")
        figure_worker.prepare(plot_base.prebuild, "summary", "imperial", for_figure="summary")   # never drawn
        with figure_worker.session():                                # a nested stage's flush
            figure_worker.submit(sim_plots.inertia_histories, t, np.tile(np.eye(3) * 1e6, (t.size, 1, 1)),
                                 tmp_path / "inner.png")
        assert (tmp_path / "inner.png").exists()
        figure_worker.submit(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "reserved.png")
        figure_worker.submit(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "second.png")
    assert not figure_worker.active()
    here = (tmp_path / "here.png").read_bytes()
    assert (tmp_path / "reserved.png").read_bytes() == here == (tmp_path / "second.png").read_bytes()
    assert not list(tmp_path.glob("*summary*"))


def test_reserved_writers_abort_with_the_stage_and_report_failures(tmp_path):
    from acmm.plots import base as plot_base
    from acmm.plots import simulation as sim_plots
    from acmm_qpp import figure_worker
    from acmm_qpp.errors import OutputError

    if not figure_worker.usable():
        pytest.skip("no fork, one CPU or other threads alive")
    t, x = _histories()
    with pytest.raises(RuntimeError, match="stage failed"):
        with figure_worker.session():
            figure_worker.prepare(plot_base.prebuild, "axis_histories", "imperial", for_figure="axis_histories")
            raise RuntimeError("stage failed")
    assert not figure_worker.active()
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputError):
        with figure_worker.session():
            figure_worker.prepare(plot_base.prebuild, "axis_histories", "imperial", for_figure="axis_histories")
            figure_worker.submit(sim_plots.axis_histories, t, x, x, x, x, "t", tmp_path / "file" / "a.png")
    assert not figure_worker.active() and not list(tmp_path.glob("**/*.tmp*"))


@pytest.mark.slow
def test_qpp_simulate_reuses_the_gains_qpp_design_wrote(tmp_path, monkeypatch):
    """Same config and code: the stored K1, Kc, H (no second ch. 12.1 design) and a qpp_sim.h5
    identical to the one a simulation designing for itself writes; another config: a design."""
    from qpp.io import stages
    from qpp.design import procedure as procedure_mod
    from qpp.io.config import load_config as qpp_config
    from qpp.io.stored_design import StoredDesign
    from acmm.report.manifest import dataset_hashes

    import h5py

    from acmm_qpp import provenance

    over = [f"output.root={tmp_path}", "simulation.t_final=3.0"]
    alone = stages.run_simulate(qpp_config("qpp_siso", over + ["name=alone"]), figures=False)
    cfg = qpp_config("qpp_siso", over + ["name=pair"])
    _, designed, dpath = stages.run_design(cfg, figures=False)
    real_design = procedure_mod.design
    monkeypatch.setattr(provenance, "source_unchanged", lambda: True)     # as in a clean checkout
    monkeypatch.setattr(stages, "design", lambda c: pytest.fail("designed again"))
    _, reused, _, path = stages.run_simulate(cfg, figures=False)
    assert isinstance(reused, StoredDesign) and reused.verdict == designed.verdict
    for name in ("K1", "Kc", "H"):
        assert np.array_equal(getattr(reused, name), getattr(designed, name))
    assert dataset_hashes(path) == dataset_hashes(alone[3])
    called = []
    monkeypatch.setattr(stages, "design", lambda c: called.append(1) or real_design(c))
    stages.run_simulate(qpp_config("qpp_siso", over + ["name=pair", "simulation.t_final=2.0"]), figures=False)
    assert called == [1]                       # the config changed: designed
    monkeypatch.setattr(provenance, "source_unchanged", lambda: False)    # edited source: designed
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1]
    monkeypatch.setattr(provenance, "source_unchanged", lambda: True)
    with h5py.File(dpath, "r+") as f:          # gains edited in the file: designed
        f["K1"][0, 0] = 50.0 * f["K1"][0, 0]
    stages.run_simulate(cfg, figures=False)
    assert called == [1, 1, 1]
