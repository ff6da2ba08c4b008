"""Throughput of ``acmm sweep`` (issue 7): a 200-case ±30 % inertia Monte Carlo of 10-orbit MB3
runs (fixed nominal design), with 1 worker (in-process) and 2 worker processes.

    MPLBACKEND=Agg .venv/bin/python scripts/bench_sweep.py [--cases 200] [--base mb3] [--orbits 10]

Prints the wall time of each (design, warm-up, all cases, writing sweep.h5/csv; no figures),
the speed-up from 1 to 2 workers, and checks that both runs produced identical tables.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--base", default="mb3")
    ap.add_argument("--orbits", type=float, default=10.0)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()

    from acmm_qpp.results import read_h5
    from acmm.sweep.run import run_sweep
    from acmm.sweep.config import parse_sweep

    tmp = Path(tempfile.mkdtemp(prefix="bench_sweep_"))
    spec = {"base": args.base, "monte_carlo": {"inertia": {"percent": 30}}, "n_runs": args.cases,
            "seed": 185644, "design": "fixed", "orbits": args.orbits}
    print(f"{args.cases}-case ±30 % inertia Monte Carlo, {args.base}, {args.orbits:g}-orbit runs, "
          f"fixed design; {os.cpu_count()} CPU(s)")
    times, tables = {}, {}
    for w in args.workers:
        sw = parse_sweep({"name": f"bench_w{w}", "sweep": spec, "output": {"root": str(tmp), "figures": False}})
        t0 = time.perf_counter()
        r = run_sweep(sw, workers=w)
        times[w] = time.perf_counter() - t0
        tables[w] = read_h5(r.path)
        s = r.summary()[sw.bases[0].label]
        print(f"  workers={w}: {times[w]:6.2f} s wall  ({args.cases / times[w]:.1f} cases/s; "
              f"{s['bounded']}/{s['total']} bounded)")
    ws = sorted(times)
    for w in ws[1:]:
        print(f"  speed-up {ws[0]} -> {w} workers: {times[ws[0]] / times[w]:.2f}x")
    ref = tables[ws[0]]
    same = all(np.array_equal(ref[k], tables[w][k], equal_nan=ref[k].dtype.kind == "f")
               for w in ws[1:] for k in ("verdict", "peak_attitude_error", "peak_momentum", "time_to_divergence"))
    print(f"  identical tables across worker counts: {same}")


if __name__ == "__main__":
    main()
