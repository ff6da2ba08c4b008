"""`make bench`: the speed and memory targets (issues 4, 5, 40) and the ratios that matter (issue 16),
printed, never asserted; docs/performance.md lists each number and its target.

First the targets: `acmm --help`; the packaged stair-case design in-process, its 12 LMI points
one after another and on the process pool, the 12-point stair-case on the LMI route against the
report's route; MB3's and AC's regional LMI program by conelp, DSDP and Clarabel; the 130-orbit
stair-case by the compiled kernel against `solve_ivp`; peak memory of `acmm simulate`.  Then the
ratios: (1) one Monte Carlo case over the bare integration of the same plant; (2) the same seeded
sweep on 1 vs N local workers, tables identical; (3) a Dask LocalCluster against the local pool,
with Dask's defaults and with ``DASK_SETTINGS``; (4) the stair-case CLI with and without
figures; (5) `acmm report --fast` (and the full report with ``--full``), fresh and reusing its
stage results.

    MPLBACKEND=Agg .venv/bin/python scripts/bench.py [--workers 2] [--cases 3200] [--full]
        [--report-jobs 1 2] [--only-targets | --only-ratios | --only-report]

(`make bench` runs targets and ratios in two processes: the ratios in a fresh interpreter.)

``--scaling`` prints instead the scaling table of ``acmm sweep`` for sizing a machine or a
cluster (blocks 1–3 for any list of N, cluster start-up and each worker's one-time kernel load
excluded; ``--unchunked`` adds a Dask run with one case per task; ``--repeat R`` runs it R times):

    MPLBACKEND=Agg .venv/bin/python scripts/bench.py --scaling [--workers 1 2 4 8 16]
        [--cases 400] [--base mb3] [--orbits 10] [--no-dask] [--unchunked] [--repeat R] [--no-case-cost]

The machine's load average is printed with each block: on a shared machine compare ratios.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from functools import partial
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from acmm.design.methods import pole_method  # noqa: E402
from acmm.design.regional_lmi import regional_lmi  # noqa: E402
from acmm.design.schedule import design_one  # noqa: E402
from acmm.design.schedule_points import point_specs  # noqa: E402
from acmm.design.settings import design_settings  # noqa: E402
from acmm.io.config import load_config  # noqa: E402
from acmm.model import kinematics as kin  # noqa: E402
from acmm.model.inertia import perturb_inertia  # noqa: E402
from acmm.model.state_scaling import torque_scale  # noqa: E402
from acmm.simulate import kernel as sm  # noqa: E402
from acmm.simulate import reference  # noqa: E402
from acmm.simulate import scenario as scen  # noqa: E402
from acmm.stages.design import compute_design  # noqa: E402
from acmm.sweep.case import prepare_base, run_case, simulate_values  # noqa: E402
from acmm.sweep.cases import case_values  # noqa: E402
from acmm.sweep.config import parse_sweep  # noqa: E402
from acmm.sweep.dask_settings import DASK_SETTINGS  # noqa: E402
from acmm.sweep.run import run_sweep, warm_worker  # noqa: E402
from acmm.stages.pool import pool_map, process_pool, stop_pool  # noqa: E402
from acmm_qpp.results import read_h5  # noqa: E402

BIN = Path(sys.executable).parent
KEYS = ("verdict", "peak_attitude_error", "steady_attitude_error", "peak_momentum", "time_to_divergence",
        "tea_true", "torque_saturation_time")


def _spec(base: str, cases: int, orbits: float) -> dict:
    """The seeded ±30 % inertia Monte Carlo of a fixed design every block runs."""
    return {"base": base, "monte_carlo": {"inertia": {"percent": 30}}, "n_runs": cases, "seed": 185644,
            "design": "fixed", "orbits": orbits}


def per_case_cost(base: str, orbits: float, n: int = 60) -> tuple[float, float]:
    """(seconds per sweep case, seconds per bare integration of the same perturbed plants)."""
    sw = parse_sweep({"name": "bench_case", "sweep": _spec(base, n, orbits),
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
        scenarios.append((i, replace(sc0, inertia=inertia, x0=x0)))
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
    tmp = Path(tempfile.mkdtemp(prefix="bench_scaling_"))
    spec = _spec(base, cases, orbits)
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
            rows += [("Dask LocalCluster", "dask", {}), ("Dask, acmm settings", "dask_acmm", {})]
        if unchunked:
            rows.append(("Dask, 1 case/task", "dask1", {"chunk": 1}))
        for name, label, kw in rows:
            if label == "pool":
                load = load1 if n == 1 else os.getloadavg()[0]
                if n != 1:
                    one(label, n, **kw)
            else:
                import dask

                # Dask's defaults, and the settings acmm recommends for a sweep cluster
                settings = DASK_SETTINGS if label == "dask_acmm" else {}
                with dask.config.set(settings), distributed.LocalCluster(
                        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
                    # start-up and the one-time kernel load per worker are not timed: a cluster
                    # serving many sweeps pays them once (a forked pool inherits them)
                    with distributed.Client(cluster) as client:
                        client.run(warm_worker)
                    load = os.getloadavg()[0]
                    one(label, n, scheduler=cluster.scheduler_address, **kw)
            t = times[label, n]
            vs = f"{t / times['pool', n]:.2f}x" if label != "pool" else "-"
            c = f"{cpu[label, n]:7.2f}" if cpu[label, n] is not None else f"{'-':>7}"
            same = all(np.array_equal(ref[k], tables[label, n][k], equal_nan=ref[k].dtype.kind == "f") for k in KEYS)
            out(f"  {name:<22} {n:>3} {t:8.2f} {c} {load:5.1f} {cases / t:8.1f} {times['pool', 1] / t:8.2f}x {vs:>8}  "
                f"{same}")
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


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs"


def _wall(cmd, cwd, repeat=3) -> float:
    """The best wall time of ``repeat`` runs of the command ``cmd``, s."""
    return min(_timed(subprocess.run, cmd, cwd=cwd, check=True, capture_output=True)[1] for _ in range(repeat))


def _timed(fn, *args, **kw):
    """(what ``fn(*args, **kw)`` returns, its wall time in s)."""
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def _row(name, value, target, ok):
    print(f"  {name:<52} {value:>14}   target {target:<12} {'ok' if ok else 'MISSED'}")


def baseline_solve_ivp(sc: scen.Scenario, rtol=1e-8):
    """The same closed loop, level by level, with scipy's RK45 and the numpy right-hand side."""
    x = sc.x0.copy()
    ends = np.append(sc.level_start[1:], sc.t_end)
    steps = 0
    for k, (t0, t1) in enumerate(zip(sc.level_start, ends)):
        sol = solve_ivp(lambda t, y: reference.rhs_numpy(t, y, sc, k), (t0, t1), x, method="RK45",
                        rtol=rtol, atol=sc.atol)
        x = sol.y[:, -1]
        steps += sol.t.size
    return x, steps


