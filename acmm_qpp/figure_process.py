"""The figure worker's process side: the forked worker that pre-imports matplotlib (without the
property tables of its docstrings: :func:`acmm_qpp.plot_style.import_pyplot_to_draw_only`), reads the
stage's pickled figure calls from a pipe and draws each in a forked writer (issue 16).

Split from :mod:`acmm_qpp.figure_worker` (issue 12), which holds the stage's side (:func:`~acmm_qpp.figure_worker.submit`,
:func:`~acmm_qpp.figure_worker.session`, ...); see its module docstring for the design.
"""
from __future__ import annotations

import os
import pickle
import signal
import threading

from acmm_qpp.forked import FRAME_HEADER, flush_std_streams, read_exact, recv_frame, send_frame, write_all
from acmm_qpp.plot_style import import_pyplot_to_draw_only
from acmm_qpp.signals import die_with_parent


#: niceness added to the figure worker and its writers (measured on 2 cores: 5 beat 0 and 10)
FIGURE_NICE = 5

_BARRIER = 0xFFFFFFFFFFFFFFFE


def _warm(spec: str | None) -> None:
    """Run the worker's warm-up: ``spec`` names a function as ``"module:function"`` (the
    product's own: its style, its font caches); None draws one small figure on Agg with the
    rcParams left as they are."""
    if spec:
        import importlib

        module, _, name = spec.partition(":")
        getattr(importlib.import_module(module), name)()
        return
    from acmm_qpp.plot_style import agg_pyplot, draw_warm_up_figure

    draw_warm_up_figure(agg_pyplot(force=True))


def _draw(job: bytes, fd: int) -> None:
    """Grandchild: run one pickled call, send back ("ok", paths) or ("error", message)."""
    try:
        fn, args, kwargs = pickle.loads(job[1:])
        res = fn(*args, **kwargs)              # the path written, or a list of them
        msg = ("ok", [str(p) for p in ([res] if isinstance(res, (str, os.PathLike)) else (res or []))])
    except BaseException as exc:  # noqa: BLE001 (reported to the stage through the pipe)
        msg = ("error", str(exc) or type(exc).__name__)
    write_all(fd, pickle.dumps(msg))


def _send_framed(fd: int, obj) -> None:
    send_frame(fd, pickle.dumps(obj))


def _recv_framed(fd: int):
    data = recv_frame(fd)
    return None if data is None else pickle.loads(data)


def _fork_writer(job: bytes, close: tuple, prepare: bytes | None = None) -> tuple[int, int, int | None]:
    """Fork a writer (closing the worker's descriptors ``close`` in it); returns its pid, the read
    end of its result pipe and, for a *reserved* writer (``prepare`` given), the write end of its
    job pipe.  A writer draws ``job``; a reserved one first runs ``prepare`` (the figure's
    skeleton), then waits for its job on that pipe (end of file: it exits having drawn nothing)."""
    r, w = os.pipe()
    jr = jw = None
    if prepare is not None:
        jr, jw = os.pipe()
        _grow_pipe(jw)
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:
        die_with_parent(parent)
        os.close(r)
        for fd in close + ((jw,) if jw is not None else ()):
            os.close(fd)
        try:
            if prepare is not None:
                _prepare(prepare)
                job = recv_frame(jr)
            if job is None:
                os.write(w, pickle.dumps(("ok", [])))
            else:
                _draw(job, w)
        finally:
            os._exit(0)
    os.close(w)
    if jr is not None:
        os.close(jr)
    return pid, r, jw


def _prepare(job: bytes) -> None:
    """Run a prepare job here, for the writers forked later (a failure: the writer builds it)."""
    try:
        fn, args, kwargs = pickle.loads(job[1:])
        fn(*args, **kwargs)
    except Exception:  # noqa: BLE001
        pass


def _split(job: bytes) -> tuple[bytes, str | None, bytes]:
    """(kind, routing key or None, the job as ``kind + pickle``) of a job read from the pipe."""
    kind = job[:1]
    if kind not in (b"D", b"R"):
        return kind, None, job
    n = int.from_bytes(job[1:3], "little")
    return kind, job[3:3 + n].decode() or None, kind + job[3 + n:]


