"""Sweep worker processes (issue 16): heap reuse restored where Dask's worker environment stops it."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

_PROBE = r"""
import resource, sys
import numpy as np
from acmm.sweep.executors import _restore_heap_reuse

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
    from acmm.sweep.executors import _in_dask_worker

    # a fresh process (this one may still hold in-process workers of earlier tests)
    out = subprocess.run([sys.executable, "-c", "import distributed\nfrom acmm.sweep.executors import "
                          "_in_dask_worker as f\nprint(f())"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        assert list(client.run(_in_dask_worker).values()) == [True]
        assert client.submit(_in_dask_worker, pure=False).result() is True
