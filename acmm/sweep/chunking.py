"""How the sweep's tasks are cut into chunks for the executors (guided self-scheduling, issue 16):
sizes from the run's own measured throughput, so that a task's fixed cost stays a few per cent at
any number of workers and the last chunks leave no worker idle (docs/performance.md)."""
from __future__ import annotations

import math
import time
from typing import Optional

#: cases per task while the cost of a case is not yet measured (the first chunk of each worker):
#: 64 10-orbit cases are ~0.2–2 s of work
MAX_CHUNK = 64
#: chunks per worker aimed at over the rest of the sweep (guided: the chunks shrink towards the
#: end, so that the last ones do not leave workers idle)
CHUNKS_PER_WORKER = 8
#: work per task (s) once the cost of a case is measured: at least this, so that the fixed cost
#: of a task (a few ms of scheduler, client and worker time on Dask) stays a few per cent at any
#: number of workers and the scheduler sees at most ~10 tasks per second per worker ...
MIN_TASK_SECONDS = 0.1
#: ... and at most this, so that progress, the journal and an interruption stay live
MAX_TASK_SECONDS = 1.0


def chunk_size(n_tasks: int, workers: int, case_seconds: Optional[float] = None,
               n_total: Optional[int] = None) -> int:
    """Cases per task when ``n_tasks`` cases remain for ``workers`` workers (a pool or a Dask
    cluster; the in-process executor runs one case per task).

    ⌈n / (8·workers)⌉: about 8 tasks per worker over what remains (the tail imbalance is then
    ≤ 1/8 of a worker's remaining share).  Without ``case_seconds`` (the cost of one case on one
    worker, s; not yet measured) it is clipped to [1, :data:`MAX_CHUNK`]; with it, to the cases
    that take :data:`MIN_TASK_SECONDS` … :data:`MAX_TASK_SECONDS`, and never above
    ⌈``n_total`` / workers⌉ (every worker gets a share of a small sweep; ``n_total``: the tasks of
    the whole sweep, default ``n_tasks``).  See docs/performance.md for why this holds at large N.

    Parameters
    ----------
    n_tasks : int
        Tasks still to hand out.
    workers : int
        Number of workers.
    case_seconds : float, optional
        Measured cost of one case on one worker, s (None: not measured yet).
    n_total : int, optional
        Tasks of the whole sweep (default ``n_tasks``).

    Returns
    -------
    int
        Cases per task.
    """
    n_workers = max(1, workers)
    c = -(-n_tasks // (CHUNKS_PER_WORKER * n_workers))
    if case_seconds is None or not case_seconds > 0:
        return max(1, min(MAX_CHUNK, c))
    lo = max(1, math.ceil(MIN_TASK_SECONDS / case_seconds))
    hi = max(lo, int(MAX_TASK_SECONDS / case_seconds))
    return max(1, min(max(c, lo), hi, -(-(n_total or n_tasks) // n_workers)))


class Chunker:
    """The tasks handed out in chunks as they are submitted (guided self-scheduling).

    Each chunk holds consecutive case tasks of one base (a margin search alone).  Its size is
    ``size`` when given, else :func:`chunk_size` of the tasks still to hand out with the cost of
    a case measured so far: ``workers`` × the time since the first chunk came back / the cases
    that came back since (the throughput of the whole run, so it includes every per-task cost;
    before every worker can have returned a chunk, unmeasured).  The results do not depend on
    the chunking.

    Parameters
    ----------
    tasks : list of tuple
        Tasks ``("case", base, index)`` or ``("margin", base, direction)``, in order.
    workers : int
        Number of workers (Dask: worker threads).
    size : int, optional
        Fixed cases per chunk (None: guided, as above).
    """

    def __init__(self, tasks: list, workers: int, size: Optional[int] = None):
        self._tasks, self._pos = tasks, 0
        self.workers = max(1, workers)
        self.size = size
        self._first_back: Optional[float] = None
        self._cases_since = 0
        self._chunks_since = 0

    def case_seconds(self) -> Optional[float]:
        """Measured cost of one case on one worker.

        Returns
        -------
        float or None
            Cost of one case, s; None before there is a measure.
        """
        if self._first_back is None or self._chunks_since < self.workers or self._cases_since == 0:
            return None
        return self.workers * (time.monotonic() - self._first_back) / self._cases_since

    def returned(self, n_tasks: int) -> None:
        """Record that a chunk came back.

        Parameters
        ----------
        n_tasks : int
            Tasks in the chunk.
        """
        if self._first_back is None:
            self._first_back = time.monotonic()
        else:
            self._chunks_since += 1
            self._cases_since += n_tasks

    def next(self) -> Optional[list]:
        """The next chunk.

        Returns
        -------
        list of tuple or None
            Its tasks, or None when every task was handed out.
        """
        tasks, pos = self._tasks, self._pos
        if pos >= len(tasks):
            return None
        size = self.size or chunk_size(len(tasks) - pos, self.workers, self.case_seconds(), len(tasks))
        chunk = [tasks[pos]]
        pos += 1
        if chunk[0][0] == "case":
            while (pos < len(tasks) and len(chunk) < size and tasks[pos][0] == "case"
                   and tasks[pos][1] == chunk[0][1]):
                chunk.append(tasks[pos])
                pos += 1
        self._pos = pos
        return chunk
