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
  (:class:`acmm.report.runner.EarlyWorker`), so that the other core is not idle for those 1–2 s.

The results are the same either way: every task is a deterministic function of its arguments and
of files its dependencies wrote completely before it starts.

Failures: a task that raises an :class:`~acmm_qpp.errors.AcmmError` in a worker is re-raised here
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

from acmm_qpp.errors import AcmmError
from acmm_qpp.workers import stop_pool, submit
from typing import Optional


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
        from acmm_qpp.errors import ConfigError

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
    acmm_qpp.errors.AcmmError
        The first error a task raised (re-built with its class and message when it came from a
        worker); :class:`~acmm_qpp.errors.OutputError` if a worker process died.
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
        from acmm_qpp.forked import raise_warnings_again

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
    from acmm_qpp.workers import pool_worker

    pool_worker(parent)                # Ctrl-C is the parent's; dies with it
    WORKER_CACHE.clear()
    os.environ["ACMM_FORK"] = "0"      # the pool uses the cores: no stage forks a child of its own


def _call(fn, args):
    """Run ``fn(*args)``: ``("ok", result, warnings, wall, cpu)``, or an :class:`AcmmError` as
    data ``("error", module, class name, message, exit code, warnings, wall, cpu)`` (its class may
    not pickle); the warnings it raised travel for the parent to raise again
    (:func:`acmm_qpp.forked.portable_warnings`)."""
    import warnings

    from acmm_qpp.forked import portable_warnings

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
        from acmm_qpp.errors import OutputError

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


# ------------------------------------------------------------------------------------------------
# The report's early worker: a child that runs ready tasks while the main process warms up
# for its pool of workers (issue 16; used by :func:`acmm.report.runner.run_tasks`).  Process plumbing:
# no mathematics of the report.


class EarlyWorker:
    """A child forked before the pool's warm-up (which takes ~1–2 s of one core in the report:
    imports, the compiled simulator, a first figure) that runs ready tasks meanwhile, so that the
    other core is not idle (issue 16).

    The child starts like a pool worker (:func:`acmm.report.runner._worker_init`) and runs, one after
    the other and highest priority first, tasks that depend on none (their arguments are what
    this process would build for them: a task's arguments may rest on what ``on_done`` recorded
    here), each claimed in shared memory under a lock; :meth:`seal` (when the pool starts) ends
    the claiming, and the child exits after its current task.  Each result comes back as one frame through a pipe
    (:func:`acmm_qpp.forked.send_frame`); an :class:`~acmm_qpp.errors.AcmmError` is rebuilt with its
    class and message, another exception is raised again with the child's traceback, and a child
    that dies is the same :class:`~acmm_qpp.errors.OutputError` as a pool worker that dies.  While
    it works it counts as one of the ``jobs`` processes; a failure elsewhere waits for its current
    task, as for the pool's running tasks.

    Parameters
    ----------
    pid : int
        The child's process id.
    fd : int
        The read end of its pipe.
    tasks : list of acmm.report.runner.Task
        The graph's tasks, in order (the claims are indexed like them).
    claims : multiprocessing.RawArray of int8
        Per task: 0 free, 1 claimed by the child.
    lock : multiprocessing.Lock
        Guards ``claims`` and ``sealed``.
    sealed : multiprocessing.RawValue of int8
        1 once the pool has started: the child claims nothing more.
    """

    def __init__(self, pid: int, fd: int, tasks: list, claims, lock, sealed) -> None:
        self._pid, self._fd = pid, fd
        self._tasks, self._claims, self._lock, self._sealed = tasks, claims, lock, sealed
        self._owned: Optional[set] = None          # set by seal()
        self._reported: set = set()

    @classmethod
    def start(cls, tasks: list, done: dict) -> Optional["EarlyWorker"]:
        """Fork the child.

        Parameters
        ----------
        tasks : list of acmm.report.runner.Task
            The graph's tasks (their ``priority`` set).
        done : dict
            Results so far (what a task's arguments are built from).

        Returns
        -------
        EarlyWorker or None
            The worker; None when no task is ready or no child may be forked
            (:func:`acmm_qpp.forked.usable`).
        """
        import multiprocessing

        from acmm_qpp.forked import flush_std_streams, usable

        if not any(not t.deps for t in tasks) or not usable():
            return None
        ctx = multiprocessing.get_context("fork")
        claims, lock, sealed = ctx.RawArray("b", len(tasks)), ctx.Lock(), ctx.RawValue("b", 0)
        parent = os.getpid()
        r, w = os.pipe()
        flush_std_streams()
        pid = os.fork()
        if pid == 0:                                     # pragma: no cover (the child)
            from acmm_qpp.signals import die_with_parent

            die_with_parent(parent)
            os.close(r)
            _early_worker(parent, tasks, dict(done), claims, lock, sealed, w)
        os.close(w)
        return cls(pid, r, tasks, claims, lock, sealed)

    def seal(self) -> set:
        """Stop the child from claiming more tasks.

        Returns
        -------
        set of str
            The names of the tasks it has claimed (run or running).
        """
        with self._lock:
            self._sealed.value = 1
            self._owned = {t.name for i, t in enumerate(self._tasks) if self._claims[i] == 1}
        return set(self._owned)

    @property
    def busy(self) -> bool:
        """Whether a task it claimed has not been reported yet (after :meth:`seal`)."""
        return self._fd is not None and bool(self._owned - self._reported)

    def ready(self, timeout: Optional[float]) -> bool:
        """Whether a result (or the child's end) is there.

        Parameters
        ----------
        timeout : float or None
            Longest wait, s (None: until then).

        Returns
        -------
        bool
            Whether :meth:`next_result` would not wait for a task.
        """
        import select

        poller = select.poll()              # not select.select: any fd number (≥ 1024 too)
        poller.register(self._fd, select.POLLIN | select.POLLHUP | select.POLLERR)
        return bool(poller.poll(None if timeout is None else max(0, int(timeout * 1000))))

    def _next_frame(self):
        """The next message from the child (None at its end); closes the pipe at its end and
        says whether tasks it claimed were never reported (``(None, True)``: it died)."""
        import pickle

        from acmm_qpp.forked import recv_frame

        data = recv_frame(self._fd)
        msg = pickle.loads(data) if data else None
        if msg is None:
            self._close()
            return None, self._owned is not None and bool(self._owned - self._reported)
        self._reported.add(msg[0])
        return msg, False

    def next_result(self) -> Optional[tuple]:
        """The child's next result.

        Returns
        -------
        tuple or None
            (task name, the :func:`acmm.report.runner._call` tuple), or None at the child's normal end.

        Raises
        ------
        acmm_qpp.errors.OutputError
            The child died before it reported every task it claimed.
        Exception
            A task's exception that is not an :class:`~acmm_qpp.errors.AcmmError` (with the child's
            traceback as its cause).
        """
        from acmm_qpp.errors import OutputError

        msg, died = self._next_frame()
        if msg is None:
            if died:
                raise OutputError("a report worker process died (killed, or out of memory); nothing was written")
            return None
        name, (kind, *value) = msg
        if kind == "raise":
            exc, tb = value
            raise exc from _ChildTraceback(tb)
        return name, value[0]

    def finish(self) -> None:
        """After a failure (or at the end): seal, let the current task finish (its files
        complete), then reap the child; killed at once if that wait is interrupted."""
        try:
            if self._owned is None:
                self.seal()
            while self._fd is not None:       # its messages are dropped: the first error is
                try:                          # already on its way, or the graph is done
                    if self._next_frame()[0] is None:
                        break
                except Exception:  # noqa: BLE001 (a message that does not unpickle)
                    pass
        finally:
            self._close(kill=True)

    def _close(self, kill: bool = False) -> None:
        import signal

        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self._pid is not None:
            pid, self._pid = self._pid, None
            try:
                if kill:
                    os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except (ProcessLookupError, ChildProcessError):
                pass


