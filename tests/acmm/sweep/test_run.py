"""Whole sweeps (acmm.sweep.run, issue 7): the same table serial and on a pool or a Dask
cluster, kill and resume, a resume refused for another config, background snapshots; the workers
(heap reuse restored where Dask's worker environment stops it, a lost worker, a repeated
interrupt, a cluster running other code)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import yaml

from acmm_qpp.errors import ConfigError
from acmm_qpp.results import read_h5
from acmm.model.inertia import perturb_inertia, unphysical_reason
from acmm.sweep.cases import case_values
from acmm.sweep.run import MAX_CHUNK, MAX_TASK_SECONDS, MIN_TASK_SECONDS, _Chunker, _chunk_size, run_sweep
from acmm.sweep.config import load_sweep, parse_sweep

from tests.acmm.conftest import _sweep_yaml
from tests.acmm.sweep.conftest import _assert_same_data, _cfg, _run_bytes
from tests.conftest import REPO


# --------------------------------------------------------------------------------------------
# whole sweeps
# --------------------------------------------------------------------------------------------
def test_an_interrupted_rerun_does_not_sit_beside_the_earlier_runs_config_and_figures(tmp_path):
    """Seed A ran to the end (figures, config.yaml); seed B, interrupted, left its partial results
    beside A's config.yaml and figures (a review).  A sweep started afresh now writes its own
    config.yaml first and removes the earlier run's results and figures."""
    class _Stop(Exception):
        pass

    def stop(n_new):
        if n_new == 2:
            raise _Stop

    run_sweep(_sweep_yaml(tmp_path, "rerun", seed=1, margin=None), workers=1, figures=True)
    run = tmp_path / "runs" / "rerun"
    assert list(run.glob("sweep_*.png")) and "seed: 1" in (run / "config.yaml").read_text()
    with pytest.raises(_Stop):
        run_sweep(_sweep_yaml(tmp_path, "rerun", seed=2, margin=None), workers=1, figures=True,
                  after_record=stop, snapshot_interval=0.0)
    assert not list(run.glob("sweep_*.png"))
    assert "seed: 2" in (run / "config.yaml").read_text()
    if (run / "sweep.h5").exists():
        h = read_h5(run / "sweep.h5")
        assert not h["attrs"]["complete"] and "seed: 2" in h["attrs"]["config"]


def test_a_sweep_whose_figure_fails_finishes_with_its_config(tmp_runs):
    """The sweep's tables are written before its figures: a figure in the way is exit 4 with
    this run's config.yaml, and the earlier run's other figure pruned."""
    import yaml
    from typer.testing import CliRunner

    from acmm.cli.app import app
    from tests.conftest import CONFIGS

    cfg = yaml.safe_load((CONFIGS / "sweep_smoke.yaml").read_text())
    cfg["sweep"].pop("margin", None)
    cfg["sweep"].update(n_runs=2, orbits=0.5)
    cfg["output"] = {"root": str(tmp_runs / "runs"), "figures": True}
    path = tmp_runs / "sw.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(app, ["sweep", str(path), "-j", "1"])
    assert r.exit_code == 0, r.output
    run = tmp_runs / "runs" / cfg["name"]
    (run / "sweep_map.png").unlink()
    (run / "sweep_map.png").mkdir()
    r = CliRunner().invoke(app, ["sweep", str(path), "-j", "1", "sweep.n_runs=3"])
    assert r.exit_code == 4, r.output
    assert "n_runs: 3" in (run / "config.yaml").read_text()
    # the map is drawn first and failed; the earlier run's peak-error figure is not this run's
    assert not (run / "sweep_peak_error.png").exists()


