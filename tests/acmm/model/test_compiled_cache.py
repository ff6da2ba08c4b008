"""The compiled kernels where numba cannot cache them (acmm.model.compiled_cache): a read-only install
for a user without a home crashed at import with numba's "no locator available" traceback, and a
full disk under NUMBA_CACHE_DIR failed the run with "I/O error: No space left on device"."""
from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap

import numba.core.caching as numba_caching
import pytest

from acmm.model import compiled_cache

from tests.conftest import REPO as ROOT

KERNEL = textwrap.dedent("""
    from acmm.model.compiled_cache import njit_cached

    @njit_cached()
    def plus_one(x):
        return x + 1.0
""")


def _kernel_module(tmp_path, name):
    (tmp_path / f"{name}.py").write_text(KERNEL)
    sys.path.insert(0, str(tmp_path))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop(name, None)


def test_without_a_cache_folder_the_kernel_is_compiled_uncached(tmp_path, monkeypatch):
    monkeypatch.setattr(numba_caching.CacheImpl, "_locator_classes", [])
    monkeypatch.setattr(compiled_cache, "UNCACHED", [])
    mod = _kernel_module(tmp_path, "kernel_without_cache")
    assert mod.plus_one(1.5) == 2.5
    assert compiled_cache.UNCACHED == ["plus_one"]
    assert "NUMBA_CACHE_DIR" in compiled_cache.uncached_note()


def test_a_cache_that_cannot_be_written_leaves_the_kernel_running(tmp_path, monkeypatch):
    """numba writes the index, then the machine code; the disk fills up in between: the run
    goes on with a note, and the next process, finding an index entry without its data, compiles
    and saves again (numba treats the missing file as a miss)."""
    monkeypatch.setattr(compiled_cache, "CACHE_WRITE_ERRORS", [])
    mod = _kernel_module(tmp_path, "kernel_disk_full")
    cache_file = mod.plus_one._cache._cache_file

    def disk_full(name, data):
        raise OSError(28, "No space left on device")

    cache_file._save_data = disk_full
    assert mod.plus_one(2.0) == 3.0
    notes = compiled_cache.write_error_notes()
    assert len(notes) == 1 and "No space left on device" in notes[0]
    cache = tmp_path / "__pycache__"
    assert list(cache.glob("kernel_disk_full.plus_one-*.nbi")) and not list(cache.glob("*.nbc"))
    again = _kernel_module(tmp_path, "kernel_disk_full")          # a later run: a fresh dispatcher
    assert again.plus_one(4.0) == 5.0
    assert list(cache.glob("kernel_disk_full.plus_one-*.nbc")) and len(compiled_cache.CACHE_WRITE_ERRORS) == 1


@pytest.mark.slow
def test_acmm_simulate_without_a_cache_folder_runs_and_says_why_it_compiles(tmp_path):
    """End to end, numba's cache locators all refusing (as on a read-only install whose user
    has no home): the run succeeds and one note says why every run compiles."""
    script = ("import numba.core.caching as c\nc.CacheImpl._locator_classes = []\n"
              "from acmm.cli.app import main\nmain()\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", script, "simulate", "mb3", "simulation.orbits=0.2",
                           "--no-figures"], cwd=tmp_path, capture_output=True, text=True, env=env,
                          timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("note: numba has no writable folder") == 1, done.stderr
    assert "Traceback" not in done.stderr and (tmp_path / "runs" / "mb3" / "sim.h5").exists()
    warm = subprocess.run([sys.executable, "-c", script.replace("from acmm.cli.app import main\nmain()",
                                                                "from acmm.simulate.warmup import main\nmain()")],
                          cwd=tmp_path, capture_output=True, text=True, env=env, timeout=120, check=False)
    assert warm.returncode == 0 and "nothing compiled ahead" in warm.stdout, warm.stdout + warm.stderr
