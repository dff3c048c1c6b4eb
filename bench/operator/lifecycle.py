"""How a run ends: signals, the supervising parent, disk space for the summary, exit codes.

A ``thruster-hil run`` is three processes: the command (this supervisor), the bench (a
forked child) and the flight software (the bench's child). Whatever ends the run, the run
folder is completed and ``summary.json`` says how (``ended``):

* ``completed``: the run reached its duration (exit 0 if it passed, 1 if not);
* ``error``: the run could not go on (a process died, the disk filled up...; exit 3);
* ``SIGINT``, ``SIGTERM``, ``SIGHUP``: stopped by that signal (exit 128 + its number:
  130, 143, 129, as shells report it), the folder completed from what ran.

Signals reach the whole process group (a terminal's Ctrl-C, a CI runner's or ``timeout``'s
SIGTERM) or just one process. The bench stops on the first one (:func:`stop_on_signals`:
it raises :class:`Stopped` once, then ignores further signals so its clean-up runs to the
end); the supervisor forwards what it receives to the bench and waits for it
(:func:`supervise`); the flight software gets SIGTERM from the bench and writes its
statistics. A little disk space is kept back while the run writes its files
(:class:`DiskReserve`) and given up before the summary is written, so a full disk still
leaves a valid summary.
"""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import FrameType
from typing import IO, Any, NoReturn

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
SIGNAL_EXIT_BASE = 128  # a process ended by signal N reports 128 + N in shells
RESERVE_BYTES = 1 << 20  # kept free for summary.json and the end of the files
RESERVE_NAME = ".space-for-summary"
RESERVE_CHUNK = 64 * 1024


class Stopped(BaseException):
    """A stop signal ended the run; ``signum`` says which."""

    def __init__(self, signum: int, summary: dict[str, Any] | None = None,
                 out: Path | None = None) -> None:
        self.signum = signum
        self.summary = summary  # the completed run's summary, when there is one
        self.out = out  # its run folder
        super().__init__(signal.Signals(signum).name)

    @property
    def name(self) -> str:
        """The signal's name (SIGTERM ...)."""
        return signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        """128 + the signal's number."""
        return SIGNAL_EXIT_BASE + self.signum


def exit_now(code: int, flush: Sequence[IO[str]] = ()) -> NoReturn:
    """End this forked process with ``code`` (``os._exit``: none of the parent's exit
    handlers run) once ``flush`` is flushed, whatever a stop signal does on the way.

    The stop signals are blocked first. A handler of :func:`stop_on_signals` that fires
    before that raises :class:`Stopped` here, where it is caught (and it ignores every later
    stop signal): without this, a signal landing as a child flushed its output carried the
    child, a copy of its parent, on into the parent's code (a forked bench went on running
    the rest of a test session). The handler can also fire on the way into this function,
    before its first line: a caller with such a handler calls it in a loop,
    ``while True: try: exit_now(...) except BaseException: pass``.
    """
    # bare try/except, not contextlib.suppress: its __exit__ is Python code, where a
    # handler could raise again before the mask is set
    try:  # noqa: SIM105
        signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    except BaseException:  # the handler fired first: it ignores every later stop signal
        pass
    for f in flush:
        try:  # noqa: SIM105
            f.flush()
        except BaseException:  # a closed or broken stream: nothing more to keep
            pass
    os._exit(code)


def stop_on_signals() -> None:
    """In the bench: the first stop signal raises :class:`Stopped`; later ones are ignored,
    so that the run folder is completed."""

    def handler(signum: int, frame: FrameType | None) -> None:
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_IGN)
        raise Stopped(signum)

    for s in STOP_SIGNALS:
        signal.signal(s, handler)


def supervise(pid: int, meanwhile: Callable[[], None] | None = None,
              pending: list[int] | None = None) -> tuple[int, int | None]:
    """In the supervisor: wait for child ``pid``, forwarding stop signals to it.

    ``pending``: stop signals held while the child was being started (forwarded first).
    ``meanwhile`` runs then, with the signals already forwarded (the supervisor's own
    work while the bench runs: loading the plotting library). Returns the child's wait
    status and the first stop signal received (None if none).
    """
    received: list[int] = []

    def forward(signum: int, frame: FrameType | None) -> None:
        if not received:
            received.append(signum)
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signum)

    previous = {s: signal.signal(s, forward) for s in STOP_SIGNALS}
    for s in pending or []:
        forward(s, None)
    try:
        if meanwhile is not None:
            meanwhile()
        _, status = os.waitpid(pid, 0)  # retried after each handled signal (PEP 475)
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
    return status, received[0] if received else None


@contextlib.contextmanager
def held_stop_signals() -> Iterator[list[int]]:
    """In the supervisor, after the bench: stop signals received inside the block are
    held, not acted on, so its work (the summary read, the plots) runs to the end; the
    list yielded holds them, in order, for the caller to act on after the block."""
    held: list[int] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        held.append(signum)

    previous = {s: signal.signal(s, hold) for s in STOP_SIGNALS}
    try:
        yield held
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


class DiskReserve:
    """A file of ``RESERVE_BYTES`` in the run folder, removed before the summary is written
    (a full disk then still has room for it)."""

    def __init__(self, folder: Path) -> None:
        self.path = folder / RESERVE_NAME
        try:
            with open(self.path, "wb") as f:
                for _ in range(RESERVE_BYTES // RESERVE_CHUNK):
                    f.write(bytes(RESERVE_CHUNK))
        except OSError:  # no room even for this: nothing reserved
            self.release()

    def release(self) -> None:
        """Give the space back (idempotent)."""
        with contextlib.suppress(OSError):
            self.path.unlink()