def _solver_rows(name):
    """One point's regional LMI program solved by each solver, in this process: times, their ratio,
    iterations, certified margins and the gains' agreement (issue 40)."""
    cfg = load_config(name, ["design.pole_method=lmi"])
    s = design_settings(cfg)
    pd = design_one(point_specs(cfg)[0], replace(s, method=pole_method("shift")))    # model, reference gain
    m, ref = pd.model, pd.gain
    out = {}
    # each solver on the program; Clarabel on the unregularized program (the route before issue 40)
    for key, solver, reg in (("conelp", "conelp", s.lmi.regularization), ("dsdp", "dsdp", s.lmi.regularization),
                             ("clarabel", "clarabel", s.lmi.regularization), ("before", "clarabel", 0.0)):
        st = replace(s.lmi, solver=solver, n_random=0, regularization=reg)
        out[key] = _timed(regional_lmi, m.A, m.B, s.orbit_rate, ref.K, st, scale=m.scales,
                          input_scale=torque_scale(m.scales))
    (a, ta), (d, td), (c, tc), (b, tb) = out["conelp"], out["dsdp"], out["clarabel"], out["before"]

    def apart(x):
        return np.linalg.norm(x.K - c.K) / np.linalg.norm(c.K)

    _row(f"{name.upper()} regional LMI by {a.solver} (structured KKT; iterations {'+'.join(map(str, a.iterations))}), "
         f"certified margin {a.certified_margin:.5f}n", f"{ta:.2f} s", "-", a.solver == "conelp" and not a.rejected)
    _row(f"{name.upper()} the same program by {d.solver} (2 passes; cvxopt reports no iteration count), certified "
         f"margin {d.certified_margin:.5f}n", f"{td:.2f} s", "-", d.solver == "dsdp" and not d.rejected)
    _row(f"{name.upper()} the same program by {c.solver} (iterations {'+'.join(map(str, c.iterations))}), certified "
         f"margin {c.certified_margin:.5f}n", f"{tc:.2f} s", "-", c.solver == "clarabel" and not c.rejected)
    _row(f"  {c.solver} / {a.solver} time; gains apart (relative, 2-norm) {apart(a):.1e} ({d.solver}: {apart(d):.1e})",
         f"{tc / ta:.1f}x", ">= 20x", tc / ta >= 20)
    _row(f"{name.upper()} the unregularized program by {b.solver} (before issue 40; iterations "
         f"{'+'.join(map(str, b.iterations))}), energy {b.energy / a.energy - 1:+.3%} vs {a.solver}'s", f"{tb:.2f} s",
         "-", b.solver == "clarabel")
    _row(f"  that / {a.solver} time (issue 40's ratio)", f"{tb / ta:.1f}x", ">= 20x", tb / ta >= 20)