class _Server:
    """The worker's loop state: its writers, the reserved ones by key, what they wrote."""

    def __init__(self, jobs: int, status: int) -> None:
        self.jobs, self.status = jobs, status
        self.running: dict[int, int] = {}          # pid → read end of its result pipe
        self.figure: dict[int, str] = {}           # pid → the figure (function) it draws
        self.reserved: dict[str, tuple[int, int]] = {}   # key → (pid, write end of its job pipe)
        self.written: list[str] = []
        self.errors: list[str] = []
        # one writer per CPU, plus one: the stage itself only writes its HDF5 file meanwhile
        self.slots = (os.cpu_count() or 1) + 1

    def _close_in_child(self) -> tuple:
        return ((self.jobs, self.status) + tuple(self.running.values())
                + tuple(jw for _, jw in self.reserved.values()))

    def _waiting(self) -> set:
        return {pid for pid, _ in self.reserved.values()}

    def join(self, pid: int, quiet: bool = False) -> None:
        fd = self.running.pop(pid)
        with os.fdopen(fd, "rb") as f:
            data = f.read()
        _, st = os.waitpid(pid, 0)
        code = os.waitstatus_to_exitcode(st)
        how = f"killed by signal {-code}" if code < 0 else f"exit {code}"
        failed = f"a figure writer process failed ({self.figure.pop(pid, 'figure')}: {how})"
        try:
            kind, val = pickle.loads(data) if data else ("error", failed)
        except Exception:  # noqa: BLE001 (a writer killed while it sent its result)
            kind, val = "error", failed
        if kind == "ok" and code == 0:
            self.written.extend(val)
        elif not quiet:
            self.errors.append(val if kind == "error" else failed)

    def join_drawing(self) -> None:
        """Join every writer that has its job (not the reserved ones still waiting)."""
        waiting = self._waiting()
        for pid in [p for p in self.running if p not in waiting]:
            self.join(pid)

    def release(self) -> None:
        """Tell the reserved writers that no job comes (they exit having drawn nothing)."""
        for _, jw in self.reserved.values():
            os.close(jw)
        self.reserved.clear()

    def kill(self) -> None:
        for pid in self.running:
            os.kill(pid, signal.SIGKILL)
        for _, jw in self.reserved.values():
            os.close(jw)
        self.reserved.clear()
        for pid in list(self.running):
            os.close(self.running.pop(pid))
            os.waitpid(pid, 0)

    def reserve(self, key: str, job: bytes) -> None:
        """Fork a writer for the figure ``key`` that builds its skeleton (``job``) now."""
        if key in self.reserved:
            return
        pid, fd, jw = _fork_writer(b"", self._close_in_child(), prepare=job)
        self.running[pid] = fd
        self.reserved[key] = (pid, jw)

    def draw(self, key: str | None, job: bytes) -> None:
        """Hand ``job`` to the writer reserved for ``key``, or fork one (within the slots)."""
        if key in self.reserved:
            pid, jw = self.reserved.pop(key)
            self.figure[pid] = key
            try:
                send_frame(jw, job)
                return
            except OSError:     # it died before its job was sent: a fresh writer (after: an error)
                self.join(pid, quiet=True)
            finally:
                os.close(jw)
        waiting = self._waiting()
        while len(self.running) - len(waiting) >= self.slots:
            self.join(next(p for p in self.running if p not in waiting))
        pid, fd, _ = _fork_writer(job, self._close_in_child())
        self.running[pid] = fd
        self.figure[pid] = key or "figure"


def _serve(jobs: int, status: int, warm: str | None = None) -> None:
    """The worker: warm up, then run each job: a prepare here (``P``), a reserved writer that
    builds a figure's skeleton now (``R``), a figure drawn by its reserved writer or a new one
    (``D``; at most one per CPU, plus one, drawing at a time)."""
    code = 0
    sv = _Server(jobs, status)
    try:
        # the stage's own computation is the critical path while the skeletons are built: the
        # worker and its writers yield the CPU to it when both cores are busy (issue 16)
        try:
            os.nice(FIGURE_NICE)
        except (AttributeError, OSError):
            pass
        try:
            import_pyplot_to_draw_only()        # this process only draws: no property tables
        except Exception:  # noqa: BLE001 (the warm-up below imports matplotlib as it is)
            pass
        try:
            _warm(warm)
        except Exception:  # noqa: BLE001 (a real failure shows again, and is reported, in the writer)
            pass
        while True:
            head = read_exact(jobs, FRAME_HEADER.size)
            if head is None:
                break
            (n,) = FRAME_HEADER.unpack(head)
            if n == _BARRIER:                 # report what is done so far (a nested stage ends)
                sv.join_drawing()
                _send_framed(status, (sv.written, sv.errors))
                sv.written, sv.errors = [], []
                continue
            job = read_exact(jobs, n)
            if job is None:
                break
            kind, key, job = _split(job)
            if kind == b"P":
                _prepare(job)
            elif kind == b"R":
                sv.reserve(key, job)
            else:
                sv.draw(key, job)
        sv.release()
        for pid in list(sv.running):
            sv.join(pid)
        _send_framed(status, (sv.written, sv.errors))
    except BaseException:  # noqa: BLE001
        code = 1
        try:
            sv.kill()             # no writer outlives a failed worker
        except BaseException:  # noqa: BLE001
            pass
    finally:
        os._exit(code)


