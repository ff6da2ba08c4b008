"""The note on numba's first compile of the simulator, for the ``acmm`` commands (stderr)."""
from __future__ import annotations

import sys
from pathlib import Path

from acmm.model.compiled_cache import uncached_note
from acmm.simulate import kernel
from acmm_qpp.cli.progress import console, enabled


def _numba_needs_compile() -> bool:
    """True when the compiled simulator is neither loaded in this process nor in numba's on-disk
    cache (first run, or the source changed since the cache was written); False also when numba's
    internals cannot be read."""
    try:
        disp = kernel._integrate
        if disp.signatures:
            return False
        index = Path(disp._cache._cache_file._index_path)
        src = Path(kernel.__file__)
        return not index.exists() or index.stat().st_mtime < src.stat().st_mtime
    except Exception:  # noqa: BLE001 — numba internals moved: say nothing rather than fail
        return False


def announce_numba_compile() -> None:
    """Announce numba's first compile of the simulator (~8–12 s, cached afterwards); say always
    (progress or not) when numba has no cache folder, so that every run compiles (the kernels,
    imported with this module, are defined: whether they are cached is known)."""
    why = uncached_note()
    if why is not None:
        print(f"note: {why}", file=sys.stderr, flush=True)
        return
    if enabled() and _numba_needs_compile():
        console().print("compiling the closed-loop simulator with numba (first run only, ~10 s; cached afterwards) ...",
                        markup=False, highlight=False)
