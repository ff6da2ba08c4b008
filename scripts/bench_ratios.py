"""`make bench`, issue 16: the ratios that matter, in one run (printed, never asserted).

1. one 10-orbit Monte Carlo case over the bare 10-orbit integration of the same plant (≤ 3x);
2. the same seeded sweep on 1 vs N local worker processes (≥ 1.8x at N = 2 when idle);
3. a Dask LocalCluster of N single-threaded workers vs the local pool at the same N (≤ 1.15x),
   with the CPU time of each run (driver + workers) and the load average beside it;
4. `acmm simulate staircase` and `acmm design staircase` with figures vs without (≤ 1.5 s with);
5. `acmm report --fast` (and the full report with ``--full``): wall time per section.

    MPLBACKEND=Agg .venv/bin/python scripts/bench_ratios.py [--workers 2] [--cases 3200] [--full]

The machine's load average is printed with each block: on a shared machine compare ratios.
``scripts/bench_scaling.py`` prints the scaling table for any list of N (bigger machines).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

sys.path.insert(0, str(Path(__file__).resolve().parent))
BIN = Path(sys.executable).parent


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs"


def _wall(cmd, cwd, repeat=3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, cwd=cwd, check=True, capture_output=True)
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--cases", type=int, default=3200,
                    help="sweep size of blocks 2-3 (the Dask overhead shows at a few thousand cases)")
    ap.add_argument("--full", action="store_true", help="also the full report (~20 s or more)")
    args = ap.parse_args()
    from bench_scaling import per_case_cost, scaling

    print(f"issue 16 benchmarks ({_load()}; best of repeats)")
    c, b = per_case_cost("mb3", 10.0)
    print(f"1. MC case {c * 1e3:.2f} ms / bare 10-orbit integration {b * 1e3:.2f} ms = {c / b:.2f}x  "
          f"(target <= 3x)")
    print(f"2./3. {args.cases}-case ±30 % MB3 Monte Carlo, 1 vs {args.workers} workers, pool vs Dask ({_load()}):")
    scaling(sorted({1, args.workers}), args.cases, "mb3", 10.0, out=lambda s: print("   " + s))
    print(f"4. stair-case CLI, wall time ({_load()}):")
    with tempfile.TemporaryDirectory() as tmp:
        acmm = str(BIN / "acmm")
        subprocess.run([acmm, "simulate", "staircase"], cwd=tmp, check=True, capture_output=True)
        for stage in ("simulate", "design"):
            with_f = _wall([acmm, stage, "staircase"], tmp)
            without = _wall([acmm, stage, "staircase", "--no-figures"], tmp)
            print(f"   acmm {stage:<8} staircase: with figures {with_f:5.2f} s, without {without:5.2f} s "
                  f"(figures {with_f - without:+.2f} s; target with figures <= 1.5 s)")
    from report import build_report

    for fast in ([True, False] if args.full else [True]):
        with tempfile.TemporaryDirectory() as tmp:
            r = build_report(Path(tmp) / "report", fast=fast, root=Path(tmp))
            print(f"5. acmm report{' --fast' if fast else ''}: {r.wall_time:.1f} s from scratch "
                  f"(target {'10' if fast else '20'} s; {_load()}); per part:")
            for k, v in r.timings.items():
                print(f"   {k:<28} {v:6.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
