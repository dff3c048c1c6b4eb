"""The receive side of a hilbus member: its own socket, read into frames.

:class:`Inbox` owns the member's bound socket. It returns one frame per
:meth:`Inbox.next_frame`: from a local backlog first (datagrams a blocked sender moved out
of the socket so that its own queue keeps moving, own frames that found the socket full,
the rest of a burst), else from the socket. A burst datagram's records come out one at a
time, in order, with the datagram's arrival time. Malformed datagrams are counted
(:attr:`Inbox.malformed_records`) and skipped, never raised.

Arrival times [s, wall clock]: the kernel's stamp of when the datagram was queued to the
socket (``SO_TIMESTAMPNS`` on Linux, as SocketCAN's receive timestamps are), else
:func:`time.time` when it is read. Deadlines are :func:`time.monotonic` seconds; poll
timeouts whole milliseconds, rounded up.

Thread safety: the backlog and the socket's reads are guarded by one lock, so a sender
thread may drain while another thread receives; :meth:`next_frame` itself is for one
thread at a time, as ``recv`` is on any python-can bus.
"""

from __future__ import annotations

import contextlib
import math
import select
import socket
import struct
import sys
import threading
import time
from collections import deque

from dbc.errors import BusOperationError
from transport.wire import DATAGRAM_MAX_B, HilMessage, decode, is_burst, split_burst

MS_PER_S = 1000
NS_PER_S = 1_000_000_000
# Linux stamps a datagram as it is queued to a socket that asked for SO_TIMESTAMPNS
# (<asm-generic/socket.h>; Python's socket module does not name it); the stamp comes back
# as an SCM_TIMESTAMPNS control message carrying a struct timespec.
SO_TIMESTAMPNS = 35
TIMESPEC = struct.Struct("@qq")
TIMESTAMP_CMSG_B = socket.CMSG_SPACE(TIMESPEC.size)


def deadline_of(timeout_s: float | None) -> float | None:
    """The monotonic time ``timeout_s`` from now (None: no deadline; negative: now)."""
    return None if timeout_s is None else time.monotonic() + max(timeout_s, 0.0)


def poll_ms(deadline: float | None) -> int | None:
    """Milliseconds left until ``deadline`` rounded up (None: forever); 0 when past."""
    if deadline is None:
        return None
    left_s = deadline - time.monotonic()
    return math.ceil(left_s * MS_PER_S) if left_s > 0 else 0


