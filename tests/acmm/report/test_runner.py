"""The report's task graph (issue 16, :mod:`acmm.report.runner`, :mod:`acmm.report.plan`): the same results on
worker processes as one after the other, and one clear error with no output on a failure."""
from __future__ import annotations

import importlib
import os
import re
import time

import numpy as np
import pytest

from acmm_qpp.errors import ConvergenceError, OutputError
from acmm.report.runner import Task, run_tasks
from tests.acmm.report.conftest import manifest_stages, moved_aside

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="worker processes are forked")


# ----------------------------------------------------------------------------- toy graphs
def _square(x):
    return x * x


def _add(a, b):
    return a + b


def _pid_after(path, delay):
    time.sleep(delay)
    with open(path, "a") as f:
        f.write(f"{os.getpid()}\n")
    return os.getpid()


def _fail(msg):
    raise ConvergenceError(msg)


def _die():
    os._exit(9)


def _graph(tmp_path):
    log = tmp_path / "log"
    return [
        Task("a", _square, (), lambda d: (3,)),
        Task("b", _square, (), lambda d: (4,)),
        Task("slow1", _pid_after, (), lambda d: (log, 0.0), cost=5),
        Task("slow2", _pid_after, (), lambda d: (log, 0.0), cost=5),
        Task("sum", _add, ("a", "b"), lambda d: (d["a"], d["b"])),
        Task("sum2", _add, ("sum", "slow1"), lambda d: (d["sum"], 0)),
    ]


def test_parallel_and_serial_give_the_same_results(tmp_path):
    seen = []
    serial = run_tasks(_graph(tmp_path), 1, on_done=lambda n, r: seen.append(n))
    assert seen == ["a", "b", "slow1", "slow2", "sum", "sum2"]          # list order when serial
    order = []
    stats: dict = {}
    par = run_tasks(_graph(tmp_path), 2, on_done=lambda n, r: order.append(n), stats=stats)
    assert {k: v for k, v in par.items() if not k.startswith("slow")} == \
        {k: v for k, v in serial.items() if not k.startswith("slow")} == {"a": 9, "b": 16, "sum": 25, "sum2": 25}
    # ran in two other processes at the same time, each task once, after its dependencies
    assert os.getpid() not in (par["slow1"], par["slow2"])            # in other processes
    assert sorted(order) == sorted(serial) and order.index("sum") > max(order.index("a"), order.index("b"))
    assert order.index("sum2") > order.index("slow1")
    assert set(stats) == set(serial) and all(w >= 0 and c >= 0 for w, c in stats.values())


def test_a_dependency_must_come_first():
    with pytest.raises(ValueError, match="'x'"):
        run_tasks([Task("x", _square, ("y",)), Task("y", _square)], 2)


def test_error_in_a_worker_is_the_same_error_and_stops_the_graph(tmp_path):
    log = tmp_path / "log"
    tasks = [Task("decoy", _square, (), lambda d: (1,), cost=20),     # the first to start
             Task("bad", _fail, (), lambda d: ("solver did not converge: field x",), cost=10),
             Task("slow", _pid_after, (), lambda d: (log, 0.2)),
             Task("after", _pid_after, ("bad",), lambda d: (log, 0.0))]
    with pytest.raises(ConvergenceError, match="^solver did not converge: field x$") as exc:
        run_tasks(tasks, 2)
    assert exc.value.exit_code == 3
    ran = log.read_text().split() if log.exists() else []
    assert len(ran) <= 1                              # "after" never ran; "slow", if started, was waited for


def test_a_worker_that_dies_is_one_clear_error():
    with pytest.raises(OutputError, match="worker process died"):
        run_tasks([Task("die", _die), Task("ok", _square, (), lambda d: (2,), cost=9)], 2)   # "die" on the pool


def _stamp_then(path, what):
    """Write this process's start time to ``path``, then fail in the way ``what`` names."""
    with open(path, "w") as f:
        f.write(f"{os.getpid()} {time.time()}")
    if what == "acmm":
        raise ConvergenceError("no convergence: field y")
    if what == "key":
        raise KeyError("not an AcmmError")
    if what == "die":
        os._exit(9)
    if what == "unpicklable":
        return lambda: None
    raise AssertionError(what)


@pytest.mark.parametrize("what,error,match", [
    ("acmm", ConvergenceError, "^no convergence: field y$"),
    ("key", KeyError, "not an AcmmError"),
    ("die", OutputError, "worker process died"),
    ("unpicklable", Exception, "pickle|local object"),
])
def test_a_pool_tasks_error_is_raised_here(tmp_path, what, error, match):
    """On the pool: an AcmmError comes back as the same class and message, another exception as
    itself with the worker's traceback, a dying worker as one OutputError, a result that does not
    pickle as the pickling error; the task ran in another process."""
    with pytest.raises(error, match=match) as exc:
        run_tasks([Task("bad", _stamp_then, (), lambda d: (tmp_path / "bad", what), cost=9),
                   Task("ok", _square, (), lambda d: (2,))], 2)
    pid, _ = (tmp_path / "bad").read_text().split()
    assert int(pid) != os.getpid()
    if what == "key":
        assert "_stamp_then" in str(exc.value.__cause__)


