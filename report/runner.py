"""A small task graph run in dependency order, in this process or on forked worker processes (issue 16).

The report is a graph of independent pieces of work: the stages it gathers (designs, simulations,
the robustness sweep, the QPP chapters) and the parts of its sections (each writes its own
figures).  :func:`run_tasks` runs such a graph

* serially (``jobs=1``): in the order of the list, in this process — exactly what the report
  did before it had a graph;
* on ``jobs`` forked worker processes (POSIX): a task is submitted as soon as the tasks it
  depends on have finished, longest remaining chain first.  Only the task's function, its
  arguments (built in this process from the results of its dependencies) and its return value
  cross the process boundary; everything a task writes (HDF5 files, figures) is a file.
  The workers are forked after a warm-up (imports every worker needs, done once); while this
  process warms up on one core, a child of its own already runs the ready tasks
  (:class:`report.early_worker.EarlyWorker`), so that the other core is not idle for those 1–2 s.

The results are the same either way: every task is a deterministic function of its arguments and
of files its dependencies wrote completely before it starts.

Failures: a task that raises an :class:`~common.errors.AcmmError` in a worker is re-raised here
as the same class with the same message (one clear line at the command line); any other
exception propagates with the worker's traceback attached.  On the first failure no further task
is started, the running ones are waited for, and the error is raised — the caller writes its
output only after :func:`run_tasks` returned.
"""
from __future__ import annotations

import concurrent.futures as cf
import gc
import importlib
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

from common.errors import AcmmError
from common.workers import stop_pool, submit


def _no_args(done: dict) -> tuple:
    """The default :attr:`Task.args`: a task that takes no arguments.

    Parameters
    ----------
    done : dict
        Name → result of every finished task (unused).

    Returns
    -------
    tuple
        The empty tuple.
    """
    return ()


@dataclass
class Task:
    """One node of the graph.

    Attributes
    ----------
    name : str
        Unique name; the key of its result.
    fn : callable
        A module-level function (sent to a worker by reference).
    deps : tuple of str
        Names of the tasks that must have finished first.
    args : callable
        ``args(done) -> tuple``: the positional arguments of ``fn``, built in the calling process
        from ``done`` (name → result of every finished task).
    cost : float
        Rough run time (s) used only to order the ready tasks (longest remaining chain first).
    priority : float
        Not an argument: set by :func:`run_tasks` before forking to ``cost`` plus the longest
        chain (s) of tasks that wait for this one; the ready task of highest priority starts first.
    """

    name: str
    fn: Callable
    deps: tuple = ()
    args: Callable[[dict], tuple] = _no_args
    cost: float = 1.0
    priority: float = field(default=0.0, init=False)


def default_jobs() -> int:
    """Worker processes for the report: ``ACMM_REPORT_JOBS`` if set, else min(2, CPUs); 1 without
    ``os.fork`` or when this process runs other threads (forking a multi-threaded process, e.g. one
    holding a Dask client, can deadlock the child).

    Returns
    -------
    int
        Number of worker processes, at least 1.

    Raises
    ------
    ConfigError
        ``ACMM_REPORT_JOBS`` is set to something else than a whole number 1–1024.
    """
    import threading

    env = os.environ.get("ACMM_REPORT_JOBS", "").strip()
    if env and not (env.isdigit() and 1 <= int(env) <= 1024):
        from common.errors import ConfigError

        raise ConfigError(f"ACMM_REPORT_JOBS: must be a whole number from 1 to 1024 (got {env!r}); unset it for "
                          "the default")
    if not hasattr(os, "fork"):
        return 1
    if env:
        return int(env)
    if threading.active_count() > 1:
        return 1
    return max(1, min(2, os.cpu_count() or 1))


def run_tasks(tasks: list[Task], jobs: int = 1, on_done: Optional[Callable[[str, object], None]] = None,
              warm: Optional[Callable[[], None]] = None, stats: Optional[dict] = None) -> dict:
    """Run ``tasks`` (a list in a valid serial order) and return ``{name: result}``.

    Parameters
    ----------
    tasks : list of Task
        Every dependency must name an earlier task of the list.
    jobs : int
        1: in this process, in list order; > 1: that many forked worker processes.
    on_done : callable(name, result), optional
        Called in this process after each task, in completion order.
    warm : callable, optional
        Called once in this process before the workers are forked (imports they all need).
    stats : dict, optional
        Filled with ``name → (wall s, CPU s)`` of each task (CPU of the process that ran it).

    Returns
    -------
    dict
        ``{name: result}`` of every task of ``tasks``.

    Raises
    ------
    ValueError
        If a task's name is repeated or a dependency is not listed before it.
    common.errors.AcmmError
        The first error a task raised (re-built with its class and message when it came from a
        worker); :class:`~common.errors.OutputError` if a worker process died.
    """
    _check(tasks)
    on_done = on_done or (lambda name, result: None)
    stats = {} if stats is None else stats
    done: dict[str, object] = {}
    jobs = min(int(jobs), len(tasks))        # never more processes than tasks
    if jobs <= 1 or len(tasks) <= 1 or not hasattr(os, "fork"):
        for t in tasks:              # errors propagate unchanged
            t0, c0 = time.perf_counter(), time.process_time()
            done[t.name] = t.fn(*t.args(done))
            stats[t.name] = (time.perf_counter() - t0, time.process_time() - c0)
            on_done(t.name, done[t.name])
        return done
    _prioritize(tasks)
    # the warm-up below runs on one core: meanwhile a child of its own runs the ready tasks
    from report.early_worker import EarlyWorker

    early = EarlyWorker.start(tasks, done)
    try:
        if warm is not None:
            warm()
        # what this process holds is not garbage: frozen, the workers' collections skip it and do
        # not copy its pages on write (issue 16: ~40 % fewer page faults per worker); thawed after
        gc.collect()
        gc.freeze()
        try:
            _run_pool(tasks, jobs, done, on_done, stats, early)
        finally:
            gc.unfreeze()
    finally:
        if early is not None:       # a failure elsewhere: let its task finish, like the pool's
            early.finish()
    return done


