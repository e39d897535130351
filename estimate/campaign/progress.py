"""Progress of a campaign as a whole, on one terminal line: tasks done, failed and running,
taken from the store, and the time left."""

from __future__ import annotations

import sys
from typing import TextIO

__all__ = ["Progress"]


def _clock(seconds: float) -> str:
    m, s = divmod(int(round(seconds)), 60)
    h, m = divmod(m, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class Progress:
    """A one-line campaign progress display, shown only on a terminal.

    Each task has a *work*, a measure proportional to its run time (the runner gives the
    bytes of data it fits, times the cost of a diagnosis over a fit); the time left is the
    work left at the seconds per unit of work of the tasks finished so far, shared by the
    workers (or by the tasks left, when fewer). Without work figures the mean task time is used.

    Parameters
    ----------
    workers : int
        Tasks that run at once (for the running count and the time left).
    stream : text file, default sys.stderr
    enabled : bool, optional
        Default: when ``stream`` is a terminal.
    """

    def __init__(self, workers: int, *, stream: TextIO | None = None,
                 enabled: bool | None = None) -> None:
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.workers = max(1, workers)
        self.total = self.done = self.failed = self.reused = self.submitted = 0
        self._work_total = self._work_finished = 0.0
        self._planned: tuple[int, float] = (0, 0.0)
        self._timed: list[tuple[float, float]] = []        # (seconds, work) of tasks run

    def plan(self, tasks: int, work: float = 0.0) -> None:
        """Tasks of a later stage, not known one by one yet (counted until ``plan(0)``):
        the groups, whose members are known once the records are fitted."""
        self._planned = (tasks, work)      # shown with the next event

    def expect(self, tasks: int, work: float = 0.0) -> None:
        """``tasks`` more tasks of ``work`` in all belong to the campaign (run or taken from
        the store)."""
        self.total += tasks
        self._work_total += work
        self._show()

    def from_store(self, tasks: int, work: float = 0.0) -> None:
        self.reused += tasks
        self._work_finished += work
        self._show()

    def submit(self, tasks: int) -> None:
        self.submitted += tasks
        self._show()

    def finish(self, ok: bool, seconds: float, work: float = 0.0) -> None:
        """A task of ``work`` ended (``ok`` False: it failed) after ``seconds`` (0: it did
        not run, e.g. its data did not load; it then tells nothing of the time left)."""
        self.done += ok
        self.failed += not ok
        self._work_finished += work
        if seconds > 0:
            self._timed.append((seconds, work))
        self._show()

    @property
    def running(self) -> int:
        return min(self.workers, self.submitted - self.done - self.failed)

    def _eta(self) -> float | None:
        if not self._timed:
            return None
        seconds = sum(s for s, _ in self._timed)
        work = sum(w for _, w in self._timed)
        tasks, planned = self._planned
        left = self.total + tasks - self.done - self.failed - self.reused
        share = min(self.workers, left)     # the last tasks leave workers idle
        left_work = self._work_total + planned - self._work_finished
        if work > 0 and left_work > 0:
            return left_work * seconds / work / share
        return left * seconds / len(self._timed) / share

    def line(self) -> str:
        finished = self.done + self.failed + self.reused
        total = self.total + self._planned[0]
        text = (f"campaign: {finished}/{total} tasks done ({self.reused} from the store), "
                f"{self.failed} failed, {self.running} running")
        eta = self._eta() if finished < total else None
        if eta is not None:
            text += f", about {_clock(eta)} left"
        return text

    def _show(self) -> None:
        if self.enabled:
            print(f"\r\033[K{self.line()}", end="", file=self.stream, flush=True)

    def close(self) -> None:
        if self.enabled:
            print(file=self.stream, flush=True)
