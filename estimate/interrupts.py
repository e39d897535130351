"""Interrupts (SIGINT, SIGTERM) that abort the whole computation, also from native solvers.

CasADi runs IPOPT and its iteration callback in native code: the ``KeyboardInterrupt`` that
Python's SIGINT handler raises there is caught and turned into an IPOPT status
(``User_Requested_Stop`` or ``NonIpopt_Exception_Thrown``), so the solve returns as if it
had merely not converged. :func:`surfacing` notes every signal that arrives while such code
runs and raises :class:`Interrupted` when it returns.

The ``slosh`` command line runs each command inside :func:`handled`: SIGINT and SIGTERM
raise :class:`Interrupted`, every signal received is remembered (so that output files are
never committed after one, whoever swallowed the exception), and :func:`deferred` holds
signals back while outputs are being renamed into place. Python runs signal handlers only
between bytecodes, so native code that never returns to Python (an IPOPT iteration on a
huge problem) would delay them indefinitely: a watchdog thread woken by the signal itself
(:func:`signal.set_wakeup_fd`) ends the process after :data:`GRACE_SECONDS` when the
command has not stopped by then, removing the temporary files of its outputs.

Examples
--------
>>> from estimate.interrupts import surfacing
>>> with surfacing():        # a signal inside raises Interrupted here, once the block ends
...     pass
"""

from __future__ import annotations

import functools
import os
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

__all__ = ["GRACE_SECONDS", "Interrupted", "SIGNALS", "deferred", "handled", "received",
           "surfacing", "temporary"]

#: The signals that abort a computation.
SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)
#: Seconds a command has to stop by itself after a signal before the watchdog ends it.
GRACE_SECONDS = 5.0

_received: list[int] = []   # signals seen by the handler of `handled`
_deferring: list[bool] = []  # non-empty while `deferred` holds signals back
_temporary: set[Path] = set()  # temporary output files the watchdog removes


class Interrupted(KeyboardInterrupt):
    """The computation was interrupted by a signal (a ``KeyboardInterrupt``, so that code
    catching ``Exception`` lets it through).

    Attributes
    ----------
    signum : int
        The signal number (``signal.SIGINT``, ``signal.SIGTERM``).
    """

    def __init__(self, signum: int) -> None:
        self.signum = int(signum)
        super().__init__(f"interrupted by {self.signal_name}")

    @property
    def signal_name(self) -> str:
        """``"SIGINT"`` or ``"SIGTERM"``."""
        return signal.Signals(self.signum).name

    @property
    def exit_status(self) -> int:
        """The shell's status for death by this signal: 128 + its number (130, 143)."""
        return 128 + self.signum


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _raise(signum: int, frame: FrameType | None) -> None:
    _received.append(signum)
    if not _deferring:
        raise Interrupted(signum)


def received() -> int | None:
    """The first signal received inside the current :func:`handled` block, or None (also
    outside such a block)."""
    return _received[0] if _received else None


@contextmanager
def temporary(paths: Iterator[Path] | list[Path]) -> Iterator[None]:
    """Within the block, the watchdog of :func:`handled` removes ``paths`` (temporary
    output files or folders) when it ends the process."""
    paths = list(paths)
    _temporary.update(paths)
    try:
        yield
    finally:
        _temporary.difference_update(paths)


def _watchdog(wake: socket.socket, done: threading.Event, command: str) -> None:
    """Wait for a signal byte on ``wake``; end the process when the command has not
    stopped ``GRACE_SECONDS`` later (and is not committing its outputs)."""
    try:
        while data := wake.recv(64):
            signums = [b for b in data if b in SIGNALS]
            if not signums:
                continue
            while not done.wait(GRACE_SECONDS) and _deferring:
                pass
            if done.is_set():
                return
            for path in list(_temporary):
                _remove(path)
            name = signal.Signals(signums[0]).name
            sys.stderr.write(f"{command}: interrupted by {name}; it did not stop within "
                             f"{GRACE_SECONDS:g} s (native code), so it was ended: nothing was "
                             "written; existing output files are unchanged\n")
            sys.stderr.flush()
            os._exit(128 + signums[0])
    except OSError:  # the socket was closed: the command ended
        return


def _remove(path: Path) -> None:
    import shutil

    if path.is_dir():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


@contextmanager
def handled(command: str = "slosh") -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`Interrupted` and are remembered
    (:func:`received`); a watchdog ends the process when the block has not stopped
    :data:`GRACE_SECONDS` after a signal (``command`` names it in the message). The
    previous handlers come back afterwards. Main thread only (elsewhere the block runs
    unchanged)."""
    if not _main_thread():
        yield
        return
    _received.clear()
    wake, notify = socket.socketpair()
    notify.setblocking(False)
    done = threading.Event()
    previous = {s: signal.signal(s, _raise) for s in SIGNALS}
    old_fd = signal.set_wakeup_fd(notify.fileno(), warn_on_full_buffer=False)
    watchdog = threading.Thread(target=_watchdog, args=(wake, done, command), daemon=True,
                                name="interrupt-watchdog")
    watchdog.start()
    try:
        yield
    finally:
        done.set()
        signal.set_wakeup_fd(old_fd)
        for s, h in previous.items():
            signal.signal(s, h)
        notify.close()
        watchdog.join(timeout=1.0)
        wake.close()
        _received.clear()  # a signal of this command must not stop the commits of later ones


@contextmanager
def deferred() -> Iterator[None]:
    """Hold back :class:`Interrupted` within the block (a signal is still remembered); on
    entry, raise it for a signal already received. For the few renames that commit
    outputs: they either all happen or none does."""
    _deferring.append(True)
    try:
        if _received:
            raise Interrupted(_received[0])
        yield
    finally:
        _deferring.pop()


def _note(caught: list[int], previous: Callable, signum: int, frame: FrameType | None) -> None:
    caught.append(signum)
    previous(signum, frame)


@contextmanager
def surfacing() -> Iterator[None]:
    """Raise :class:`Interrupted` after the block when SIGINT or SIGTERM arrived within it,
    even when native code (IPOPT through CasADi) swallowed what the handler raised.

    Only signals with a Python handler are watched (SIGINT by default; both inside
    :func:`handled`); the previous handler still runs. Main thread only.
    """
    if not _main_thread():
        yield
        return
    caught: list[int] = []
    previous = {s: h for s in SIGNALS if callable(h := signal.getsignal(s))}
    for s, h in previous.items():
        signal.signal(s, functools.partial(_note, caught, h))
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
    if caught:
        raise Interrupted(caught[0])