def _blocked_until(event_path, marker):
    """Write ``marker`` then wait until ``event_path`` exists (at most 60 s)."""
    marker.write_text(str(os.getpid()))
    deadline = time.monotonic() + 60
    while not event_path.exists() and time.monotonic() < deadline:
        time.sleep(0.005)
    return os.getpid()


def _release(event_path, marker):
    """Wait until the other task has started (``marker``), then let it go (``event_path``)."""
    deadline = time.monotonic() + 60
    while not marker.exists() and time.monotonic() < deadline:
        time.sleep(0.005)
    event_path.write_text("go")
    return os.getpid()


def test_two_jobs_run_two_tasks_at_once_in_two_workers(tmp_path):
    """Each task waits for the other to have started: this ends only when both run at once."""
    ev, marker = tmp_path / "go", tmp_path / "started"
    out = run_tasks([Task("wait", _blocked_until, (), lambda d: (ev, marker)),
                     Task("release", _release, (), lambda d: (ev, marker))], 2)
    assert len({out["wait"], out["release"], os.getpid()}) == 3


# ----------------------------------------------------------------------------- the report's graph
def _claim1_graph(root, figdir, jobs):
    """The MB3 stages and the parts that read them (claim-1 poles and section), as in build_report."""
    from acmm.report.context import SectionWriter
    from acmm.report.gather import (
        Gathered,
        keep_stage,
        order_runs,
        report_configs,
        stage_tasks,
        warm_workers,
    )
    from acmm.report.plan import section_tasks

    g = Gathered(report_configs(root), {})
    stages = [t for t in stage_tasks(g.configs, root, robustness=False, jobs=jobs)
              if t.name.endswith((":mb3", ":mb3_decoupled"))]
    rep = SectionWriter(g, figdir, False)
    names = {t.name for t in stages}
    parts = [t for t in section_tasks(g, figdir, False, names, rep.results if jobs == 1 else None)
             if t.name in ("poles", "claim1")]
    done = run_tasks(stages + parts, jobs, lambda n, r: keep_stage(g, n, r, lambda s: None) if n in names else None,
                     warm=warm_workers)
    order_runs(g, stages)
    return g, done


def test_report_graph_in_workers_matches_serial(tmp_path):
    """The claim-1 branch of the report (4 stages, 2 parts) on 2 processes and on 1: the same
    datasets (hashes), run order, document blocks, printed numbers and figure bytes."""
    from acmm.report.manifest import dataset_hashes

    out = {}
    for jobs in (1, 2):
        figdir = tmp_path / f"fig{jobs}"
        figdir.mkdir()
        g, done = _claim1_graph(tmp_path / f"runs{jobs}", figdir, jobs)
        out[jobs] = (g, done, figdir)
    (g1, d1, f1), (g2, d2, f2) = out[1], out[2]
    assert list(g1.runs) == list(g2.runs) == ["acmm design:mb3", "acmm design:mb3_decoupled",
                                              "acmm simulate:mb3", "acmm simulate:mb3_decoupled"]
    for key in g1.runs:
        assert dataset_hashes(g1.runs[key].path) == dataset_hashes(g2.runs[key].path), key
    np.testing.assert_array_equal(d1["poles"].value, d2["poles"].value)
    c1, c2 = d1["claim1"], d2["claim1"]
    assert c1.value.div == c2.value.div and c1.value.maxre == c2.value.maxre
    strip = lambda blocks: [b[:3] if b[0] == "fig" else b for b in blocks]  # noqa: E731 (paths differ)
    assert strip(c1.blocks) == strip(c2.blocks) and len(c1.blocks) >= 4
    assert [(p.quantity, p.computed, p.status) for p in c1.ledger] == \
        [(p.quantity, p.computed, p.status) for p in c2.ledger]
    png = "claim1_responses.png"
    assert (f1 / png).read_bytes() == (f2 / png).read_bytes()


def _broken_qpp(cfg, stage, rerun):
    raise ConvergenceError(f"qpp {stage} of {cfg.name}: Riccati solver did not converge")