def test_same_config_and_seed_give_identical_data_serial_and_pool(tmp_path):
    cfg = _sweep_yaml(tmp_path, "same", margin={"low": 0.8, "high": 1.25, "scan_points": 1, "rel_tol": 0.1})
    r1 = run_sweep(cfg, workers=1)
    a = read_h5(r1.path)
    os.replace(r1.path, tmp_path / "first.h5")
    r2 = run_sweep(cfg, workers=2)
    b = read_h5(r2.path)
    _assert_same_data(read_h5(tmp_path / "first.h5"), b)
    assert a["attrs"]["complete"] and a["attrs"]["n_cases_done"] == 6
    assert a["parameters"]["dI11"].shape == (6,) and a["peak_attitude_error"].shape == (6, 3)
    assert a["attrs"]["results_key"] == b["attrs"]["results_key"]
    # the stored inertia is the perturbation of the base inertia by the stored parameters
    base = parse_sweep(yaml.safe_load(cfg.read_text())).bases[0].config.inertia.matrix()
    for i in range(6):
        f = {k: a["parameters"][k][i] for k in a["parameters"]}
        np.testing.assert_allclose(a["inertia"][i], perturb_inertia(base, f), rtol=1e-15)
        assert unphysical_reason(a["inertia"][i]) is None
    # margin: the reported limit is bounded and the first failure (when found) is not
    for key, m in a["margin"].items():
        v = dict(zip(m["evaluated_s"], m["evaluated_verdict"]))
        assert v[m["limit"]] == b"bounded"
        if np.isfinite(m["first_failure"]):
            assert v[m["first_failure"]] != b"bounded"


class _Kill(Exception):
    pass


def test_interrupted_then_resumed_equals_uninterrupted(tmp_path):
    cfg = _sweep_yaml(tmp_path, "resume", n_runs=8)
    ref = read_h5(run_sweep(cfg, workers=1).path)

    def boom(n):
        if n == 3:
            raise _Kill
    with pytest.raises(_Kill):
        run_sweep(cfg, workers=1, after_record=boom)
    part = read_h5(tmp_path / "runs" / "resume" / "sweep.h5")
    assert not part["attrs"]["complete"] and part["attrs"]["n_cases_done"] == 3
    # a torn line left by a killed writer is ignored on resume
    with open(tmp_path / "runs" / "resume" / "sweep.journal", "a") as f:
        f.write('{"kind": "case", "base": "ac", "ind')
    r = run_sweep(cfg, workers=1, resume=True)
    assert r.n_resumed == 3 and r.n_new == 5
    _assert_same_data(ref, read_h5(r.path))
    # resuming a complete sweep runs nothing
    assert run_sweep(cfg, workers=1, resume=True).n_new == 0


def test_sigkill_then_resume_equals_uninterrupted(tmp_path):
    cfg = _sweep_yaml(tmp_path, "killed", n_runs=16, orbits=40.0)
    journal = tmp_path / "runs" / "killed" / "sweep.journal"
    proc = subprocess.Popen([sys.executable, "-c", "from acmm.cli.app import main; main()", "sweep", str(cfg),
                             "--workers", "1"], cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "MPLBACKEND": "Agg"})
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.exists() and journal.read_text().count('"kind": "case"') >= 3:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(10) == -signal.SIGKILL, "the sweep finished before it could be killed"
    n_before = journal.read_text().count('"kind": "case"')
    assert 3 <= n_before < 16
    r = run_sweep(cfg, workers=2, resume=True)
    assert r.n_resumed == n_before and r.n_new == 16 - n_before
    resumed = read_h5(r.path)
    os.replace(r.path, tmp_path / "resumed.h5")
    _assert_same_data(read_h5(run_sweep(cfg, workers=1).path), resumed)


def test_resume_refuses_a_journal_of_another_config(tmp_path):
    run_sweep(_sweep_yaml(tmp_path, "other", n_runs=2), workers=1)
    with pytest.raises(ConfigError, match=r"different sweep configuration.*\(changed since: sweep\.seed: \d+ → 12\)$"):
        run_sweep(_sweep_yaml(tmp_path, "other", n_runs=2, seed=12), workers=1, resume=True)


