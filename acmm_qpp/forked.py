"""A call computed in a forked child process while the caller goes on (issue 16).

The design stage solves the 201 local models along the stair-case path (~0.1 s) in a child
while it designs the 12 points, instead of after them::

    models = ForkedCall(path_models_from_specs, specs, settings, 201)
    ...design the points...
    path = models.result()          # the child's result, or computed here and now

The child runs the same code on the same inputs, so the result is the same bit for bit as the
call in place.  :meth:`ForkedCall.result` calls the function in place when no child was forked
(no ``os.fork``, one CPU, another non-daemon thread alive, ``ACMM_FORK=0``) or when the child
failed (so a real error is raised in the caller, with its own type and message).
:meth:`ForkedCall.cancel` (also on garbage collection) kills a child whose result is not wanted.
For pure computations whose result pickles; never inside a process pool's worker (the pool
already uses every core).

The result travels as one length-prefixed pickle through a pipe (:func:`send_frame`,
:func:`recv_frame`, also the framing of the figure worker's and the report's early worker's
pipes): the reader takes exactly that many bytes, so a grandchild that inherited the pipe cannot
hold it up.
"""
from __future__ import annotations

import os
import pickle
import signal
import struct
import sys
import threading

from acmm_qpp.signals import die_with_parent


def usable() -> bool:
    """Whether a child may be forked here.

    Returns
    -------
    bool
        True when ``os.fork`` exists, there is more than one CPU, no non-daemon thread other
        than this one runs and ``ACMM_FORK`` is not ``0``.
    """
    me = threading.current_thread()
    return (os.environ.get("ACMM_FORK", "1") != "0" and hasattr(os, "fork")
            and (os.cpu_count() or 1) > 1
            and all(t.daemon for t in threading.enumerate() if t is not me))


def flush_std_streams() -> None:
    """Flush ``sys.stdout`` and ``sys.stderr`` before a fork or ``os._exit`` (a child must not
    write the parent's buffered output again); a stream closed by the shell (``>&-``, then
    ``None``) or failing to flush is skipped."""
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):
            pass


#: the length prefix of a framed message (unsigned 64-bit, little-endian)
FRAME_HEADER = struct.Struct("<Q")


def read_exact(fd: int, size: int) -> bytes | None:
    """Exactly ``size`` bytes from ``fd``; None at end of file before that (the writer died).

    Parameters
    ----------
    fd : int
        A readable file descriptor (a pipe's read end).
    size : int
        Number of bytes, B.

    Returns
    -------
    bytes or None
        The bytes, or None.
    """
    chunks, got = [], 0
    while got < size:
        chunk = os.read(fd, min(size - got, 1 << 20))
        if not chunk:
            return None
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


def frame(data: bytes) -> bytes:
    """``data`` after its length (:data:`FRAME_HEADER`): one message for :func:`recv_frame`.

    Parameters
    ----------
    data : bytes
        The message.

    Returns
    -------
    bytes
        The framed message.
    """
    return FRAME_HEADER.pack(len(data)) + data