@pytest.mark.slow
def test_report_failure_in_a_worker_is_one_line_and_shown_in_its_sections(fast_report, tmp_path, monkeypatch):
    """Every qpp stage raising in a worker: one ``error:`` line, exit 3, no traceback; the report
    is written (issue 30: it stopped with nothing written), its qpp sections show the error and the
    acmm sections are complete.  (The acmm stages are the session's fast report's, reused.)"""
    from typer.testing import CliRunner

    from acmm.cli.app import app

    gather_mod = importlib.import_module("acmm.report.gather")

    monkeypatch.setattr(gather_mod, "ensure_qpp", _broken_qpp)
    out, root = tmp_path / "out", fast_report[0] / "runs"
    with moved_aside(root, "qpp_siso", "qpp_manipulator"):
        res = CliRunner().invoke(app, ["report", "--fast", "--jobs", "2", "--out", str(out), "--root", str(root)])
        assert not (root / "qpp_siso").exists() and not (root / "qpp_manipulator").exists()
    assert res.exit_code == 3, res.output
    lines = res.output.strip().splitlines()
    assert lines[-1].startswith("error:") and "did not converge" in lines[-1]
    assert not any(line.startswith("Traceback") for line in lines)
    md = (out / "report.md").read_text(encoding="utf-8")
    assert "FAILED — qpp13 not computed: qpp design:qpp_siso failed: qpp design of qpp_siso: Riccati" in md
    assert "FAILED" not in md.split("## QPP chapter 13")[0]
    assert (out / "index.html").is_file() and (out / "manifest.json").is_file()
    assert not any(k.startswith("qpp ") for k in manifest_stages(out)) and "acmm simulate:mb3" in manifest_stages(out)


@pytest.mark.slow
def test_an_interrupted_report_leaves_out_as_it_was(fast_report, tmp_path, monkeypatch):
    """Ctrl-C after every section was drawn (here: in the printed-values section, which runs
    last): the figures had been written into --out/figures as their tasks finished, beside the
    previous report's pages (a review).  They are drawn in a staging folder now and moved in only
    with the pages."""
    from typer.testing import CliRunner

    from acmm.cli.app import app

    out = tmp_path / "out"
    (out / "figures").mkdir(parents=True)
    (out / "index.html").write_text("the previous report")
    build_mod = importlib.import_module("acmm.report.build")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(build_mod, "_printed", interrupted)
    res = CliRunner().invoke(app, ["report", "--fast", "--out", str(out), "--root", str(fast_report[0] / "runs")])
    assert res.exit_code == 130, res.output
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == ["figures", "index.html"]
    assert (out / "index.html").read_text() == "the previous report"


def test_default_jobs(monkeypatch):
    import threading

    from acmm.report.runner import default_jobs

    monkeypatch.setenv("ACMM_REPORT_JOBS", "3")
    assert default_jobs() == 3
    from acmm_qpp.errors import ConfigError

    for bad in ("0", "abc", "-1", "1.5", "5000"):         # were ignored without a word (a review)
        monkeypatch.setenv("ACMM_REPORT_JOBS", bad)
        with pytest.raises(ConfigError, match=f"ACMM_REPORT_JOBS: must be a whole number from 1 to 1024 \\(got '{re.escape(bad)}'\\)"):
            default_jobs()
    monkeypatch.delenv("ACMM_REPORT_JOBS")
    assert default_jobs() == (1 if threading.active_count() > 1 else max(1, min(2, os.cpu_count() or 1)))
    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert default_jobs() == 1                    # no fork beside other threads
    finally:
        stop.set()
        t.join()


def _warns():
    import warnings

    warnings.warn("numerical trouble", RuntimeWarning, stacklevel=1)
    return 1


@pytest.mark.parametrize("action, expected", [("default", 1), ("always", 3)])
def test_worker_warnings_reach_the_caller_as_in_a_serial_run(action, expected):
    """A task's warnings raised in a pool worker are raised again in the
    caller, counted as the serial run counts them (the CLI's note: line)."""
    import warnings

    from acmm.report.runner import Task, run_tasks

    counts = []
    for jobs in (1, 2):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter(action)
            out = run_tasks([Task("a", _warns), Task("b", _warns), Task("c", _warns)], jobs=jobs)
        assert out == {"a": 1, "b": 1, "c": 1}
        counts.append(sum(str(w.message) == "numerical trouble" for w in got))
    assert counts == [expected, expected]


@pytest.mark.slow
def test_a_results_file_rewritten_while_the_report_runs_is_refused(fast_report, tmp_path, monkeypatch):
    """The report holds no run lock while its sections read the stages' files: a user's
    `acmm design staircase_fast schedule.n_points=3` during the report gave a report whose
    schedule section spoke of 3 points and whose errata row of 12 (a review).  A results file
    rewritten after the report took it is now named, and nothing is written."""
    import shutil

    from typer.testing import CliRunner

    from acmm.cli.app import app

    out = tmp_path / "out"
    build_mod = importlib.import_module("acmm.report.build")
    original = build_mod._printed

    def rewrite_then_build(rep, *args, **kwargs):
        path = next(r.path for k, r in rep.g.runs.items() if k.startswith("acmm design:"))
        shutil.copy2(path, path.with_name("copy.h5"))
        path.with_name("copy.h5").replace(path)              # another run's atomic write
        return original(rep, *args, **kwargs)

    monkeypatch.setattr(build_mod, "_printed", rewrite_then_build)
    # (the session's fast report's stages: the copy moved into place holds the same bytes)
    res = CliRunner().invoke(app, ["report", "--fast", "--out", str(out), "--root", str(fast_report[0] / "runs")])
    assert res.exit_code == 4, res.output
    assert res.output.strip().splitlines()[-1].startswith("error: acmm design:") and "rewritten" in res.output
    assert not [p for p in out.rglob("*") if p.is_file()]