@pytest.mark.parametrize("section, a, b", [
    ("grid", {"dI11": [-0.05, 0.05], "bias_pitch": [-1.0, 1.0]}, {"bias_pitch": [-1.0, 1.0], "dI11": [-0.05, 0.05]}),
    ("monte_carlo", {"inertia": {"percent": 10}, "bias_pitch": {"uniform": [-1, 1]}},
     {"bias_pitch": {"uniform": [-1, 1]}, "inertia": {"percent": 10}})])
def test_resume_refuses_a_journal_whose_parameters_came_in_another_order(tmp_path, section, a, b):
    """The order of the parameters decides which values case i gets (the grid's product, the
    draws), but the results key hashed the config with sorted keys: resuming one order's journal
    with the other mixed the cases without a word (a review: one grid point twice, one never)."""
    over = {"monte_carlo": None, "n_runs": None} if section == "grid" else {"n_runs": 2}
    sa, sb = (load_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: x})) for x in (a, b))
    values = [[case_values(sw.spec, i, sw.bases[0].config.inertia.matrix()[None])[0] for i in range(2)]
              for sw in (sa, sb)]
    assert values[0] != values[1]                     # the orders give case 0 and 1 other values
    assert sa.results_key() != sb.results_key()
    run_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: a}), workers=1)
    with pytest.raises(ConfigError, match="different sweep configuration"):
        run_sweep(_sweep_yaml(tmp_path, "ord", False, **{**over, section: b}), workers=1, resume=True)


def test_resume_refuses_a_journal_of_an_earlier_case_model(tmp_path, monkeypatch):
    # a journal written before cases started at the design TEA's equilibrium (case model 1) must
    # not be completed with rows of the current model
    import acmm.sweep.config as sweep_config

    cfg = _sweep_yaml(tmp_path, "model", n_runs=2)
    monkeypatch.setattr(sweep_config, "CASE_MODEL", 1)
    run_sweep(cfg, workers=1)
    monkeypatch.setattr(sweep_config, "CASE_MODEL", 2)
    with pytest.raises(ConfigError, match="computed cases differently"):
        run_sweep(cfg, workers=1, resume=True)


def test_dask_local_cluster_gives_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed", reason="optional extra acmm-qpp[dask] not installed")
    cfg = _sweep_yaml(tmp_path, "dask", n_runs=4)
    ref = read_h5(run_sweep(cfg, workers=1).path)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        r = run_sweep(cfg, scheduler=cluster.scheduler_address)
    _assert_same_data(ref, read_h5(r.path))


def test_background_snapshots_same_table_and_errors_reach_the_caller(tmp_path, monkeypatch):
    import threading

    import acmm.sweep.run as run
    from acmm.sweep import output as sweep_output
    from acmm_qpp.errors import OutputError

    cfg = _cfg(tmp_path, "snaps")
    ref, ref_csv = _run_bytes(cfg, workers=1)
    real = sweep_output.write_results
    calls = []

    def spy(sweep, records, complete, **kw):
        calls.append((complete, len(records), threading.current_thread().name))
        return real(sweep, records, complete, **kw)

    monkeypatch.setattr(run, "write_results", spy)
    got, csv = _run_bytes(cfg, workers=1, chunk=1, snapshot_interval=0.0)
    _assert_same_data(ref, got)
    assert csv == ref_csv
    partial = [c for c in calls if not c[0]]
    assert partial and all(name == "acmm-sweep-snapshot" for _, _, name in partial)   # beside the driver
    assert calls[-1][:2] == (True, 9)                                                # then the final table
    assert all(n < 9 for _, n, _ in partial)

    def failing(sweep, records, complete, **kw):
        if threading.current_thread().name == "acmm-sweep-snapshot":
            raise OutputError("cannot write sweep.h5: No space left on device")
        return real(sweep, records, complete, **kw)

    monkeypatch.setattr(run, "write_results", failing)
    with pytest.raises(OutputError, match="No space left"):
        run_sweep(cfg, workers=1, chunk=1, snapshot_interval=0.0)


