"""Scaling table of ``acmm sweep`` for sizing a machine or a cluster (issue 16).

    MPLBACKEND=Agg .venv/bin/python scripts/bench_scaling.py [--workers 1 2 4 8 16] [--cases 400]
        [--base mb3] [--orbits 10] [--no-dask] [--unchunked]

For each N it runs the same seeded ±30 % inertia Monte Carlo (fixed design, no figures) on N
local worker processes and, when ``distributed`` is installed, on a Dask LocalCluster of N
single-threaded worker processes, once with Dask's default configuration and once with
:data:`acmm.sweep.dask_settings.DASK_SETTINGS` (cluster start-up and the one-time kernel load per
worker excluded: a user starts and warms a cluster once),
and prints wall time, the CPU time of the run's processes (driver + workers; with psutil), the
load average, cases/s, speed-up over 1 worker and Dask / pool; ``--unchunked`` adds a Dask run
with one case per task (the pre-issue-16 behaviour) to show what chunking buys.  Every run's
table is compared with the 1-worker table (bit for bit).  Also prints the per-case cost over the
bare 10-orbit integration of the same plants (one core).  ``--repeat R`` runs the table R times
back to back (on a shared machine compare the ratios of one repetition).
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

KEYS = ("verdict", "peak_attitude_error", "steady_attitude_error", "peak_momentum", "time_to_divergence",
        "tea_true", "torque_saturation_time")


def _spec(args):
    return {"base": args.base, "monte_carlo": {"inertia": {"percent": 30}}, "n_runs": args.cases,
            "seed": 185644, "design": "fixed", "orbits": args.orbits}


def _same(a, b) -> bool:
    return all(np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == "f") for k in KEYS)


def per_case_cost(base: str, orbits: float, n: int = 60) -> tuple[float, float]:
    """(seconds per sweep case, seconds per bare integration of the same perturbed plants)."""
    from acmm.model import dynamics as dyn
    from acmm.model import kinematics as kin
    from acmm.simulate import kernel as sm
    from acmm.model.inertia import perturb_inertia
    from acmm.sweep.cases import case_values
    from acmm.sweep.case import prepare_base, run_case, simulate_values
    from acmm.sweep.config import parse_sweep

    sw = parse_sweep({"name": "bench_case", "sweep": {"base": base, "monte_carlo": {"inertia": {"percent": 30}},
                                                       "n_runs": n, "seed": 185644, "design": "fixed",
                                                       "orbits": orbits},
                      "output": {"root": tempfile.mkdtemp(), "figures": False}})
    ctx = prepare_base(sw.bases[0], sw.spec)
    simulate_values(ctx, {})
    sc0 = ctx.scenario
    scenarios = []
    for i in range(n):
        values, _, why = case_values(sw.spec, i, sc0.inertia)
        if why is not None:
            continue
        row = simulate_values(ctx, values)
        if row["verdict"] in ("no_equilibrium", "unphysical"):
            continue
        true = np.radians(np.array(row["tea_true"]))
        x0 = np.concatenate([kin.lvlh_rate_in_body(true, sc0.n), true, np.zeros(18)])
        inertia = np.array([perturb_inertia(m, values) for m in sc0.inertia])
        scenarios.append((i, dataclasses.replace(sc0, inertia=inertia, x0=x0)))
    best_case, best_bare = np.inf, np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for i, _sc in scenarios:
            run_case(ctx, i)
        best_case = min(best_case, (time.perf_counter() - t0) / len(scenarios))
        t0 = time.perf_counter()
        for _i, sc in scenarios:
            sm.simulate(sc)
        best_bare = min(best_bare, (time.perf_counter() - t0) / len(scenarios))
    return best_case, best_bare


def scaling(workers: list[int], cases: int, base: str, orbits: float, dask: bool = True,
            unchunked: bool = False, out=print) -> dict:
    """Run the table; returns {(executor, N): seconds} and prints rows through ``out``."""
    from acmm_qpp.results import read_h5
    from acmm.sweep.run import run_sweep
    from acmm.sweep.config import parse_sweep

    tmp = Path(tempfile.mkdtemp(prefix="bench_scaling_"))
    spec = {"base": base, "monte_carlo": {"inertia": {"percent": 30}}, "n_runs": cases, "seed": 185644,
            "design": "fixed", "orbits": orbits}
    try:
        import distributed
    except ImportError:
        distributed = None
        dask = unchunked = False
    times, tables, cpu = {}, {}, {}

    def one(label, n, **kw):
        sw = parse_sweep({"name": f"s_{label}_{n}", "sweep": spec, "output": {"root": str(tmp), "figures": False}})
        c0 = _tree_cpu()
        t0 = time.perf_counter()
        r = run_sweep(sw, **kw)
        times[label, n] = time.perf_counter() - t0
        cpu[label, n] = _tree_cpu(c0)
        tables[label, n] = read_h5(r.path)
        return times[label, n]

    load1 = os.getloadavg()[0]
    one("pool", 1, workers=1)
    ref = tables["pool", 1]
    out(f"  {'executor':<22} {'N':>3} {'wall s':>8} {'cpu s':>7} {'load':>5} {'cases/s':>8} {'speed-up':>9} "
        f"{'vs pool':>8}  identical")
    for n in workers:
        rows = [("local pool", "pool", {"workers": n})]
        if dask:
            rows.append(("Dask LocalCluster", "dask", {}))
            rows.append(("Dask, acmm settings", "dask_acmm", {}))
        if unchunked:
            rows.append(("Dask, 1 case/task", "dask1", {"chunk": 1}))
        for name, label, kw in rows:
            if label == "pool":
                if n != 1:
                    load = os.getloadavg()[0]
                    one(label, n, **kw)
                else:
                    load = load1
            else:
                import dask

                from acmm.sweep.dask_settings import DASK_SETTINGS

                # Dask's defaults, and the settings acmm recommends for a sweep cluster
                settings = DASK_SETTINGS if label == "dask_acmm" else {}
                with dask.config.set(settings), distributed.LocalCluster(
                        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
                    # start-up and the one-time kernel load per worker are not timed: a cluster
                    # serving many sweeps pays them once (a forked pool inherits them)
                    with distributed.Client(cluster) as client:
                        from acmm.sweep.executors import _warm_worker

                        client.run(_warm_worker)
                    load = os.getloadavg()[0]
                    one(label, n, scheduler=cluster.scheduler_address, **kw)
            t = times[label, n]
            vs = f"{t / times['pool', n]:.2f}x" if label != "pool" else "-"
            c = f"{cpu[label, n]:7.2f}" if cpu[label, n] is not None else f"{'-':>7}"
            out(f"  {name:<22} {n:>3} {t:8.2f} {c} {load:5.1f} {cases / t:8.1f} {times['pool', 1] / t:8.2f}x {vs:>8}  "
                f"{_same(ref, tables[label, n])}")
    return times


def _tree_cpu(since=None):
    """user+sys CPU seconds of this process, its finished children and its live descendants
    (Dask workers); the difference from ``since`` when given; None without psutil."""
    try:
        import psutil
    except ImportError:
        return None
    t = os.times()
    own = t.user + t.system + t.children_user + t.children_system
    live = {}
    for p in psutil.Process().children(recursive=True):
        try:
            c = p.cpu_times()
            live[p.pid] = c.user + c.system
        except psutil.Error:
            pass
    if since is None:
        return own, live
    own0, live0 = since
    return own - own0 + sum(v - live0.get(k, 0.0) for k, v in live.items())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--cases", type=int, default=400)
    ap.add_argument("--base", default="mb3")
    ap.add_argument("--orbits", type=float, default=10.0)
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--unchunked", action="store_true")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-case-cost", action="store_true", help="skip the per-case / bare integration ratio")
    args = ap.parse_args()
    print(f"{args.cases}-case ±30 % inertia Monte Carlo of {args.base}, {args.orbits:g}-orbit runs, fixed design; "
          f"{os.cpu_count()} CPU(s), load average {os.getloadavg()[0]:.1f}")
    if not args.no_case_cost:
        c, b = per_case_cost(args.base, args.orbits)
        print(f"  per case {c * 1e3:.2f} ms / bare {args.orbits:g}-orbit integration {b * 1e3:.2f} ms = "
              f"{c / b:.2f}x (target <= 3x; load {os.getloadavg()[0]:.1f})")
    for k in range(args.repeat):
        if args.repeat > 1:
            print(f" repetition {k + 1}/{args.repeat}")
        scaling(args.workers, args.cases, args.base, args.orbits, dask=not args.no_dask, unchunked=args.unchunked)


if __name__ == "__main__":
    main()