class _ChildTraceback(Exception):
    """The traceback of an exception raised in the early worker's child (its text)."""

    def __str__(self) -> str:
        return "\n" + self.args[0]


def _early_worker(parent: int, tasks: list, done: dict, claims, lock, sealed, fd: int) -> None:  # pragma: no cover (the child)
    """In :class:`EarlyWorker`'s child: start as a worker; claim and run the tasks without
    dependencies until sealed, none is left or one fails; send one frame per task, then
    ``None``; exit."""
    import pickle
    import traceback

    from acmm_qpp.forked import flush_std_streams, send_frame

    code = 0
    try:
        _worker_init(parent)
        while True:
            with lock:
                ready = [i for i, t in enumerate(tasks) if claims[i] == 0 and not t.deps]
                if sealed.value or not ready:
                    break
                i = max(ready, key=lambda i: tasks[i].priority)     # the first of equals
                claims[i] = 1
            t = tasks[i]
            try:
                out = _call(t.fn, t.args(done))
                msg = pickle.dumps((t.name, ("out", out)), protocol=pickle.HIGHEST_PROTOCOL)
            except BaseException as exc:  # noqa: BLE001 (raised again in the parent)
                tb = traceback.format_exc()
                try:
                    msg = pickle.dumps((t.name, ("raise", exc, tb)), protocol=pickle.HIGHEST_PROTOCOL)
                except Exception:  # noqa: BLE001 (an exception that does not pickle)
                    msg = pickle.dumps((t.name, ("raise", RuntimeError(repr(exc)), tb)))
                out = None
            flush_std_streams()
            send_frame(fd, msg)
            if out is None or out[0] != "ok":
                break                                   # a failure: the parent stops the graph
        send_frame(fd, pickle.dumps(None))
    except BaseException:  # noqa: BLE001 (the parent sees the frames stop: a dead worker)
        code = 1
    finally:
        flush_std_streams()
        os._exit(code)