def _targets() -> None:
    """The targets of issues 4, 5 and 40 (the rows of the docstring's first list)."""
    print("acmm-qpp benchmarks (2-core machine; best of repeated runs)")
    with tempfile.TemporaryDirectory() as tmp:
        t_help = _wall([str(BIN / "acmm"), "--help"], tmp)
        _row("acmm --help", f"{t_help:.3f} s", "< 0.5 s", t_help < 0.5)

    cfg = load_config("staircase")
    shipped, t_design = _timed(compute_design, cfg)
    _row(f"packaged stair-case design in-process ({len(shipped.points)} LMI points with the refined nodes, "
         f"{shipped.path_check.theta2.size} path TEAs)", f"{t_design:.1f} s", "-", True)
    cfg12 = load_config("staircase", ["schedule.refine_points=0"])
    specs, s12 = point_specs(cfg12), design_settings(cfg12)
    _, t_serial = _timed(lambda: [design_one(spec, s12) for spec in specs])
    t0 = time.perf_counter()
    pool = process_pool(os.cpu_count())
    list(pool_map(pool, partial(design_one, s=s12), specs))
    stop_pool(pool)
    t_pool = time.perf_counter() - t0
    _row(f"  the 12 LMI points one after another / on the process pool ({os.cpu_count()} CPUs, its start included)",
         f"{t_serial / t_pool:.2f}x", ">= 1.6x", t_serial / t_pool >= 1.6)

    _, t_lmi12 = _timed(compute_design, cfg12)
    _row("the 12-point stair-case on the LMI route (schedule.refine_points=0) in-process", f"{t_lmi12:.1f} s", "-", True)
    _, t_lqr = _timed(compute_design, load_config("staircase", ["design.pole_method=shift", "schedule.refine_points=0"]))
    _row("the same on the report's route (design.pole_method=shift) in-process", f"{t_lqr:.1f} s", "-", True)
    _row("  12-point LMI stair-case / report's route (issue 40)", f"{t_lmi12 / t_lqr:.1f}x", "<= 4x",
         t_lmi12 <= 4 * t_lqr)
    _row("  packaged stair-case (refined) / report's route", f"{t_design / t_lqr:.1f}x", "-", True)
    for name in ("mb3", "ac"):
        _solver_rows(name)

    sc = scen.scenario_from_config(cfg, shipped.table)
    _, t_first = _timed(sm.simulate, sc)          # compile or load the cached machine code
    r, t_sim = min((_timed(sm.simulate, sc) for _ in range(3)), key=lambda x: x[1])
    _row("first simulate() in this process (cache load/compile)", f"{t_first:.2f} s", "-", True)
    _row(f"130-orbit stair-case, compiled DOPRI5 ({r.n_steps} steps)", f"{t_sim:.3f} s", "<= 1 s",
         t_sim <= 1.0)

    (x_ref, steps), t_base = _timed(baseline_solve_ivp, sc)
    _row(f"same model, solve_ivp RK45 rtol 1e-8 + numpy rhs ({steps} steps)", f"{t_base:.2f} s", "-", True)
    ratio = t_base / t_sim
    _row("speed-up over the solve_ivp baseline", f"{ratio:.0f}x", ">= 15x", ratio >= 15)
    scale = scen.plain_scales(sc.n, sc.drf_mode)
    diff = np.max(np.abs(r.state[-1] - x_ref) / (scale * 1e-6 + 1e-6 * np.abs(x_ref)))
    _row("final-state agreement with the baseline (in 1e-6 units)", f"{diff:.2f}", "-", True)

    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    # `acmm simulate` from a fresh process whose only descendants are it and its pool workers
    # (this process's own children — the pool workers of the in-process design above, forked
    # from its larger heap — would otherwise set the maximum)
    probe = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, capture_output=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    with tempfile.TemporaryDirectory() as tmp:
        out = subprocess.run([sys.executable, "-c", probe, str(BIN / "acmm"), "simulate"], cwd=tmp, check=True,
                             capture_output=True, text=True)
        child_mb = int(out.stdout.split()[-1]) / 1024
    _row("peak memory, `acmm simulate` (design + 130 orbits + figures)", f"{child_mb:.0f} MB", "< 500 MB",
         child_mb < 500)
    _row("peak memory, this benchmark process", f"{peak_mb:.0f} MB", "-", True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--workers", type=int, nargs="+", default=None,
                    help="worker counts (default: min(2, CPUs); with --scaling: 1 2)")
    ap.add_argument("--cases", type=int, default=None, help="sweep size (default 3200; with --scaling: 400; "
                    "the Dask overhead shows at a few thousand cases)")
    ap.add_argument("--full", action="store_true", help="also the full report (~20 s or more)")
    ap.add_argument("--report-jobs", type=int, nargs="+", default=[None],
                    help="report processes to compare (default: the report's default, 2 on 2+ CPUs)")
    ap.add_argument("--only-report", action="store_true", help="block 5 only")
    ap.add_argument("--only-ratios", action="store_true", help="blocks 1-5 only, not the targets")
    ap.add_argument("--only-targets", action="store_true", help="the targets only, not blocks 1-5")
    ap.add_argument("--scaling", action="store_true", help="the scaling table only (see above)")
    ap.add_argument("--base", default="mb3")
    ap.add_argument("--orbits", type=float, default=10.0)
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--unchunked", action="store_true")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-case-cost", action="store_true", help="skip the per-case / bare integration ratio")
    args = ap.parse_args()
    other = (("full", "report_jobs", "only_report", "only_ratios", "only_targets") if args.scaling else
             ("base", "orbits", "no_dask", "unchunked", "repeat", "no_case_cost"))
    if wrong := [f"--{k.replace('_', '-')}" for k in other if getattr(args, k) != ap.get_default(k)]:
        ap.error(f"{', '.join(wrong)}: " + ("not with --scaling" if args.scaling else "only with --scaling"))
    if args.scaling:
        _scaling_table(args)
        return 0
    if not (args.only_report or args.only_ratios):
        _targets()
    if args.only_targets:
        return 0
    if not args.only_report:
        _blocks_1_to_4(args)
    for fast in ([True, False] if args.full else [True]):
        for jobs in args.report_jobs:
            _report_block(fast, jobs)
    return 0


