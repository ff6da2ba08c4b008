"""Sweep worker processes (issue 16): heap reuse restored where Dask's worker environment stops it."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.conftest import REPO

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
    from acmm.sweep.executors import call_chunk, same_code
    from acmm_qpp.errors import ConfigError
    from acmm.sweep.executors import code_identity

    with pytest.raises(ConfigError, match="--scheduler: a Dask worker runs other acmm code"):
        call_chunk([], None, "0.0.0+000000000000")         # before anything else of the chunk
    same_code(code_identity())
    assert len(code_identity().rsplit("+", 1)[1]) == 12


@pytest.mark.parametrize("address", ["tls://127.0.0.1:1", "ucx://127.0.0.1:1"])
def test_a_scheduler_address_dask_cannot_use_is_one_line(address):
    pytest.importorskip("distributed")
    from acmm.sweep.executors import make_executor
    from acmm_qpp.errors import ConfigError

    with pytest.raises(ConfigError, match=f"--scheduler: cannot connect to the Dask scheduler at {address}"):
        make_executor(0, address)