def _check(tasks: list[Task]) -> None:
    seen: set[str] = set()
    for t in tasks:
        missing = [d for d in t.deps if d not in seen]
        if missing or t.name in seen:
            raise ValueError(f"task {t.name!r}: duplicate, or dependencies {missing} not listed before it")
        seen.add(t.name)


def _prioritize(tasks: list[Task]) -> None:
    """``priority`` = cost of the task plus the longest chain of tasks that wait for it."""
    after: dict[str, list[Task]] = {t.name: [] for t in tasks}
    for t in tasks:
        for d in t.deps:
            after[d].append(t)
    for t in reversed(tasks):
        t.priority = t.cost + max((s.priority for s in after[t.name]), default=0.0)


def _run_pool(tasks: list[Task], jobs: int, done: dict, on_done, stats: dict,
              early=None) -> None:
    import multiprocessing

    owned = early.seal() if early is not None else set()     # what the early child runs or ran
    waiting = [t for t in tasks if t.name not in owned]
    by_name = {t.name: t for t in tasks}
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("fork"),
                                  initializer=_worker_init, initargs=(os.getpid(),))
    running: dict[cf.Future, Task] = {}

    def finish(t: Task, out: tuple) -> None:
        from common.forked import raise_warnings_again

        stats[t.name] = out[-2:]
        raise_warnings_again(out[-3])        # as the serial run raises them
        done[t.name] = _unwrap_value(out)
        on_done(t.name, done[t.name])

    try:
        while waiting or running or (early is not None and early.busy):
            while early is not None and early.busy and early.ready(0.0):   # its results first
                got = early.next_result()           # (a failure raises before anything starts)
                if got is not None:
                    finish(by_name[got[0]], got[1])
            busy = early is not None and early.busy          # the early child counts as one job
            ready = sorted((t for t in waiting if all(d in done for d in t.deps)), key=lambda t: -t.priority)
            for t in ready[: max(0, jobs - len(running) - busy)]:
                waiting.remove(t)
                sys.stdout.flush()
                sys.stderr.flush()
                running[submit(pool, _call, t.fn, t.args(done))] = t
            finished: set = set()
            if not busy:
                finished, _ = cf.wait(list(running), return_when=cf.FIRST_COMPLETED)
            elif running:  # poll the pool's futures and (above) the early child's pipe in turn
                finished, _ = cf.wait(list(running), timeout=0.05, return_when=cf.FIRST_COMPLETED)
            else:
                early.ready(None)
            for fut in finished:
                finish(running.pop(fut), _result(fut))
    except BaseException:
        stop_pool(pool, abort=True)
        raise
    pool.shutdown(wait=True)


# ---------------------------------------------------------------------------------------------
# in the worker
# ---------------------------------------------------------------------------------------------
#: per-worker-process cache (e.g. HDF5 files already read), emptied when the worker starts
WORKER_CACHE: dict = {}


def _worker_init(parent: int) -> None:
    from common.workers import pool_worker

    pool_worker(parent)                # Ctrl-C is the parent's; dies with it
    WORKER_CACHE.clear()
    os.environ["ACMM_FORK"] = "0"      # the pool uses the cores: no stage forks a child of its own


def _call(fn, args):
    """Run ``fn(*args)``: ``("ok", result, warnings, wall, cpu)``, or an :class:`AcmmError` as
    data ``("error", module, class name, message, exit code, warnings, wall, cpu)`` (its class may
    not pickle); the warnings it raised travel for the parent to raise again
    (:func:`common.forked.portable_warnings`)."""
    import warnings

    from common.forked import portable_warnings

    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        try:
            out = ("ok", fn(*args))
        except AcmmError as exc:
            cls = type(exc)
            out = ("error", cls.__module__, cls.__qualname__, str(exc), getattr(exc, "exit_code", None))
    return out + (portable_warnings(caught), time.perf_counter() - t0, time.process_time() - c0)


def _result(fut: cf.Future) -> tuple:
    from concurrent.futures.process import BrokenProcessPool

    try:
        return fut.result()
    except BrokenProcessPool:
        from common.errors import OutputError

        raise OutputError("a report worker process died (killed, or out of memory); nothing was written") from None


def _unwrap_value(out: tuple):
    if out[0] == "ok":
        return out[1]
    raise _rebuild(*out[1:5])


def _rebuild(module: str, qualname: str, message: str, exit_code) -> AcmmError:
    """The worker's error as the same class (or a plain :class:`AcmmError` with its exit code)."""
    try:
        cls = importlib.import_module(module)
        for part in qualname.split("."):
            cls = getattr(cls, part)
        exc = cls(message)
        if isinstance(exc, AcmmError):
            return exc
    except Exception:  # noqa: BLE001 (a class that cannot be rebuilt from its message)
        pass
    exc = AcmmError(message)
    if exit_code is not None:
        exc.exit_code = exit_code
    return exc
