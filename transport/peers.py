"""The other members of a hilbus channel, as one member sees them (its send side).

:class:`Peers` keeps one connected socket per other member of the channel directory, so a
send needs no path lookup per frame. The member list is cached and rescanned only when the
directory's ``st_mtime_ns`` changes (and, because file systems stamp directories with a
coarse clock, on every send for :data:`MTIME_SETTLE_S` after a change: at most every
:data:`UNSETTLED_RESCAN_NS`, or after a frame arrived, whose sender may be a member not
seen yet). A member whose socket refuses (``ECONNREFUSED``/``ENOENT``: its process died
without shutting down) is stale: it is dropped, and its socket file unlinked if the pid in
its name is no longer alive.

Not thread-safe on its own: the owning bus calls it, and polls its pollers, under its send
lock only; none of them is the receive side's. Times: ``_s``
seconds, ``_ns`` nanoseconds.
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dbc.errors import BusInitError, BusOperationError
from transport import channel

#: size asked for SO_SNDBUF/SO_RCVBUF; the kernel clamps it to its maximum.
SOCKET_BUFFER_B = 4 * 1024 * 1024
#: a directory changed less than this long ago may change again with the same mtime
#: (coarse file-system clocks: a jiffy on Linux, 1 s on old file systems): rescan.
MTIME_SETTLE_S = 1.1
NS_PER_S = 1_000_000_000
# While unsettled, rescan on send at most this often, unless a frame arrived since the last
# scan (its sender may be a member not seen yet; it bound its socket before sending).
UNSETTLED_RESCAN_NS = 1_000_000


def set_buffers(sock: socket.socket) -> None:
    """Ask for :data:`SOCKET_BUFFER_B` send and receive buffers (the kernel may clamp)."""
    for opt in (socket.SO_SNDBUF, socket.SO_RCVBUF):
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, opt, SOCKET_BUFFER_B)


@dataclass
class Peer:
    """Another member: its socket file's name and a socket connected to it."""

    name: str
    sock: socket.socket
    #: waits for room in the peer's queue or for a datagram in our own (see HilBus._send_to)
    poller: Any
    #: its queue stayed full for member_stall_s: frames to it are dropped until it has room
    overrun: bool = False


class Peers:
    """The members of ``directory`` other than ``own_name``, connected and cached.

    ``own_fileno``: this member's socket, registered for POLLIN in every peer's poller (a
    sender waiting for room keeps its own queue moving). Raises BusInitError if the
    directory cannot be opened.
    """

    def __init__(self, directory: Path, own_name: str, own_fileno: int) -> None:
        self.directory = directory
        self._own_name = own_name
        self._own_fileno = own_fileno
        try:
            self._dir_fd = os.open(directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError as exc:
            raise BusInitError(f"hilbus: cannot open directory {directory}: {exc}") from exc
        self._by_name: dict[str, Peer] = {}
        #: waits for our own socket only: the send side's own poller (a receiving thread may
        #: be blocked on the inbox's at the same time, and one poll object must never be
        #: polled by two threads at once: CPython raises "concurrent poll() invocation")
        self.own_poller = select.poll()
        self.own_poller.register(own_fileno, select.POLLIN)
        #: the peers as a tuple, rebuilt when the set changes (iterated on every send)
        self.current: tuple[Peer, ...] = ()
        self._scan_mtime_ns: int | None = None
        self._scan_unsettled = True
        self._scan_mono_ns = 0
        self._scan_rx_count = 0

    def refresh(self, rx_count: int) -> tuple[Peer, ...]:
        """The peers now: rescans the directory if it changed (or may have) since the last
        scan. ``rx_count``: how many datagrams this member has received so far (one that
        arrived since the last scan may come from a member not seen yet). Raises
        BusOperationError if the directory cannot be listed."""
        mtime = os.fstat(self._dir_fd).st_mtime_ns  # the cheapest change check per send
        if mtime == self._scan_mtime_ns:
            if not self._scan_unsettled:
                return self.current
            mono_ns = time.monotonic_ns()
            if (rx_count == self._scan_rx_count
                    and mono_ns - self._scan_mono_ns < UNSETTLED_RESCAN_NS):
                return self.current
        self._scan_rx_count = rx_count
        self._scan_mono_ns = time.monotonic_ns()
        now_ns = time.time_ns()
        try:
            listing = os.listdir(self.directory)
        except OSError as exc:
            raise BusOperationError(
                f"hilbus: cannot list channel directory {self.directory}: {exc}"
            ) from exc
        names = {
            n for n in listing if n != self._own_name and channel.MEMBER_RE.fullmatch(n) is not None
        }
        for gone in set(self._by_name) - names:
            self._by_name.pop(gone).sock.close()
        for new in sorted(names - set(self._by_name)):
            self._connect(new)
        self._scan_mtime_ns = mtime
        self._scan_unsettled = now_ns - mtime < MTIME_SETTLE_S * NS_PER_S
        self.current = tuple(self._by_name.values())
        return self.current

    def _connect(self, name: str) -> None:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        try:
            set_buffers(s)
            s.connect(os.fspath(self.directory / name))
        except OSError as exc:
            s.close()
            if exc.errno in channel.STALE_ERRNOS:
                channel.remove_if_dead(self.directory, name)
                return
            raise BusOperationError(f"hilbus: cannot reach member {name}: {exc}") from exc
        poller = select.poll()
        poller.register(self._own_fileno, select.POLLIN)
        poller.register(s.fileno(), select.POLLOUT)
        self._by_name[name] = Peer(name, s, poller)

    def stale(self, name: str) -> None:
        """Forget a member whose socket refused; unlink its file if its process is dead."""
        peer = self._by_name.pop(name, None)
        if peer is not None:
            peer.sock.close()
            self.current = tuple(self._by_name.values())
        channel.remove_if_dead(self.directory, name)

    def close(self) -> None:
        """Close every peer socket and the directory handle."""
        for peer in self._by_name.values():
            peer.sock.close()
        self._by_name.clear()
        self.current = ()
        os.close(self._dir_fd)