# ---------------------------------------------------------------------------------------------
# sweep worker processes (issue 16)
# ---------------------------------------------------------------------------------------------
_PROBE = r"""
import resource, sys
import numpy as np
from acmm.sweep.run import _restore_heap_reuse

def faults():
    r0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(200):                       # a case's short-lived 1 MiB arrays, touched and freed
        a = np.empty(1 << 17)
        a[:] = 1.0
        del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0

before = faults()
changed = _restore_heap_reuse()
after = faults()
print(before, int(changed), after)
"""


def _run(env_extra):
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.update(env_extra)
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, check=True)
    return [int(x) for x in out.stdout.split()]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc mallopt")
def test_heap_reuse_restored_under_dask_trim_threshold():
    # the environment a Dask nanny gives its workers: every 1 MiB array is mmapped and faulted
    # in afresh (256 pages each), until the fixed mmap threshold serves it from the heap
    before, changed, after = _run({"MALLOC_TRIM_THRESHOLD_": "65536"})
    assert changed == 1
    assert before > 200 * 200
    assert after < 0.05 * before


def test_heap_reuse_untouched_without_the_trim_variable():
    # glibc's dynamic threshold is on: nothing to restore, malloc left alone
    before, changed, after = _run({})
    assert changed == 0
    assert after < 0.05 * 200 * 256