def ask_for_timestamps(sock: socket.socket) -> bool:
    """Ask the kernel to stamp each datagram's arrival (Linux); True if it will."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    except OSError:
        return False
    return True


class Inbox:
    """The read side of member socket ``sock`` (bound at ``path_b``) on ``channel``."""

    def __init__(self, sock: socket.socket, path_b: bytes, channel: str) -> None:
        self.sock = sock
        self.fileno = sock.fileno()
        self.channel = channel
        self._path_b = path_b
        self._kernel_stamps = ask_for_timestamps(sock)
        #: datagrams received that were not valid records (dropped).
        self.malformed_records = 0
        #: datagrams with frames taken from the socket so far (their senders are members)
        self.received = 0
        #: set by :meth:`close`: reads raise, drains stop
        self.closed = False
        self.lock = threading.Lock()
        # guarded by lock: (arrival time, record) read ahead of next_frame, in order
        self._backlog: deque[tuple[float, bytes]] = deque()
        self._fileno_used = False  # someone waits on the socket: see _unpack_burst
        self.poller = select.poll()
        self.poller.register(self.fileno, select.POLLIN)

    def watched(self) -> None:
        """Someone waits for the socket to turn readable (``fileno()``): from now on the
        records of a burst left waiting keep it readable."""
        self._fileno_used = True

    def next_frame(self, deadline: float | None) -> HilMessage | None:
        """The next frame, waiting until ``deadline`` (monotonic s; None: for ever) for one;
        None at the deadline. Raises BusOperationError once closed or on a failed read."""
        record: bytes | None
        while True:
            if self.closed:
                raise BusOperationError("hilbus: receive on a bus that was shut down")
            with self.lock:
                if self._backlog:
                    rx_time, record = self._backlog.popleft()
                else:
                    try:
                        record, rx_time = self._recv_record()
                    except BlockingIOError:
                        record = None
                    except OSError as exc:
                        raise BusOperationError(f"hilbus: receive failed: {exc}") from exc
            if record is None:
                wait_ms = poll_ms(deadline)
                if wait_ms == 0 or not self.poller.poll(wait_ms):
                    return None
                continue
            if not record:
                continue  # a wake-up datagram
            self.received += 1
            if is_burst(record):
                record = self._unpack_burst(record, rx_time)
            msg = decode(record, rx_time, self.channel)
            if msg is None:
                self.malformed_records += 1
                continue
            return msg

    def _unpack_burst(self, datagram: bytes, rx_time: float) -> bytes:
        """The first record of a burst datagram; the others go to the front of the backlog
        (trailing bytes that do not make a whole record are counted as malformed)."""
        records, torn = split_burst(datagram)
        if torn:
            self.malformed_records += 1  # the trailing bytes; the records before are good
        with self.lock:
            self._backlog.extendleft((rx_time, r) for r in reversed(records[1:]))
        if self._fileno_used and len(records) > 1:
            self.wake()  # the socket must read as readable while these wait
        return records[0]

    def _recv_record(self) -> tuple[bytes, float]:
        """One datagram of the socket (non-blocking) and its time of arrival; raises
        BlockingIOError when nothing is queued."""
        if not self._kernel_stamps:
            return self.sock.recv(DATAGRAM_MAX_B, socket.MSG_DONTWAIT), time.time()
        record, ancillary, _flags, _addr = self.sock.recvmsg(
            DATAGRAM_MAX_B, TIMESTAMP_CMSG_B, socket.MSG_DONTWAIT
        )
        for level, kind, data in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and len(data) >= TIMESPEC.size:
                sec, nsec = TIMESPEC.unpack_from(data)
                return record, sec + nsec / NS_PER_S
        return record, time.time()

    def drain(self) -> None:
        """Move every queued datagram of the socket to the backlog (keeping order)."""
        with self.lock:
            self._drain_locked()
            if self._backlog:
                self.wake()

    def _drain_locked(self) -> None:
        # after close() the socket reads as end-of-file (empty records) for ever: stop
        while not self.closed:
            try:
                record, rx_time = self._recv_record()
            except BlockingIOError:
                break
            if record:
                self._backlog.append((rx_time, record))

    def wake(self) -> None:
        """Queue an empty datagram so the socket reads as readable while a backlog waits."""
        with contextlib.suppress(OSError):  # full: readable anyway
            self.sock.sendto(b"", socket.MSG_DONTWAIT, self._path_b)

    def deliver_own(self, record: bytes) -> None:
        """Queue ``record`` (marked as our own) behind everything received so far."""
        with self.lock:
            try:
                self.sock.sendto(record, socket.MSG_DONTWAIT, self._path_b)
                return
            except OSError:
                pass  # our queue is full: move it to the backlog, then append behind it
            self._drain_locked()
            self._backlog.append((time.time(), record))
            self.wake()

    def close(self) -> None:
        """Stop reading and wake every thread waiting on the socket (they raise).

        SHUT_RD leaves the socket readable for every waiter (a wake-up datagram could be
        consumed by one before another saw it); members sending to us get EPIPE.
        """
        self.closed = True
        try:
            self.sock.shutdown(socket.SHUT_RD)
        except OSError:
            self.wake()

    def release(self) -> None:
        """Close the socket (after :meth:`close` and after senders have let go of it)."""
        with contextlib.suppress(KeyError, ValueError):
            self.poller.unregister(self.fileno)
        self.sock.close()
