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
  process warms up on one core, the ready task of highest priority already runs on a child of
  its own (:class:`_EarlyTask`), so that the other core is not idle for those 1–2 s.

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
    """
    import threading

    if not hasattr(os, "fork"):
        return 1
    env = os.environ.get("ACMM_REPORT_JOBS", "").strip()
    if env.isdigit() and int(env) > 0:
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
    if jobs <= 1 or len(tasks) <= 1 or not hasattr(os, "fork"):
        for t in tasks:              # errors propagate unchanged
            t0, c0 = time.perf_counter(), time.process_time()
            done[t.name] = t.fn(*t.args(done))
            stats[t.name] = (time.perf_counter() - t0, time.process_time() - c0)
            on_done(t.name, done[t.name])
        return done
    _prioritize(tasks)
    # the warm-up below runs on one core: the first task runs meanwhile on a child of its own
    early = _EarlyTask.start(tasks, done)
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
        if early is not None:       # a failure elsewhere: let it finish, like a pool worker's task
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
              early: Optional["_EarlyTask"] = None) -> None:
    import multiprocessing

    waiting = [t for t in tasks if early is None or t is not early.task]
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("fork"),
                                  initializer=_worker_init, initargs=(os.getpid(),))
    running: dict[cf.Future, Task] = {}

    def finish(t: Task, out: tuple) -> None:
        stats[t.name] = out[-2:]
        done[t.name] = _unwrap_value(out)
        on_done(t.name, done[t.name])

    try:
        while waiting or running or early is not None:
            ready = sorted((t for t in waiting if all(d in done for d in t.deps)), key=lambda t: -t.priority)
            for t in ready[: max(0, jobs - len(running) - (early is not None))]:
                waiting.remove(t)
                sys.stdout.flush()
                sys.stderr.flush()
                running[pool.submit(_call, t.fn, t.args(done))] = t
            finished: set = set()
            if early is None:
                finished, _ = cf.wait(list(running), return_when=cf.FIRST_COMPLETED)
            else:          # poll the pool's futures and the early child's pipe in turn
                if running:
                    finished, _ = cf.wait(list(running), timeout=0.05, return_when=cf.FIRST_COMPLETED)
                if early.ready(0.0 if running else None):
                    task, out = early.task, early.result()
                    early = None
                    finish(task, out)
            for fut in finished:
                finish(running.pop(fut), _result(fut))
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


class _EarlyTask:
    """The ready task of highest priority, run on a child forked before the pool's warm-up (which
    takes ~1–2 s of one core in the report: imports, the compiled simulator, a first figure)
    so that the other core is not idle meanwhile (issue 16).

    The child (:class:`common.forked.ForkedCall`, never computed twice) starts like a pool worker
    (:func:`_worker_init`) and runs the task through :func:`_call`; an exception that is not an
    :class:`~common.errors.AcmmError` is raised here again with the child's traceback, and a child
    that dies is the same :class:`~common.errors.OutputError` as a pool worker that dies.  It
    counts as one of the ``jobs`` processes (the pool runs one task fewer while it runs), and a
    failure elsewhere waits for it as for the pool's running tasks.
    """

    def __init__(self, task: Task, call) -> None:
        self.task, self.call = task, call

    @classmethod
    def start(cls, tasks: list[Task], done: dict) -> Optional["_EarlyTask"]:
        """Fork the child for the ready task of highest priority (the first of equals, as the
        pool would pick it); None when nothing is ready or no child may be forked
        (:func:`common.forked.usable`)."""
        from common.forked import ForkedCall, usable

        ready = [t for t in tasks if not t.deps]
        if not ready or not usable():
            return None
        task = max(ready, key=lambda t: t.priority)
        call = ForkedCall(_early_call, os.getpid(), task.fn, task.args(done), fallback=False)
        return cls(task, call) if call.forked else None

    def ready(self, timeout: Optional[float]) -> bool:
        """Whether the child has sent its result (or died); waits up to ``timeout`` s (None: until then)."""
        return self.call.ready(timeout)

    def result(self) -> tuple:
        """The :func:`_call` tuple of the task (waits for the child)."""
        from common.errors import OutputError
        from common.forked import ChildDied

        try:
            kind, *value = self.call.result()
        except ChildDied:
            raise OutputError("a report worker process died (killed, or out of memory); nothing was written") from None
        if kind == "raise":
            exc, tb = value
            raise exc from _ChildTraceback(tb)
        return value[0]

    def finish(self) -> None:
        """Wait until the child's task is over (its files written: a failure elsewhere, like the
        pool's running tasks), then reap it; killed at once if that wait is interrupted."""
        try:
            self.call.ready(None)
        finally:
            self.call.cancel()


class _ChildTraceback(Exception):
    """The traceback of an exception raised in the early task's child (its text)."""

    def __str__(self) -> str:
        return "\n" + self.args[0]


def _early_call(parent: int, fn, args) -> tuple:
    """In :class:`_EarlyTask`'s child: start as a worker and run ``fn(*args)``; ("out", the
    :func:`_call` tuple), or ("raise", exception, traceback text) for any other exception."""
    import pickle
    import traceback

    if os.getpid() != parent:
        _worker_init(parent)
    try:
        out = ("out", _call(fn, args))
        pickle.dumps(out)                 # a result that does not pickle: its own error, not a death
        return out
    except BaseException as exc:  # noqa: BLE001 (raised again in the parent)
        tb = traceback.format_exc()
        try:
            pickle.dumps(exc)
        except Exception:  # noqa: BLE001 (an exception that does not pickle)
            exc = RuntimeError(repr(exc))
        return ("raise", exc, tb)


# ---------------------------------------------------------------------------------------------
# in the worker
# ---------------------------------------------------------------------------------------------
#: per-worker-process cache (e.g. HDF5 files already read), emptied when the worker starts
WORKER_CACHE: dict = {}


def _worker_init(parent: int) -> None:
    from common.workers import die_with_parent

    WORKER_CACHE.clear()
    os.environ["ACMM_FORK"] = "0"      # the pool uses the cores: no stage forks a child of its own
    die_with_parent(parent)


def _call(fn, args):
    """Run ``fn(*args)``: ``("ok", result, wall, cpu)``, or an :class:`AcmmError` as data
    ``("error", module, class name, message, exit code, wall, cpu)`` (its class may not pickle)."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        out = ("ok", fn(*args))
    except AcmmError as exc:
        cls = type(exc)
        out = ("error", cls.__module__, cls.__qualname__, str(exc), getattr(exc, "exit_code", None))
    return out + (time.perf_counter() - t0, time.process_time() - c0)


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