def test_heap_setting_only_in_dask_worker_processes():
    # the driver and pool processes keep the user's own MALLOC_* choice; a Dask worker (also in
    # ``client.run``, where no task is running) gets the heap reuse back
    from acmm.sweep.run import _in_dask_worker

    # a fresh process (this one may still hold in-process workers of earlier tests)
    out = subprocess.run([sys.executable, "-c", "import distributed\nfrom acmm.sweep.run import "
                          "_in_dask_worker as f\nprint(f())"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        assert list(client.run(_in_dask_worker).values()) == [True]
        assert client.submit(_in_dask_worker, pure=False).result() is True


# ---------------------------------------------------------------------------------------------
# a lost worker, a repeated interrupt, a cluster running other code (a review)
# ---------------------------------------------------------------------------------------------
_BIG = ["sweep", "sweep_inertia30", "sweep.n_runs=600", "sweep.orbits=3", "--no-figures", "-j", "2"]


def _start_sweep(tmp_path):

    env = {**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "Agg",
           "OPENBLAS_NUM_THREADS": "1"}
    p = subprocess.Popen([sys.executable, "-m", "acmm.cli.app", *_BIG], cwd=tmp_path, env=env, text=True,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    journal = tmp_path / "runs" / "sweep_inertia30" / "sweep.journal"
    import time

    t0 = time.monotonic()
    while time.monotonic() - t0 < 120 and p.poll() is None:      # cases are coming back
        if journal.exists() and journal.read_text().count("\n") >= 3:
            break
        time.sleep(0.02)
    assert p.poll() is None, p.stderr.read()
    return p, env, journal


def _children(pid):
    with open(f"/proc/{pid}/task/{pid}/children") as f:
        return [int(x) for x in f.read().split()]


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc, fork")
def test_a_killed_pool_worker_is_one_line_and_the_sweep_resumes(tmp_path):
    """It was a 93-line BrokenProcessPool traceback with exit 1 (the code of --strict)."""
    import signal

    p, env, journal = _start_sweep(tmp_path)
    os.kill(_children(p.pid)[0], signal.SIGKILL)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 4, err
    assert err.strip().splitlines() == ["error: a sweep worker process died (killed, or out of memory); the "
                                        "finished cases are kept in the journal: run the sweep again with --resume"]
    again = subprocess.run([sys.executable, "-m", "acmm.cli.app", *_BIG, "--resume"], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=300, check=False)
    assert again.returncode == 0, again.stderr
    import json

    records = [json.loads(line) for line in journal.read_text().splitlines()[1:]]
    cases = [(r["base"], r["index"]) for r in records if r["kind"] == "case"]
    assert len(cases) == len(set(cases)) == 2 * 600                # each base's cases, once


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="process groups")
@pytest.mark.parametrize("gap", [0.0, 0.05])
def test_a_second_ctrl_c_does_not_hang_the_sweep(tmp_path, gap):
    """Ctrl-C twice to the terminal's process group (the driver and its pool): the second one broke
    the pool's shutdown and the sweep hung in multiprocessing's exit handler (a review)."""
    import signal
    import time

    p, _, _ = _start_sweep(tmp_path)
    os.killpg(p.pid, signal.SIGINT)
    time.sleep(gap)
    os.killpg(p.pid, signal.SIGINT)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        raise
    assert p.returncode == 130 and err.strip() == "interrupted", err


def test_a_dask_worker_running_other_code_is_refused():
    from acmm.sweep.run import _call_chunk, code_identity

    with pytest.raises(ConfigError, match="--scheduler: a Dask worker runs other acmm code"):
        _call_chunk([], None, "0.0.0+000000000000")         # before anything else of the chunk
    # (the same code passes: every Dask sweep above)
    assert len(code_identity().rsplit("+", 1)[1]) == 12


@pytest.mark.parametrize("address", ["tls://127.0.0.1:1", "ucx://127.0.0.1:1"])
def test_a_scheduler_address_dask_cannot_use_is_one_line(address):
    pytest.importorskip("distributed")
    from acmm.sweep.run import _make_executor

    with pytest.raises(ConfigError, match=f"--scheduler: cannot connect to the Dask scheduler at {address}"):
        _make_executor(0, address)


# ---------------------------------------------------------------------------------------------
# sweep tasks in chunks (issue 16): the chunk sizes, and tables that do not depend on them
# ---------------------------------------------------------------------------------------------

def test_chunk_size_and_chunks():
    assert _chunk_size(1000, 1) == 64                      # one worker process: still amortized
    assert _chunk_size(10, 2) == 1
    assert _chunk_size(3200, 2) == 64 == MAX_CHUNK
    assert _chunk_size(3200, 16) == 25                     # 8 tasks per worker
    tasks = [("case", "a", i) for i in range(5)] + [("case", "b", i) for i in range(3)] + \
        [("margin", "a", "up"), ("margin", "a", "down")]
    chunks = list(iter(_Chunker(tasks, 2, size=2).next, None))      # handed out lazily
    assert [len(c) for c in chunks] == [2, 2, 1, 2, 1, 1, 1]          # a base's cases together, each margin alone
    assert [t for c in chunks for t in c] == tasks        # order kept, nothing lost
    assert all(len({t[1] for t in c}) == 1 for c in chunks)


def test_chunk_size_with_a_measured_case_cost():
    # 3.5 ms per case: tasks of 0.1 … 1 s are 29 … 285 cases
    lo, hi = -(-MIN_TASK_SECONDS // 0.0035), MAX_TASK_SECONDS // 0.0035
    assert (lo, hi) == (29, 285)
    assert _chunk_size(3200, 2, 0.0035) == 200                     # 8 per worker, within the bounds
    assert _chunk_size(3200, 16, 0.0035) == 29                     # 8 per worker would be 25: too little work
    assert _chunk_size(10 ** 6, 100, 0.0035) == 285                # 8 per worker would be 1250: too long
    assert _chunk_size(100, 16, 0.0035) == 7                       # every worker still gets a share
    assert _chunk_size(40, 2, 0.0035, n_total=3200) == 29          # the tail of a large sweep: ≥ 0.1 s
    assert _chunk_size(400, 2, 0.09) == 11                         # redesign cases: 25 would be 2.3 s
    assert _chunk_size(5, 2, 10.0) == 1


def test_chunker_guided_sizes_and_measure(monkeypatch):
    import acmm.sweep.run as ex

    clock = [100.0]
    monkeypatch.setattr(ex.time, "monotonic", lambda: clock[0])
    tasks = [("case", "a", i) for i in range(3200)] + [("margin", "a", "up")]
    ch = _Chunker(tasks, 2)
    sizes = []
    first = [ch.next(), ch.next()]
    assert [len(c) for c in first] == [64, 64]                   # unmeasured: MAX_CHUNK
    assert ch.case_seconds() is None
    ch.returned(64)                                              # the first chunk back starts the clock
    clock[0] += 0.112
    ch.returned(64)
    assert ch.case_seconds() is None                             # one chunk per worker needed since
    clock[0] += 0.112
    ch.returned(64)
    assert ch.case_seconds() == pytest.approx(0.0035)              # 2 workers × 0.224 s / 128 cases
    while (c := ch.next()) is not None:
        sizes.append(len(c))
    assert sizes[0] == _chunk_size(3200 - 128 + 1, 2, 0.0035) == 193
    assert sizes == sorted(sizes, reverse=True)                  # guided: shrinking towards the end
    assert min(sizes[:-2]) == 29 and sizes[-1] == 1              # ≥ 0.1 s of work; the margin search alone
    assert len(sizes) < 50                                       # 25 per worker with 64 per task
    assert sum(sizes) + 128 == len(tasks)


def test_pool_chunked_unchunked_and_serial_identical(tmp_path):
    cfg = _cfg(tmp_path)
    ref, ref_csv = _run_bytes(cfg, workers=1)
    for chunk in (1, 3):
        got, csv = _run_bytes(cfg, workers=2, chunk=chunk)
        _assert_same_data(ref, got)
        assert csv == ref_csv
        assert got["margin"].keys() == ref["margin"].keys()
        for k in ref["margin"]:
            assert got["margin"][k]["limit"] == ref["margin"][k]["limit"]


def test_dask_chunked_identical(tmp_path):
    distributed = pytest.importorskip("distributed", reason="optional extra acmm-qpp[dask] not installed")
    cfg = _cfg(tmp_path, "dask_chunks", n_runs=5)
    ref, ref_csv = _run_bytes(cfg, workers=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        got, csv = _run_bytes(cfg, scheduler=cluster.scheduler_address, chunk=2)
    _assert_same_data(ref, got)
    assert csv == ref_csv


def test_chunk_sizes_and_a_process_cluster_identical(tmp_path):
    # chunks of 7 and 64 cases and guided chunks on a pool; 1 case per task and guided chunks on
    # a Dask cluster of a spawned worker process (the workers users run: read-only scattered
    # arrays, Dask's malloc environment): all the same table, bit for bit
    distributed = pytest.importorskip("distributed", reason="optional extra acmm-qpp[dask] not installed")
    cfg = _cfg(tmp_path, "sizes")
    ref, ref_csv = _run_bytes(cfg, workers=1)
    runs = [_run_bytes(cfg, workers=2, chunk=chunk) for chunk in (7, 64, None)]
    import dask

    from acmm.sweep.dask_settings import DASK_SETTINGS

    # the cluster under the recommended settings (docs/howto/sweeps.md, "A Dask cluster for sweeps"): in force in the spawned
    # worker, and the table unchanged
    with dask.config.set(DASK_SETTINGS), distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            seen = client.run(lambda: {k: dask.config.get(k) for k in DASK_SETTINGS})
        assert list(seen.values()) == [DASK_SETTINGS]
        runs += [_run_bytes(cfg, scheduler=cluster.scheduler_address, chunk=chunk) for chunk in (1, None)]
    for got, csv in runs:
        _assert_same_data(ref, got)
        assert csv == ref_csv
