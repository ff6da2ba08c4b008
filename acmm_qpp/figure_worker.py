"""Stage figures drawn by a pre-importing child process while the stage computes (issue 16).

A stage's figures cost three things: importing matplotlib (~0.5 s of CPU), building the
artists and drawing/encoding them.  None of it needs anything back, so the stages (``acmm
design``/``simulate``, ``qpp design``/``simulate``) fork one *figure worker* when they start
(the shared base of both products: each passes its own warm-up, ``"module:function"``, e.g.
:func:`acmm.plots.base.warm_figure_worker`): it imports matplotlib and warms the
font caches on the second core while the stage designs or simulates; the stage then hands it
each figure as a call of a module-level function (e.g. of :mod:`acmm.plots`) on arrays (pickled
through a pipe by a sender thread, so the stage goes on writing its HDF5 file meanwhile).  The
worker draws each figure in a forked grandchild (at most one per CPU, plus one, at a time), so the
figures are drawn in parallel with each other and with the HDF5 write.

    with figure_worker.session(want_figures):   # forks the worker (when possible)
        ...compute...
        figure_worker.submit(plots.summary, orbits, err, ...)
        ...write the HDF5 file...
    # leaving the block joins the worker: raises OutputError if a figure failed, records the
    # files written (acmm_qpp.outputs) so the stage's pruning keeps them

If the block raises, the worker and its writers are killed (figures are written atomically, so
no partial file is left) and the exception propagates.

The worker is used only where forking is safe and pays: POSIX ``os.fork``, more than one CPU,
and no other Python thread alive in the process but daemon helpers (the terminal progress bar's
refresh thread; the worker never touches what they hold).  In a process with other threads (a
Dask worker, a thread pool) every call runs in place, as it does without a session.
``ACMM_FIGURE_WORKER=0`` turns it off.

The process side (the worker's loop, its writers, the pipe framing) is in
:mod:`acmm_qpp.figure_process`.
"""
from __future__ import annotations

import contextlib
import os
import pickle
from pathlib import Path

from acmm_qpp.figure_process import _Worker
from acmm_qpp.forked import frame

#: the running worker of this process (None: calls run in place)
_WORKER: "_Worker | None" = None

#: without a worker: the figure calls of each open session, innermost last (drawn when it ends)
_DEFERRED: list = []


def usable() -> bool:
    """Whether a figure worker may be forked here (see the module docstring).

    Returns
    -------
    bool
        True when :func:`acmm_qpp.forked.usable` (``os.fork``, more than one CPU, no non-daemon
        thread other than this one, ``ACMM_FORK`` not ``0``) and ``ACMM_FIGURE_WORKER`` is not
        ``0``.
    """
    from acmm_qpp.forked import usable as fork_usable

    return os.environ.get("ACMM_FIGURE_WORKER", "1") != "0" and fork_usable()


#: True while the running worker was forked ahead by :func:`start_early` and no session owns it yet
_UNOWNED = False


def start(warm: str | None = None) -> bool:
    """Fork the figure worker if :func:`usable` and none is running, or adopt the one forked
    ahead by :func:`start_early`.

    Parameters
    ----------
    warm : str, optional
        The worker's warm-up, ``"module:function"`` (imported and called in the worker before
        its first figure: the product's style and font caches); None: one small figure on Agg.

    Returns
    -------
    bool
        True if this call started (or adopted) the worker (the caller then owns it).
    """
    global _WORKER, _UNOWNED
    if _UNOWNED and _WORKER is not None:
        _UNOWNED = False
        return True
    if _WORKER is not None or not usable():
        return False
    _WORKER = _Worker(warm)
    return True


def start_early(warm: str | None = None) -> bool:
    """Fork the worker now, before the command's own imports and argument parsing (the ``acmm``
    entry point calls this for ``design``/``simulate``), so that matplotlib is imported on the
    second core ~0.2 s sooner; the stage's :func:`session` adopts it.  A worker that no session
    adopts (a usage error, ``--help``) is killed when the process exits.

    Parameters
    ----------
    warm : str, optional
        The worker's warm-up (see :func:`start`).

    Returns
    -------
    bool
        True if a worker was forked.
    """
    global _UNOWNED
    if not start(warm):
        return False
    _UNOWNED = True
    import atexit

    atexit.register(_drop_unowned)
    return True


def _drop_unowned() -> None:
    """Kill a worker forked by :func:`start_early` that no session adopted."""
    global _UNOWNED
    if _UNOWNED:
        _UNOWNED = False
        abort()


def active() -> bool:
    """Whether a figure worker is running (then :func:`submit` hands calls to it).

    Returns
    -------
    bool
        True while a worker runs in this process.
    """
    return _WORKER is not None


def submit(fn, *args, **kwargs) -> None:
    """``fn(*args, **kwargs)`` (a module-level function that draws and writes one figure and
    returns the path or paths written) in the worker when one is running; else when the
    innermost :func:`session` ends (after the stage wrote its results, as the worker would
    finish), or here and now outside any session.

    Parameters
    ----------
    fn : callable
        Module-level figure function (picklable by reference), e.g. :func:`acmm.plots.summary`.
    *args : object
        Its positional arguments (picklable: arrays, numbers, strings, paths).
    **kwargs : object
        Its keyword arguments (picklable).
    """
    if _WORKER is None:
        if _DEFERRED:
            _DEFERRED[-1].append((fn, args, kwargs))
        else:
            fn(*args, **kwargs)
        return
    _WORKER.send(_job(b"D", fn, args, kwargs, fn.__name__))