def _grow_pipe(fd: int, size: int = 1 << 20) -> None:
    """Let the job pipe hold a stage's figure data (~0.7 MB for the stair-case) so that the
    sender thread writes each job at once instead of chunk by chunk against the stage's own
    thread (Linux ``F_SETPIPE_SZ``; elsewhere, or refused, the default size)."""
    try:
        import fcntl

        fcntl.fcntl(fd, getattr(fcntl, "F_SETPIPE_SZ", 1031), size)
    except (ImportError, OSError):
        pass


def _own_group(pid: int = 0) -> None:
    """Put the worker (``pid``; 0: this process) in a process group of its own, which its writers
    inherit, so that an abort kills all of them at once (both sides call it: no race)."""
    try:
        os.setpgid(pid, pid)
    except OSError:              # already done by the other side, or the worker has exited
        pass


def _kill_group(pid: int) -> None:
    """SIGKILL the worker's process group (the worker and its writers); the worker alone if the
    group is not there."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except OSError:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


class _Worker:
    """Parent side: the worker's pid, the job pipe (fed by one sender thread), the status pipe."""

    def __init__(self, warm: str | None = None) -> None:
        jr, jw = os.pipe()
        sr, sw = os.pipe()
        _grow_pipe(jw)
        flush_std_streams()
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:                                   # the worker: never returns
            die_with_parent(parent)
            os.close(jw)
            os.close(sr)
            _own_group()
            try:                 # a background group writing a warning to a `stty tostop` terminal
                signal.signal(signal.SIGTTOU, signal.SIG_IGN)
            except (AttributeError, OSError, ValueError):
                pass
            _serve(jr, sw, warm)
        _own_group(pid)
        os.close(jr)
        os.close(sw)
        self.pid, self.jobs, self.status = pid, jw, sr
        self.queue: list[bytes | None] = []
        self.cond = threading.Condition()
        self.failed: BaseException | None = None
        self.thread: threading.Thread | None = None

    def _send_loop(self) -> None:
        while True:
            with self.cond:
                while not self.queue:
                    self.cond.wait()
                item = self.queue.pop(0)
            if item is None:
                return
            try:
                write_all(self.jobs, item)
            except OSError as exc:                 # the worker died: reported by finish()
                self.failed = exc
                return

    def send(self, data: bytes | None) -> None:
        if self.thread is None:
            self.thread = threading.Thread(target=self._send_loop, name="figure-sender", daemon=True)
            self.thread.start()
        with self.cond:
            self.queue.append(data)
            self.cond.notify()

    def close(self, abort: bool = False) -> tuple[list, list, int]:
        """Stop the worker (after the queued jobs, or at once with ``abort``); returns
        (files written, error messages, exit code)."""
        if self.thread is None:               # never used (the config wants no figures): no wait
            _kill_group(self.pid)
            os.close(self.jobs)
            os.close(self.status)
            os.waitpid(self.pid, 0)
            return [], [], 0
        if abort:                 # at once: the worker may be waiting for its writers
            with self.cond:
                self.queue.clear()
            _kill_group(self.pid)
        self.send(None)
        self.thread.join()
        os.close(self.jobs)
        got = _recv_framed(self.status)
        os.close(self.status)
        if got is None:         # the worker died (killed): its writers, orphaned, may still write;
            _kill_group(self.pid)   # its pid is not reaped yet, so the group is still this one
        _, st = os.waitpid(self.pid, 0)
        written, errors = got if got is not None else ([], [])
        return written, errors, os.waitstatus_to_exitcode(st)

    def flush(self) -> tuple[list, list]:
        """Wait until the jobs sent so far are written; returns (files written, error messages)."""
        self.send(FRAME_HEADER.pack(_BARRIER))
        got = _recv_framed(self.status)
        if got is None:         # the worker died (not reaped yet): no orphaned writer may land later
            _kill_group(self.pid)
            return [], ["cannot write the figures: the figure process failed"]
        return got
