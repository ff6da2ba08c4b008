"""`make bench`, issue 16: the ratios that matter, in one run (printed, never asserted).

1. one 10-orbit Monte Carlo case over the bare 10-orbit integration of the same plant (≤ 3x);
2. the same seeded sweep on 1 vs N local worker processes (≥ 1.8x at N = 2 when idle);
3. a Dask LocalCluster of N single-threaded workers vs the local pool at the same N (≤ 1.15x),
   with Dask's default configuration and with ``acmm.sweep.dask_settings.DASK_SETTINGS``, with
   the CPU time of each run (driver + workers) and the load average beside it;
4. `acmm simulate staircase` and `acmm design staircase` on the report's route (`design.pole_method=shift schedule.refine_points=0`)
   with figures vs without (≤ 1.5 s with);
5. `acmm report --fast` (and the full report with ``--full``): wall and CPU time from a fresh results
   root and again reusing its stage results, per section and per stage (reusing: ≤ 10 s fast, ≤ 20 s full;
   fresh, the stair-case's LMI points take minutes).

    MPLBACKEND=Agg .venv/bin/python scripts/bench_ratios.py [--workers 2] [--cases 3200] [--full]
        [--report-jobs 1 2] [--only-report]

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
    ap.add_argument("--report-jobs", type=int, nargs="+", default=[None],
                    help="report processes to compare (default: the report's default, 2 on 2+ CPUs)")
    ap.add_argument("--only-report", action="store_true", help="block 5 only")
    args = ap.parse_args()
    if not args.only_report:
        _blocks_1_to_4(args)
    for fast in ([True, False] if args.full else [True]):
        for jobs in args.report_jobs:
            _report_block(fast, jobs)
    return 0


def _blocks_1_to_4(args) -> None:
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
        # the report's route: the figures' share, not the packaged route's minutes of LMI solves
        lqr = ["design.pole_method=shift", "schedule.refine_points=0", "name=staircase_lqr"]
        subprocess.run([acmm, "simulate", "staircase", *lqr], cwd=tmp, check=True, capture_output=True)
        for stage in ("simulate", "design"):
            with_f = _wall([acmm, stage, "staircase", *lqr], tmp)
            without = _wall([acmm, stage, "staircase", *lqr, "--no-figures"], tmp)
            print(f"   acmm {stage:<8} staircase: with figures {with_f:5.2f} s, without {without:5.2f} s "
                  f"(figures {with_f - without:+.2f} s; target with figures <= 1.5 s)")


_REPORT = """
import json, sys
from pathlib import Path
from acmm.report.build import build_report
jobs = None if sys.argv[4] == "default" else int(sys.argv[4])
r = build_report(Path(sys.argv[1]), fast=sys.argv[3] == "fast", root=Path(sys.argv[2]), jobs=jobs)
print(json.dumps({"wall": r.wall_time, "jobs": r.jobs, "timings": r.timings, "tasks": r.tasks,
                  "determinism": r.determinism["status"]}))
"""


def _report_run(out: Path, root: Path, fast: bool, jobs) -> dict:
    """One ``build_report`` in a fresh interpreter (as ``acmm report`` runs): its own numbers, plus
    the process's wall time and CPU (user + system, its worker processes included)."""
    import json
    import resource

    def cpu():
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        return ru.ru_utime + ru.ru_stime

    c0, t0 = cpu(), time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _REPORT, str(out), str(root), "fast" if fast else "full",
                        "default" if jobs is None else str(jobs)], check=True, capture_output=True, text=True)
    res = json.loads(p.stdout.strip().splitlines()[-1])
    res["process_wall"], res["process_cpu"] = time.perf_counter() - t0, cpu() - c0
    return res


def _report_block(fast: bool, jobs) -> None:
    """Block 5: the report from a fresh results root, then again reusing its stage results."""
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for label in ("fresh root", "reuse"):
            load = _load()
            runs.append((label, load, _report_run(Path(tmp) / "report", Path(tmp), fast, jobs)))
    target = 10 if fast else 20
    print(f"5. acmm report{' --fast' if fast else ''} ({runs[0][2]['jobs']} processes; target <= {target} s "
          "from a fresh root):")
    for label, load, r in runs:
        print(f"   {label:<10} {r['process_wall']:6.1f} s wall, {r['process_cpu']:6.1f} s CPU for the whole "
              f"process (report itself {r['wall']:.1f} s; {load}); determinism {r['determinism']}")
    keys = [k for k in runs[0][2]["timings"] if k.startswith("section ")]
    print(f"   {'wall time (s) per section (its parts)':<34} {'fresh':>7} {'reuse':>7}")
    for k in keys:
        print(f"   {k:<34} " + " ".join(f"{r['timings'].get(k, 0.0):7.2f}" for _, _, r in runs))
    stages = sorted(((k, w, c) for k, (w, c) in runs[0][2]["tasks"].items() if ":" in k or k == "sweep"),
                    key=lambda x: -x[2])
    print("   stages of the fresh run (wall / CPU s): " +
          ", ".join(f"{k} {w:.1f}/{c:.1f}" for k, w, c in stages))


if __name__ == "__main__":
    raise SystemExit(main())
