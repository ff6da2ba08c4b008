"""Compile the numba kernels ahead of time (``python -m acmm.simulate.warmup``; run by ``make install``).

The compiled Dormand–Prince closed loop (:mod:`acmm.simulate.kernel`) and the compiled TEA continuation
(:mod:`acmm.model.tea`) are cached by numba (``cache=True``) in ``__pycache__`` beside the
sources (or numba's user cache directory when that is not writable), so the first ``acmm simulate``
after install loads machine code instead of compiling it (~10 s).  Prints what it does.
"""
from __future__ import annotations

import time
import numpy as np
from acmm.simulate import kernel, scenario
from acmm.model import tea
from acmm.model.compiled_cache import uncached_note, write_error_notes


def warm_up() -> float:
    """Compile (or load) every numba kernel; returns the wall time (s).

    Returns
    -------
    float
        Wall time of the warm-up, s.
    """
    t0 = time.perf_counter()
    tea.warm_up()
    n = 0.0011
    inertia = np.diag([2.0e7, 1.0e6, 2.1e7])[None]
    sc = scenario.Scenario(level_start=np.zeros(1), inertia=inertia, bias=np.zeros((1, 3)), theta_est=np.zeros((1, 3)),
                         gain=np.zeros((1, 3, 24)), harmonic_a=np.zeros(3), harmonic_b=np.zeros(3), n=n,
                         torque_limit=100.0, momentum_limit=1e4, drf_mode="attitude_hold", t_end=600.0,
                         sample_times=np.array([0.0, 300.0, 600.0]), x0=np.zeros(24), rtol=1e-8,
                         atol=scenario.plain_scales(n, "attitude_hold") * 1e-8, divergence=1.0, max_saturation=1e4)
    kernel.simulate(sc)
    kernel.kernel_rhs(sc, 0.0, np.zeros(24))
    return time.perf_counter() - t0


def main() -> int:
    """``python -m acmm.simulate.warmup``: warm up and print the time taken.

    Returns
    -------
    int
        Exit code 0.
    """
    why = uncached_note()
    if why is not None:
        print(f"acmm: nothing compiled ahead: {why}")
        return 0
    print("acmm: compiling the numba kernels (simulator, TEA continuation) into the cache "
          "— one time, ~20–60 s, longer on a busy machine ... ", end="", flush=True)
    dt = warm_up()
    print(f"done in {dt:.1f} s")
    for line in write_error_notes():
        print(f"acmm: note: {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
