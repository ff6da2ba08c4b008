"""A progress bar over the steps of an acmm command (the design points, the sweep's tasks), on
stderr and only where :func:`acmm_qpp.cli.progress.enabled` (an interactive terminal)."""
from __future__ import annotations

from acmm_qpp.cli.progress import console, enabled


class Steps:
    """A progress bar over ``total`` steps with elapsed time and ETA (``rate`` adds steps/s).

    Use as a context manager; ``advance(text)`` moves one step and shows ``text``; ``describe(text)``
    only changes the text (e.g. "writing figures" after the last step).  Silent when disabled.

    Parameters
    ----------
    description : str
        Text shown before the bar.
    total : int or None
        Number of steps (None: unknown, the bar pulses).
    rate : bool, optional
        Also show the speed in steps/s.
    refresh_thread : bool, optional
        Redraw from rich's own thread (default); False redraws at each step only, so that no
        thread runs beside a process pool that forks (the design stage's).
    """

    def __init__(self, description: str, total: int | None, rate: bool = False, refresh_thread: bool = True):
        self.description = description
        self.total = total
        self.rate = rate
        self.refresh_thread = refresh_thread
        self._p = None
        self._task = None

    def __enter__(self):
        if enabled():
            from rich.progress import (BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn,
                                       TimeElapsedColumn, TimeRemainingColumn)  # deferred: rich start-up, only on a terminal

            cols = [SpinnerColumn(), TextColumn("{task.description}", markup=False), BarColumn(),
                    MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn()]
            if self.rate:
                cols.insert(4, TextColumn("{task.fields[rate]}", markup=False))
            self._p = Progress(*cols, console=console(), transient=True, auto_refresh=self.refresh_thread)
            self._p.__enter__()
            self._task = self._p.add_task(self.description, total=self.total, rate="")
        return self

    def __exit__(self, *exc):
        if self._p is not None:
            self._p.__exit__(*exc)
        return False

    def advance(self, text: str | None = None, n: int = 1) -> None:
        """Move the bar on by ``n`` steps.

        Parameters
        ----------
        text : str, optional
            New text before the bar (default: keep it).
        n : int, optional
            Number of steps done.
        """
        if self._p is None:
            return
        kw = {} if text is None else {"description": text}
        if self.rate:
            t = self._p.tasks[0]
            speed = t.finished_speed or t.speed
            kw["rate"] = f"{speed:.2f}/s" if speed else ""
        self._p.update(self._task, advance=n, refresh=not self.refresh_thread, **kw)

    def describe(self, text: str) -> None:
        """Change the text before the bar without moving it.

        Parameters
        ----------
        text : str
            New text.
        """
        if self._p is not None:
            self._p.update(self._task, description=text, refresh=not self.refresh_thread)