def _job(kind: bytes, fn, args, kwargs, key: str | None = None) -> bytes:
    head = kind
    if kind in (b"D", b"R"):
        k = (key or "").encode()
        head += len(k).to_bytes(2, "little") + k
    data = head + pickle.dumps((fn, args, kwargs), protocol=pickle.HIGHEST_PROTOCOL)
    return frame(data)


def prepare(fn, *args, for_figure: str | None = None, **kwargs) -> None:
    """``fn(*args, **kwargs)`` ahead of a figure (e.g. :func:`acmm.plots.prebuild`: build its
    skeleton while the stage computes); without a worker, nothing.  A failure is ignored (the
    figure is then built by its writer, which reports errors).

    With ``for_figure`` (the name of the figure function submitted later) the worker forks that
    figure's writer now: it runs ``fn`` at once, in parallel with the other figures' skeletons,
    and then draws the figure as soon as :func:`submit` hands it over.  Without, ``fn`` runs in
    the worker itself, before the writers forked later.

    Parameters
    ----------
    fn : callable
        Module-level function (picklable by reference).
    *args : object
        Its positional arguments (picklable).
    for_figure : str, optional
        ``__name__`` of the figure function whose writer runs ``fn`` (e.g. ``"summary"``).
    **kwargs : object
        Its keyword arguments (picklable).
    """
    if _WORKER is not None:
        _WORKER.send(_job(b"R" if for_figure else b"P", fn, args, kwargs, for_figure))


def finish() -> list[Path]:
    """Wait for every submitted figure and stop the worker.

    Returns
    -------
    list of pathlib.Path
        The files written (empty without a worker).

    Raises
    ------
    OutputError
        A figure could not be written (the first failure's message), or the worker failed.
    """
    global _WORKER
    w, _WORKER = _WORKER, None
    if w is None:
        return []
    try:
        written, errors, code = w.close()
    except BaseException:       # interrupted while waiting: no figure may land after the stage
        _kill_worker(w)         # rolls its folder back (acmm_qpp.outputs)
        raise
    if not errors and (code != 0 or w.failed is not None):
        how = f" (killed by signal {-code})" if code < 0 else (f" (exit {code})" if code else "")
        errors = [f"cannot write the figures: the figure process failed{how}"]
    return _report(written, errors)


def _report(written: list, errors: list) -> list[Path]:
    from acmm_qpp.errors import FigureError
    from acmm_qpp.outputs import record_written

    for p in written:
        record_written(p)
    if errors:
        raise FigureError(errors[0])
    return [Path(p) for p in written]


def flush() -> list[Path]:
    """Wait for the figures submitted so far (the worker keeps running); returns the files
    written and records them (:func:`acmm_qpp.outputs.record_written`).

    Returns
    -------
    list of pathlib.Path
        The files written since the last flush (empty without a worker).

    Raises
    ------
    OutputError
        A figure could not be written (the first failure's message).
    """
    global _WORKER
    w = _WORKER
    if w is None:
        return []
    try:
        got = w.flush()
    except BaseException:       # interrupted while waiting: stop the shared worker (see finish)
        _WORKER = None
        _kill_worker(w)
        raise
    return _report(*got)


def _kill_worker(w) -> None:
    """SIGKILL a worker's process group (its writers with it) and reap it; never raises."""
    from acmm_qpp.figure_process import _kill_group

    _kill_group(w.pid)
    try:
        os.waitpid(w.pid, 0)
    except OSError:
        pass



def abort() -> None:
    """Stop the worker at once, dropping the figures not yet written."""
    global _WORKER
    w, _WORKER = _WORKER, None
    if w is not None:
        w.close(abort=True)


@contextlib.contextmanager
def session(enabled: bool = True, warm: str | None = None):
    """A stage's figures: fork the worker now (see the module docstring); on leaving, join it
    (:func:`finish`) or, when the block raised, :func:`abort` it.  The ``acmm`` command opens one
    around the stage already (the worker then starts before the stage's imports); a worker that
    was never handed anything is killed at once.  A nested session (the
    design run by ``acmm simulate``) shares the outer one's worker and on leaving waits for
    its own figures (:func:`flush`), so that they are recorded before its stage prunes; when
    its block raises it stops the shared worker too (the command fails), so that no figure
    lands after its stage removed what it wrote.
    Without a worker (no fork possible, ``ACMM_FIGURE_WORKER=0``) the session's figures are
    drawn here when it ends, all of them even if one fails (the first failure is raised): as
    with a worker, a figure that cannot be written leaves the stage's results written.

    Parameters
    ----------
    enabled : bool, optional
        Whether the stage draws figures at all (False: no worker is started or waited for).
    warm : str, optional
        The worker's warm-up when this session starts it (see :func:`start`).
    """
    owner = start(warm) if enabled else False
    deferred = enabled and _WORKER is None
    if deferred:
        _DEFERRED.append([])
    try:
        yield
    except BaseException:
        # the stage fails: its figures stop now, also in a nested session (the design run by
        # `acmm simulate`), before the stage removes what it wrote (acmm_qpp.outputs)
        if owner or (enabled and _WORKER is not None):
            abort()
        raise
    finally:
        calls = _DEFERRED.pop() if deferred else []
    if owner:
        finish()
    elif enabled:
        flush()
    _draw_in_place(calls)


def _draw_in_place(calls: list) -> None:
    """Draw deferred figure calls in order; the first failure is raised after the others."""
    from acmm_qpp.errors import FigureError

    first = None
    for fn, args, kwargs in calls:
        try:
            fn(*args, **kwargs)
        except Exception as exc:  # noqa: BLE001 (raised once the others are drawn)
            first = first or exc
    if first is not None:     # as a writer of the worker reports it: the results are written
        err = FigureError.of(first)
        raise err from (None if err is first else first)
