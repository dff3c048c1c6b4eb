"""Helpers of the transport tests: frames of every kind, bounded receives, output lines.

Every wait here is bounded by a deadline on a real event (a frame, an output line), never
by sleeping.
"""

from __future__ import annotations

import os
import queue
import threading
import time
from pathlib import Path
from typing import IO

import can

DEADLINE_S = 30.0
QUEUE_OVERFILL_N = 200  # well past Linux's default of 10 queued datagrams per socket


def env_for(runtime: Path) -> dict[str, str]:
    """This process's environment with ``runtime`` as $XDG_RUNTIME_DIR, output unbuffered."""
    return {**os.environ, "XDG_RUNTIME_DIR": str(runtime), "PYTHONUNBUFFERED": "1"}


def frame_key(m: can.Message) -> tuple[object, ...]:
    """What a bus must carry unchanged: ID, flags, DLC and data (not the timestamps)."""
    return (
        m.arbitration_id,
        m.is_extended_id,
        m.is_remote_frame,
        m.is_error_frame,
        m.is_fd,
        m.bitrate_switch,
        m.error_state_indicator,
        m.dlc,
        bytes(m.data),
    )


def variety() -> list[can.Message]:
    """Every classic DLC with standard and extended IDs, remote, error and FD frames."""
    frames = []
    for dlc in range(9):
        data = bytes(range(0xA0, 0xA0 + dlc))
        frames.append(can.Message(arbitration_id=0x100 + dlc, is_extended_id=False, data=data))
        frames.append(can.Message(arbitration_id=0x1ABCDE00 + dlc, data=data))
        frames.append(
            can.Message(
                arbitration_id=0x200 + dlc, is_extended_id=False, is_remote_frame=True, dlc=dlc
            )
        )
    frames.append(can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"\xff" * 8))
    frames.append(can.Message(arbitration_id=0x1FFFFFFF, data=b""))
    frames.append(can.Message(arbitration_id=0x20000080, is_error_frame=True, data=bytes(8)))
    frames.append(can.Message(arbitration_id=0x300, is_fd=True, data=bytes(range(12))))
    frames.append(
        can.Message(
            arbitration_id=0x301,
            is_fd=True,
            bitrate_switch=True,
            error_state_indicator=True,
            data=bytes(range(64)),
        )
    )
    return frames


def recv_n(bus: can.BusABC, n: int, deadline_s: float = DEADLINE_S) -> list[can.Message]:
    """Receive n frames or fail at the deadline."""
    got: list[can.Message] = []
    deadline = time.monotonic() + deadline_s
    while len(got) < n:
        left = deadline - time.monotonic()
        assert left > 0, f"only {len(got)}/{n} frames within {deadline_s} s"
        m = bus.recv(timeout=left)
        if m is not None:
            got.append(m)
    return got


class Collector(threading.Thread):
    """Receives n frames on a bus in the background (senders block without a reader)."""

    def __init__(self, bus: can.BusABC, n: int) -> None:
        super().__init__(daemon=True)
        self.bus = bus
        self.n = n
        self.got: list[can.Message] = []
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.got = recv_n(self.bus, self.n)
        except BaseException as exc:  # reported by result()
            self.error = exc

    def result(self) -> list[can.Message]:
        """The frames, once all arrived; raises what the receiving thread raised."""
        self.join(DEADLINE_S)
        assert not self.is_alive(), "collector still running"
        if self.error is not None:
            raise self.error
        return self.got


class Lines:
    """Lines of a subprocess's pipe, read by a thread, awaited with a deadline."""

    def __init__(self, pipe: IO[str]) -> None:
        self._q: queue.Queue[str | None] = queue.Queue()
        self._t = threading.Thread(target=self._pump, args=(pipe,), daemon=True)
        self._t.start()

    def _pump(self, pipe: IO[str]) -> None:
        for line in pipe:
            self._q.put(line)
        self._q.put(None)

    def rest(self, deadline_s: float = DEADLINE_S) -> list[str]:
        """Every line until EOF (or the deadline)."""
        deadline = time.monotonic() + deadline_s
        out: list[str] = []
        while (left := deadline - time.monotonic()) > 0:
            try:
                line = self._q.get(timeout=left)
            except queue.Empty:
                break
            if line is None:
                break
            out.append(line)
        return out

    def wait_for(self, predicate_text: str, deadline_s: float = DEADLINE_S) -> str:
        """The first line containing predicate_text; fails at EOF or the deadline."""
        deadline = time.monotonic() + deadline_s
        seen: list[str] = []
        while True:
            left = deadline - time.monotonic()
            assert left > 0, f"no line with {predicate_text!r} within {deadline_s} s: {seen}"
            try:
                line = self._q.get(timeout=left)
            except queue.Empty:
                continue
            assert line is not None, f"EOF before a line with {predicate_text!r}: {seen}"
            seen.append(line)
            if predicate_text in line:
                return line
