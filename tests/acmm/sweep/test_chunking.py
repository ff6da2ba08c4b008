"""Sweep tasks in chunks (acmm.sweep.chunking, issue 16): the chunk sizes, and tables that do not
depend on chunking or executor."""
from __future__ import annotations

import pytest

from acmm.sweep.chunking import MAX_CHUNK, MAX_TASK_SECONDS, MIN_TASK_SECONDS, Chunker, chunk_size

from tests.acmm.sweep.conftest import _assert_same_data, _cfg, _run_bytes


def test_chunk_size_and_chunks():
    assert chunk_size(1000, 1) == 64                      # one worker process: still amortized
    assert chunk_size(10, 2) == 1
    assert chunk_size(3200, 2) == 64 == MAX_CHUNK
    assert chunk_size(3200, 16) == 25                     # 8 tasks per worker
    tasks = [("case", "a", i) for i in range(5)] + [("case", "b", i) for i in range(3)] + \
        [("margin", "a", "up"), ("margin", "a", "down")]
    chunks = list(iter(Chunker(tasks, 2, size=2).next, None))      # handed out lazily
    assert [len(c) for c in chunks] == [2, 2, 1, 2, 1, 1, 1]          # a base's cases together, each margin alone
    assert [t for c in chunks for t in c] == tasks        # order kept, nothing lost
    assert all(len({t[1] for t in c}) == 1 for c in chunks)


def test_chunk_size_with_a_measured_case_cost():
    # 3.5 ms per case: tasks of 0.1 … 1 s are 29 … 285 cases
    lo, hi = -(-MIN_TASK_SECONDS // 0.0035), MAX_TASK_SECONDS // 0.0035
    assert (lo, hi) == (29, 285)
    assert chunk_size(3200, 2, 0.0035) == 200                     # 8 per worker, within the bounds
    assert chunk_size(3200, 16, 0.0035) == 29                     # 8 per worker would be 25: too little work
    assert chunk_size(10 ** 6, 100, 0.0035) == 285                # 8 per worker would be 1250: too long
    assert chunk_size(100, 16, 0.0035) == 7                       # every worker still gets a share
    assert chunk_size(40, 2, 0.0035, n_total=3200) == 29          # the tail of a large sweep: ≥ 0.1 s
    assert chunk_size(400, 2, 0.09) == 11                         # redesign cases: 25 would be 2.3 s
    assert chunk_size(5, 2, 10.0) == 1


def test_chunker_guided_sizes_and_measure(monkeypatch):
    import acmm.sweep.chunking as ex

    clock = [100.0]
    monkeypatch.setattr(ex.time, "monotonic", lambda: clock[0])
    tasks = [("case", "a", i) for i in range(3200)] + [("margin", "a", "up")]
    ch = Chunker(tasks, 2)
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
    assert sizes[0] == chunk_size(3200 - 128 + 1, 2, 0.0035) == 193
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
