"""The report's task graph (stages and section parts), run in dependency order in this process
(``jobs=1``, in list order) or on a pool of worker processes (:func:`acmm.stages.pool.process_pool`:
a task starts once its dependencies finished, longest remaining chain first).

Only a task's function, its arguments (built here from its dependencies' results) and its return
value cross the process boundary; what it writes is a file, so the results are the same either
way.  A worker's :class:`~acmm_qpp.errors.AcmmError` is raised here as the same class and message;
on the first failure no further task starts and the pool is stopped.
"""
from __future__ import annotations

import concurrent.futures as cf
import importlib
import os
import threading
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Optional

from acmm_qpp.errors import AcmmError, ConfigError, OutputError
from acmm.stages.pool import portable_warnings, process_pool, raise_warnings_again, stop_pool, submit


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
        Not an argument: set by :func:`run_tasks` to ``cost`` plus the longest
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
    env = os.environ.get("ACMM_REPORT_JOBS", "").strip()
    if env and not (env.isdigit() and 1 <= int(env) <= 1024):
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
        1: in this process, in list order; > 1: on a pool of that many worker processes.
    on_done : callable(name, result), optional
        Called in this process after each task, in completion order.
    warm : callable, optional
        Called once in this process before the pool starts (imports its workers all need,
        inherited by the forked workers).
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
    acmm_qpp.errors.AcmmError
        The first error a task raised (re-built with its class and message when it came from a
        worker); :class:`~acmm_qpp.errors.OutputError` if a worker process died.
    """
    _check(tasks)
    on_done = on_done or (lambda name, result: None)
    stats = {} if stats is None else stats
    done: dict[str, object] = {}
    jobs = min(int(jobs), len(tasks))        # never more processes than tasks
    if jobs <= 1:
        for t in tasks:              # errors propagate unchanged
            t0, c0 = time.perf_counter(), time.process_time()
            done[t.name] = t.fn(*t.args(done))
            stats[t.name] = (time.perf_counter() - t0, time.process_time() - c0)
            on_done(t.name, done[t.name])
        return done
    _prioritize(tasks)
    if warm is not None:
        warm()
    pool = process_pool(jobs, WORKER_CACHE.clear)
    try:
        _run_on_pool(pool, tasks, jobs, done, on_done, stats)
    except BaseException:
        stop_pool(pool, abort=True)
        raise
    stop_pool(pool)
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


def _run_on_pool(pool, tasks: list[Task], jobs: int, done: dict, on_done, stats: dict) -> None:
    """Keep ``jobs`` tasks running: start the ready ones, highest priority first; take each
    result as it comes (its warnings raised here, then ``on_done``)."""
    waiting = list(tasks)
    running: dict[cf.Future, Task] = {}
    while waiting or running:
        ready = sorted((t for t in waiting if all(d in done for d in t.deps)), key=lambda t: -t.priority)
        for t in ready[: jobs - len(running)]:
            waiting.remove(t)
            running[submit(pool, _call, t.fn, t.args(done))] = t
        finished, _ = cf.wait(list(running), return_when=cf.FIRST_COMPLETED)
        for fut in finished:
            t = running.pop(fut)
            try:
                outcome, value, raised, wall, cpu = fut.result()
            except cf.BrokenExecutor:
                raise OutputError("a report worker process died (killed, or out of memory); nothing was "
                                  "written") from None
            stats[t.name] = (wall, cpu)
            raise_warnings_again(raised)        # as the serial run raises them
            if outcome == "error":
                raise _rebuild(*value)
            done[t.name] = value
            on_done(t.name, value)


# ---------------------------------------------------------------------------------------------
# in the worker
# ---------------------------------------------------------------------------------------------
#: per-worker-process cache (e.g. HDF5 files already read), emptied when the worker starts
WORKER_CACHE: dict = {}


def _call(fn, args) -> tuple:
    """Run ``fn(*args)`` in a worker: ``(outcome, value, warnings, wall s, CPU s)`` with outcome
    ``"ok"`` and the result, or ``"error"`` and an :class:`AcmmError` as data (module, class name,
    message, exit code: its class may not pickle); the warnings it raised travel for the parent to
    raise again (:func:`acmm.stages.pool.portable_warnings`)."""
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings(record=True) as caught:
        try:
            outcome, value = "ok", fn(*args)
        except AcmmError as exc:
            cls = type(exc)
            outcome, value = "error", (cls.__module__, cls.__qualname__, str(exc), getattr(exc, "exit_code", None))
    return outcome, value, portable_warnings(caught), time.perf_counter() - t0, time.process_time() - c0


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
