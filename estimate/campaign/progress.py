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
        self._seconds: list[float] = []

    def expect(self, tasks: int) -> None:
        """``tasks`` more tasks belong to the campaign (run or taken from the store)."""
        self.total += tasks
        self._show()

    def from_store(self, tasks: int) -> None:
        self.reused += tasks
        self._show()

    def submit(self, tasks: int) -> None:
        self.submitted += tasks
        self._show()

    def finish(self, ok: bool, seconds: float) -> None:
        """A task ended (``ok`` False: it failed) after ``seconds``."""
        self.done += ok
        self.failed += not ok
        self._seconds.append(seconds)
        self._show()

    @property
    def running(self) -> int:
        return min(self.workers, self.submitted - self.done - self.failed)

    def line(self) -> str:
        finished = self.done + self.failed + self.reused
        text = (f"campaign: {finished}/{self.total} tasks done ({self.reused} from the store), "
                f"{self.failed} failed, {self.running} running")
        left = self.total - finished
        if self._seconds and left:
            eta = left * sum(self._seconds) / len(self._seconds) / self.workers
            text += f", about {_clock(eta)} left"
        return text

    def _show(self) -> None:
        if self.enabled:
            print(f"\r\033[K{self.line()}", end="", file=self.stream, flush=True)

    def close(self) -> None:
        if self.enabled:
            print(file=self.stream, flush=True)
