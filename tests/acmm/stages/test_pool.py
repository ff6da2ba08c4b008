"""The one local process pool (:mod:`acmm.stages.pool`): its workers die with their parent."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from tests.conftest import REPO as ROOT

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals, Linux prctl")


ENV = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}


def test_a_pool_worker_dies_with_its_parent_even_under_sigkill(tmp_path):
    """The workers of :func:`acmm.stages.pool.process_pool` (the sweep's, the report's) are stopped
    when their parent is killed with SIGKILL, where no cleanup of the parent runs."""
    code = textwrap.dedent("""
        import os, sys
        from acmm.stages.pool import process_pool
        pool = process_pool(1)
        print(pool.submit(os.getpid).result(), flush=True)
        sys.stdin.readline()
    """)
    proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            text=True, env=ENV)
    worker = int(proc.stdout.readline())
    proc.kill()
    proc.wait(timeout=30)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:          # waits for the kernel's SIGKILL of the worker
        try:                            # gone, or a zombie waiting for its new parent to reap it
            if Path(f"/proc/{worker}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
                return
        except (FileNotFoundError, ProcessLookupError):
            return
        time.sleep(0.02)
    os.kill(worker, signal.SIGKILL)
    pytest.fail("the pool worker outlived its parent")
