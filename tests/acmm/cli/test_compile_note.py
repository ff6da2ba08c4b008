"""The note on numba's first compile (acmm.cli.compile_note._numba_needs_compile)."""
from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace


def test_numba_compile_detection_says_whether_the_first_call_compiles(tmp_path, monkeypatch):
    """True exactly when the simulator is neither compiled in this process nor in numba's cache (no
    index, or one older than the source); False once compiled here, and False (saying nothing)
    when numba's internals cannot be read.  (It was ``in (True, False)``: a test that cannot fail.)"""
    import acmm.simulate.kernel as sim_mod
    from acmm.cli.compile_note import _numba_needs_compile as numba_needs_compile
    from acmm.model.compiled_cache import UNCACHED

    real = sim_mod._integrate
    if "_integrate" not in UNCACHED:            # the internals it reads are those of this numba
        assert Path(real._cache._cache_file._index_path).suffix == ".nbi"
    index = tmp_path / "kernel._integrate.nbi"

    def dispatcher(signatures):
        return SimpleNamespace(signatures=signatures,
                               _cache=SimpleNamespace(_cache_file=SimpleNamespace(_index_path=str(index))))

    monkeypatch.setattr(sim_mod, "_integrate", dispatcher([]))
    assert numba_needs_compile() is True                    # no cache index: the first call compiles
    index.write_bytes(b"")
    source = os.stat(sim_mod.__file__).st_mtime
    os.utime(index, (source + 10, source + 10))
    assert numba_needs_compile() is False                   # cached after the source last changed
    os.utime(index, (source - 10, source - 10))
    assert numba_needs_compile() is True                    # the source changed since: compiles again
    monkeypatch.setattr(sim_mod, "_integrate", dispatcher(["(float64[:],)"]))
    assert numba_needs_compile() is False                   # already compiled in this process
    monkeypatch.setattr(sim_mod, "_integrate", SimpleNamespace(signatures=[]))
    assert numba_needs_compile() is False                   # numba's internals moved: no note
