"""A bus read by a process of its own: frames relayed through a pipe, for slow readers.

Why: a receiver on a bus must keep up with it. On the portable bus a member whose queue
stays full is overrun after ``member_stall_s`` (10 ms in realtime runs, transport.spec),
and a SocketCAN socket drops what overflows its buffer. A Python thread that reads beside
a busy thread (a terminal UI redrawing) gets the interpreter only every switch interval
(5 ms), per frame, so at a few hundred frames per second it falls behind. The relay
process does nothing but read the bus and write each frame into a pipe (64 kB, about a
thousand frames: seconds of slack for the reader), so the reader's own pauses cost no
frames.

:class:`RelayBus` is a read-only python-can bus: it starts ``python -m transport.relay
SPEC`` (:func:`main`), waits until that process is on the bus, and its ``recv`` returns
the frames in order, each stamped by the relay when it read it
(:attr:`RelayBus.last_rx_monotonic_ns`, CLOCK_MONOTONIC: the same clock in every process).
``shutdown`` ends the relay; the relay also ends when the pipe's reader has gone.

Record (little-endian): receive time [ns, monotonic] u64, bus timestamp [s] f64,
arbitration ID u32, flags u8 (:data:`FLAG_BITS`), DLC u8, data length u8, then the data.
The relay's first write is :data:`READY` once the bus is open; a bus that cannot be opened
makes it exit with the error on stderr, which :class:`RelayBus` raises as
:class:`~dbc.errors.BusInitError` naming the spec.
"""

from __future__ import annotations

import os
import select
import signal
import struct
import subprocess
import sys
import time
from typing import Any

import can

from dbc.errors import BusInitError

HEADER = struct.Struct("<QdIBBB")
READY = b"RLY1"
READY_TIMEOUT_S = 20.0  # a cold interpreter on a loaded machine imports python-can slowly
RECV_POLL_S = 0.5  # the relay's longest wait, so that it sees its reader gone
BATCH_FRAMES = 64  # frames read without waiting before they are written together
READ_BYTES = 65536
#: message attributes in the flags byte, bit by bit
FLAG_BITS = ("is_extended_id", "is_remote_frame", "is_error_frame", "is_fd", "is_rx",
             "bitrate_switch", "error_state_indicator")


def pack(msg: can.Message, rx_ns: int) -> bytes:
    """One record (module docstring)."""
    flags = sum(1 << i for i, name in enumerate(FLAG_BITS) if getattr(msg, name))
    data = bytes(msg.data)
    return HEADER.pack(rx_ns, msg.timestamp, msg.arbitration_id, flags, msg.dlc,
                       len(data)) + data


def unpack(buf: bytes | bytearray | memoryview, at: int) -> tuple[can.Message, int, int] | None:
    """The record at ``at`` in ``buf``: (message, receive time [ns], next offset), or None
    if ``buf`` does not hold all of it yet."""
    if len(buf) - at < HEADER.size:
        return None
    rx_ns, stamp, can_id, flags, dlc, n = HEADER.unpack_from(buf, at)
    end = at + HEADER.size + n
    if len(buf) < end:
        return None
    kw = {name: bool(flags >> i & 1) for i, name in enumerate(FLAG_BITS)}
    msg = can.Message(timestamp=stamp, arbitration_id=can_id, dlc=dlc,
                      data=bytes(buf[at + HEADER.size:end]), check=False, **kw)
    return msg, rx_ns, end


class RelayBus(can.BusABC):
    """Read-only bus whose frames a relay process reads (module docstring)."""

    def __init__(self, channel: Any = None, spec: str = "", **kwargs: Any) -> None:
        self.spec = spec
        self.channel_info = f"relay of {spec}"
        # our interpreter and module; the spec is the reader's, checked by open_bus there
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "transport.relay", spec], stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        assert self._proc.stdout is not None
        self._fd = self._proc.stdout.fileno()
        self._buf = bytearray()
        self._at = 0
        #: when the relay read the frame the last ``recv`` returned [ns, CLOCK_MONOTONIC]
        self.last_rx_monotonic_ns = 0
        self._wait_ready()
        super().__init__(channel=channel, **kwargs)

    def _wait_ready(self) -> None:
        deadline = time.monotonic() + READY_TIMEOUT_S
        while len(self._buf) < len(READY):
            left = deadline - time.monotonic()
            if left <= 0 or not self._fill(left):
                self._proc.kill()
                _, err = self._proc.communicate()
                why = err.decode(errors="replace").strip().splitlines()
                raise BusInitError(f"{self.spec}: the relay process could not read it"
                                   + (f": {why[-1]}" if why else " (no answer)"))
        if bytes(self._buf[:len(READY)]) != READY:
            self._proc.kill()
            raise BusInitError(f"{self.spec}: the relay process answered {self._buf[:8]!r}")
        self._at = len(READY)

    def _fill(self, timeout_s: float) -> bool:
        """Read what the pipe holds, waiting at most ``timeout_s``; False at its end."""
        if not select.select([self._fd], [], [], max(0.0, timeout_s))[0]:
            return True
        chunk = os.read(self._fd, READ_BYTES)
        if not chunk:
            return False
        if self._at > READ_BYTES:  # drop what was consumed
            del self._buf[:self._at]
            self._at = 0
        self._buf += chunk
        return True

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            got = unpack(self._buf, self._at)
            if got is not None:
                msg, self.last_rx_monotonic_ns, self._at = got
                return msg, False
            left = RECV_POLL_S if deadline is None else deadline - time.monotonic()
            if left <= 0:
                return None, False
            if not self._fill(left):
                raise can.CanOperationError(f"{self.spec}: the relay process ended "
                                            f"(exit {self._proc.poll()})")

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Refused: a relay only reads."""
        raise can.CanOperationError(f"{self.channel_info}: read-only")

    def shutdown(self) -> None:
        """End the relay process."""
        if self._proc.poll() is None:
            self._proc.terminate()
        try:
            self._proc.wait(timeout=READY_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        for f in (self._proc.stdout, self._proc.stderr):
            if f is not None:
                f.close()
        super().shutdown()


def write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to ``fd`` (a pipe write may be cut short by a signal)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def main(argv: list[str] | None = None) -> int:
    """``python -m transport.relay SPEC``: read bus SPEC, write its frames to stdout."""
    from transport.spec import open_bus

    args = sys.argv[1:] if argv is None else argv
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the reader decides when this ends
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    out = sys.stdout.fileno()
    reader_pid = os.getppid()
    try:
        bus = open_bus(args[0])
    except Exception as exc:  # any failure is reported to the reader, which raises it
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        return 1
    try:
        write_all(out, READY)
        while True:
            msg = bus.recv(RECV_POLL_S)
            if msg is None:
                if os.getppid() != reader_pid:  # the reader's process has gone (reparented)
                    return 0
                continue
            batch = [pack(msg, time.monotonic_ns())]
            while len(batch) < BATCH_FRAMES:
                msg = bus.recv(0.0)
                if msg is None:
                    break
                batch.append(pack(msg, time.monotonic_ns()))
            write_all(out, b"".join(batch))
    except BrokenPipeError:
        return 0
    finally:
        bus.shutdown()


if __name__ == "__main__":
    sys.exit(main())