def write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to ``fd`` (a pipe takes a large write in several parts).

    Parameters
    ----------
    fd : int
        A writable file descriptor.
    data : bytes
        The bytes.
    """
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def send_frame(fd: int, data: bytes) -> None:
    """Write ``data`` to ``fd`` as one framed message (:func:`frame`), all of it.

    Parameters
    ----------
    fd : int
        A writable file descriptor (a pipe's write end).
    data : bytes
        The message.
    """
    write_all(fd, frame(data))


def recv_frame(fd: int) -> bytes | None:
    """One message written by :func:`send_frame`: exactly its bytes (so that a process that
    inherited the write end cannot hold the reader up); None when the writer died first.

    Parameters
    ----------
    fd : int
        A readable file descriptor.

    Returns
    -------
    bytes or None
        The message, or None.
    """
    head = read_exact(fd, FRAME_HEADER.size)
    return None if head is None else read_exact(fd, FRAME_HEADER.unpack(head)[0])


def portable_warnings(caught) -> list:
    """Warnings recorded in a child process, ready to send to its parent.

    Each is checked to come back out of a pickle; one that does not (a class defined in a
    function, arguments its class cannot be rebuilt from) travels as its text with the nearest
    built-in category.

    Parameters
    ----------
    caught : list of warnings.WarningMessage
        What ``warnings.catch_warnings(record=True)`` recorded.

    Returns
    -------
    list of tuple
        (message, category, filename, lineno) of each, for :func:`raise_warnings_again`.
    """
    out = []
    for w in caught:
        item = (w.message, w.category, w.filename, w.lineno)
        try:
            pickle.loads(pickle.dumps(item[:2], protocol=pickle.HIGHEST_PROTOCOL))
        except Exception:  # noqa: BLE001
            base = next(c for c in w.category.__mro__ if c.__module__ == "builtins" and issubclass(c, Warning))
            item = (str(w.message), base, w.filename, w.lineno)
        out.append(item)
    return out


def raise_warnings_again(raised: list) -> None:
    """Raise a child's warnings (:func:`portable_warnings`) in this process, each as from the
    module it came from: its filters and its ``__warningregistry__`` apply, so a warning this
    process already showed under "default" or "once" is not shown again, as computing in place
    would not.

    Parameters
    ----------
    raised : list of tuple
        (message, category, filename, lineno) of each warning, in the order raised.
    """
    import warnings

    if not raised:
        return
    by_file = {}
    for mod in list(sys.modules.values()):
        f = getattr(mod, "__file__", None)
        if isinstance(f, str):
            by_file.setdefault(os.path.realpath(f), mod)
    for message, category, filename, lineno in raised:
        mod = by_file.get(os.path.realpath(filename)) if isinstance(filename, str) else None
        if mod is None:
            warnings.warn_explicit(message, category, filename, lineno)
        else:
            warnings.warn_explicit(message, category, filename, lineno, module=mod.__name__,
                                   registry=mod.__dict__.setdefault("__warningregistry__", {}),
                                   module_globals=mod.__dict__)


def _child(fn, args, kwargs, fd: int) -> None:
    """In the child: compute, send ("ok", value, warnings) or ("error", None, []) through ``fd``
    as one frame, flush what it printed, exit.  The warnings the call raised (under the filters
    inherited from the parent) travel along (:func:`portable_warnings`) for the parent to raise
    again (:func:`raise_warnings_again`): a caller recording warnings (the CLI's ``note:``)
    sees them as if computed in place."""
    import warnings

    code = 0
    try:
        with warnings.catch_warnings(record=True) as caught:
            value = fn(*args, **kwargs)
        data = pickle.dumps(("ok", value, portable_warnings(caught)), protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException:  # noqa: BLE001 (the parent computes again in place and raises)
        data, code = pickle.dumps(("error", None, [])), 1
    try:
        flush_std_streams()                 # os._exit does not: what the call printed is kept
        send_frame(fd, data)
    finally:
        os._exit(code)


class ForkedCall:
    """``fn(*args, **kwargs)`` in a forked child, started at construction.

    Parameters
    ----------
    fn : callable
        A pure function whose result pickles.
    *args : object
        Its positional arguments.
    enabled : bool, optional
        False: no child, :meth:`result` calls ``fn`` in place.
    in_place : callable, optional
        What :meth:`result` calls, with the same arguments, when no child was forked or it
        failed (default ``fn``; e.g. ``fn`` with a progress callback the child could not call).
    **kwargs : object
        Its keyword arguments.

    Attributes
    ----------
    forked : bool
        Whether a child was started.
    from_child : bool
        After :meth:`result`: whether the value is the child's (False: computed in place).
    """

    def __init__(self, fn, *args, enabled: bool = True, in_place=None, **kwargs) -> None:
        self._call = (in_place or fn, args, kwargs)
        self.from_child = False
        self._pid: int | None = None
        self._fd: int | None = None
        if enabled and usable():
            r, w = os.pipe()
            flush_std_streams()
            parent = os.getpid()
            pid = os.fork()
            if pid == 0:
                die_with_parent(parent)
                os.close(r)
                _child(fn, args, kwargs, w)
            os.close(w)
            self._pid, self._fd = pid, r
        self.forked = self._pid is not None

    def result(self):
        """The value of the call: the child's, or computed here when there is none or it failed.

        Returns
        -------
        object
            What ``fn(*args, **kwargs)`` returns.
        """
        fn, args, kwargs = self._call
        self.from_child = False
        if self._pid is None:
            return fn(*args, **kwargs)
        fd, self._fd = self._fd, None
        try:
            data = recv_frame(fd) or b""
        finally:
            os.close(fd)
        pid, self._pid = self._pid, None
        os.waitpid(pid, 0)
        try:
            kind, value, raised = pickle.loads(data)
        except Exception:  # noqa: BLE001 (a truncated message: the child died)
            kind, value, raised = "error", None, []
        if kind != "ok":
            return fn(*args, **kwargs)
        self.from_child = True
        raise_warnings_again(raised)
        return value

    def cancel(self) -> None:
        """Kill the child (if it still runs) and drop its result."""
        if self._pid is not None:
            pid, self._pid = self._pid, None
            try:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except (ProcessLookupError, ChildProcessError):
                pass
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __del__(self):
        if getattr(self, "_pid", None) is not None:
            self.cancel()