def _scaling_table(args) -> None:
    """``--scaling``: the per-case cost, then the scaling table for each N of ``--workers``."""
    cases = args.cases or 400
    print(f"{cases}-case ±30 % inertia Monte Carlo of {args.base}, {args.orbits:g}-orbit runs, fixed design; "
          f"{os.cpu_count()} CPU(s), load average {os.getloadavg()[0]:.1f}")
    if not args.no_case_cost:
        c, b = per_case_cost(args.base, args.orbits)
        print(f"  per case {c * 1e3:.2f} ms / bare {args.orbits:g}-orbit integration {b * 1e3:.2f} ms = "
              f"{c / b:.2f}x (target <= 3x; load {os.getloadavg()[0]:.1f})")
    for k in range(args.repeat):
        if args.repeat > 1:
            print(f" repetition {k + 1}/{args.repeat}")
        scaling(args.workers or [1, 2], cases, args.base, args.orbits, dask=not args.no_dask,
                unchunked=args.unchunked)


def _blocks_1_to_4(args) -> None:
    workers, cases = max(args.workers or [min(2, os.cpu_count() or 1)]), args.cases or 3200
    print(f"issue 16 benchmarks ({_load()}; best of repeats)")
    c, b = per_case_cost("mb3", 10.0)
    print(f"1. MC case {c * 1e3:.2f} ms / bare 10-orbit integration {b * 1e3:.2f} ms = {c / b:.2f}x  "
          f"(target <= 3x)")
    print(f"2./3. {cases}-case ±30 % MB3 Monte Carlo, 1 vs {workers} workers, pool vs Dask ({_load()}):")
    scaling(sorted({1, workers}), cases, "mb3", 10.0, out=lambda s: print("   " + s))
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
            if stage == "design":
                _row("   acmm design staircase (the report's route, 12 points) --no-figures (wall)",
                     f"{without:.2f} s", "< 10 s", without < 10.0)


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
            runs.append((label, _load(), _report_run(Path(tmp) / "report", Path(tmp), fast, jobs)))
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
