"""The report's early worker: a child that runs ready tasks while the main process warms up
for its pool of workers (issue 16; used by :func:`report.runner.run_tasks`).  Process plumbing:
no mathematics of the report."""
from __future__ import annotations

import os
from typing import Optional

from report.runner import _call, _worker_init


class EarlyWorker:
    """A child forked before the pool's warm-up (which takes ~1–2 s of one core in the report:
    imports, the compiled simulator, a first figure) that runs ready tasks meanwhile, so that the
    other core is not idle (issue 16).

    The child starts like a pool worker (:func:`report.runner._worker_init`) and runs, one after
    the other and highest priority first, tasks that depend on none (their arguments are what
    this process would build for them: a task's arguments may rest on what ``on_done`` recorded
    here), each claimed in shared memory under a lock; :meth:`seal` (when the pool starts) ends
    the claiming, and the child exits after its current task.  Each result comes back as one frame through a pipe
    (:func:`common.forked.send_frame`); an :class:`~common.errors.AcmmError` is rebuilt with its
    class and message, another exception is raised again with the child's traceback, and a child
    that dies is the same :class:`~common.errors.OutputError` as a pool worker that dies.  While
    it works it counts as one of the ``jobs`` processes; a failure elsewhere waits for its current
    task, as for the pool's running tasks.

    Parameters
    ----------
    pid : int
        The child's process id.
    fd : int
        The read end of its pipe.
    tasks : list of report.runner.Task
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
        tasks : list of report.runner.Task
            The graph's tasks (their ``priority`` set).
        done : dict
            Results so far (what a task's arguments are built from).

        Returns
        -------
        EarlyWorker or None
            The worker; None when no task is ready or no child may be forked
            (:func:`common.forked.usable`).
        """
        import multiprocessing

        from common.forked import flush_std_streams, usable

        if not any(not t.deps for t in tasks) or not usable():
            return None
        ctx = multiprocessing.get_context("fork")
        claims, lock, sealed = ctx.RawArray("b", len(tasks)), ctx.Lock(), ctx.RawValue("b", 0)
        parent = os.getpid()
        r, w = os.pipe()
        flush_std_streams()
        pid = os.fork()
        if pid == 0:                                     # pragma: no cover (the child)
            from common.signals import die_with_parent

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

        from common.forked import recv_frame

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
            (task name, the :func:`report.runner._call` tuple), or None at the child's normal end.

        Raises
        ------
        common.errors.OutputError
            The child died before it reported every task it claimed.
        Exception
            A task's exception that is not an :class:`~common.errors.AcmmError` (with the child's
            traceback as its cause).
        """
        from common.errors import OutputError

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

    from common.forked import flush_std_streams, send_frame

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
