"""hilbus: a portable, broker-less, cross-process CAN bus as a python-can interface plugin.

Why
---
The bench and flight software are separate OS processes that must share a CAN bus. Where
the kernel has SocketCAN, ``socketcan:vcan0`` is that bus. macOS, most containers and this
CI have no SocketCAN, and python-can's ``virtual`` bus only works inside one process. The
existing cross-process option, python-can-remote (a TCP/websocket server the members
connect to), was measured here at ~156 µs round trip and ~24k frames/s, and needs a server
process that must be started first and may die; a Unix-datagram relay process measured
~42 µs and 62k frames/s. hilbus has no server or relay at all: every member writes straight
into every other member's socket, one kernel hop. ``benchmarks/bus_roundtrip.py`` measured
(2 vCPUs, Python 3.11, echo in a second process): round trip p50 25-41 µs (~95 µs at
moments when even bare Python datagrams over a socketpair took 80 µs: the VM's wake-up
latency varies), the same as python-can's in-process ``virtual`` bus with an echo thread;
48k-165k frames/s one way, none lost.

It is registered as a python-can interface (entry point ``can.interface``:
``hilbus = "transport.hilbus:HilBus"``), so any python-can program or stock tool attaches::

    bus = can.Bus(interface="hilbus", channel="default")
    python -m can.logger -i hilbus -c default
    python -m can.viewer -i hilbus -c default

Design
------
* Each member (each :class:`HilBus` object) binds its own ``AF_UNIX``/``SOCK_DGRAM``
  socket file ``<pid>-<random hex>.sock`` in the channel directory
  ``<runtime>/thruster-hil-<uid>/<channel>/`` (:mod:`transport.channel`: layout,
  permissions, path limits). The directory lives as long as the channel has members: the
  last one to leave removes it, and a joining member sweeps away what processes that died
  without leaving left behind.
* Sending a frame writes one datagram to every *other* member's socket, through a socket
  connected to it (:mod:`transport.peers`: the cached member list, stale members).
* Reliable and ordered: datagrams on a Unix socket are never lost, and each receiver's
  queue is FIFO, so frames from one sender arrive in order. Sends *block* while a
  receiver's queue is full (Linux allows ``net.unix.max_dgram_qlen`` datagrams, often only
  10): a slow receiver slows its senders down instead of losing frames. While blocked, a
  sender keeps draining its *own* socket into a local backlog, so two single-threaded
  processes bursting at each other do not deadlock.
* Overrun: a member whose queue stays full for ``member_stall_s`` (default
  :data:`MEMBER_STALL_S`; a stopped ``can.logger``, a process that opened the bus only to
  send) is *overrun*, as a CAN controller whose receive buffer overflows: senders drop
  their frames to it, without waiting, until its queue has room again, and count them in
  :attr:`HilBus.overrun_drops`. Every other member still gets every frame, so a stuck
  monitor cannot stop a run. ``member_stall_s=None`` blocks without limit instead.
* ``receive_own_messages=True`` delivers each sent frame locally too (``is_rx=False``),
  after it went out to the other members.

Frames in and out
-----------------
Wire record (:mod:`transport.wire`): a header (transmission time, arbitration ID, flags,
DLC, data length) followed by 0..64 data bytes. A datagram carries one record
(:meth:`HilBus.send`) or, from :meth:`HilBus.send_burst`, up to
:data:`~transport.wire.BURST_MAX_RECORDS` records back to back: frames of one instant
that a sender hands over together (a lockstep bench's sensor samples and SYNC; a flight
software's command frames), one system call and one receiver wake-up instead of one per
frame. The receiver still returns them one ``recv()`` at a time, in order, with the same
arrival time.
Received frames are :class:`HilMessage` objects (a :class:`can.Message`):
``timestamp`` is the wall-clock time the frame arrived in the receiver's queue, stamped by
the kernel (``SO_TIMESTAMPNS``, as SocketCAN's receive timestamps are; elsewhere than Linux
the receiver's :func:`time.time` when it reads the frame), and ``tx_timestamp`` the
sender's time of transmission, so one-way latency is ``msg.timestamp - msg.tx_timestamp``
(same host, same clock) and does not include how long the receiver took to read.
:func:`tx_timestamp_of` reads it from any message (None when it is not a hilbus frame).
Filters are python-can's standard software filters. Malformed datagrams are dropped and
counted in :attr:`HilBus.malformed_records`; they never raise. ``state = BusState.PASSIVE``
makes a member listen-only (``send`` raises); ``fileno()`` is readable whenever a frame
waits, so :class:`can.Notifier` (threads or asyncio) works. ``send`` may be called from
several threads (periodic tasks); ``recv`` from one thread at a time, as with any
python-can bus.

Errors
------
python-can's, and the project's (:mod:`dbc.errors`): a bus that cannot be opened raises
:class:`~dbc.errors.BusInitError` (a :class:`can.CanInitializationError`; for an argument
out of range :class:`~dbc.errors.BusArgumentError`, also a ValueError), a failed or refused
send or receive :class:`~dbc.errors.BusOperationError` (a :class:`can.CanOperationError`;
a send that times out :class:`~dbc.errors.BusTimeoutError`, also a
:class:`can.CanTimeoutError`). All are :class:`~dbc.errors.BusError`.

Limits
------
* One host only, one user only (it is a Unix-socket bus); not on Windows.
* No physical layer: no bitrate, no arbitration, no bus-off (``bitrate`` etc. are
  accepted and ignored); the bench's bus timing model supplies those.
* A member that never reads (a process that opened the bus only to send, or is stopped)
  holds every sender up for ``member_stall_s`` once, then loses frames (see Overrun).
  ``send(msg, timeout=...)`` bounds a send in total; one that times out may have reached
  some members and not others.
* A member that joins while a frame is being sent may miss that frame.
* ``shutdown()`` wakes threads blocked in ``recv()`` or ``send()`` on the same object
  (they raise :class:`~dbc.errors.BusOperationError`).
* Path length: the socket path must fit ``sun_path`` (107 bytes on Linux, 103 elsewhere);
  a long ``$XDG_RUNTIME_DIR``/``$TMPDIR`` plus a long channel name is refused.
* macOS queues datagrams by bytes (``SO_RCVBUF``) and answers a full receiver with
  ``ENOBUFS`` instead of blocking; hilbus then retries every millisecond (untested here).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket
import threading
import time
from collections.abc import Sequence
from typing import Any

import can
from can import BusState, CanProtocol
from can.typechecking import AutoDetectedConfig, CanFilters

from dbc.errors import (
    BusArgumentError,
    BusInitError,
    BusOperationError,
    BusTimeoutError,
)
from transport.channel import (
    DEFAULT_CHANNEL,
    STALE_ERRNOS,
    bus_root,
    check_channel,
    join,
    leave,
    live_channels,
    member_pid,
    new_member_path,
    remove_if_empty,
    sweep,
)
from transport.inbox import MS_PER_S, Inbox, deadline_of, poll_ms
from transport.peers import MTIME_SETTLE_S, Peer, Peers, set_buffers
from transport.wire import BURST_MAX_RECORDS, HilMessage, encode, own_copy, tx_timestamp_of

# the plugin's public names (the frame type and its reader are defined in transport.wire)
__all__ = (
    "DEFAULT_CHANNEL",
    "INTERFACE_NAME",
    "MEMBER_STALL_S",
    "MTIME_SETTLE_S",
    "HilBus",
    "HilMessage",
    "tx_timestamp_of",
)

INTERFACE_NAME = "hilbus"
#: wait between retries where the OS cannot tell when a full receiver has room (macOS).
FULL_RETRY_S = 0.001
FULL_RETRY_MS = max(1, int(FULL_RETRY_S * MS_PER_S))
#: consecutive "peer writable, send still would block" before falling back to retries.
SPURIOUS_WRITABLE_LIMIT = 3
# a member whose queue stays full this long is overrun (its frames dropped until it reads):
# far beyond a busy process's scheduling delay, and below the bench's default lockstep
# stall timeout (2 s), so a paused monitor holds a run up once without costing it a stall
MEMBER_STALL_S = 1.0


class HilBus(can.BusABC):
    """A member of a hilbus channel; see the module docstring.

    :param channel: channel name (``[A-Za-z0-9_.-]+``), default ``"default"``.
    :param receive_own_messages: also deliver this member's own sent frames to itself.
    :param can_filters: python-can software filters.
    :param member_stall_s: how long a send waits for a member whose queue is full before
        that member is overrun (its frames dropped until it reads); None: no limit.
    Other keyword arguments (``bitrate``, ``fd``, ...) are accepted and ignored.
    """

    def __init__(
        self,
        channel: Any = DEFAULT_CHANNEL,
        can_filters: CanFilters | None = None,
        receive_own_messages: bool = False,
        member_stall_s: float | None = MEMBER_STALL_S,
        **kwargs: object,
    ) -> None:
        if member_stall_s is not None and not (
            isinstance(member_stall_s, (int, float)) and member_stall_s >= 0
        ):
            raise BusArgumentError(f"hilbus: member_stall_s = {member_stall_s!r}: expected "
                                   "seconds >= 0 or None")
        if not hasattr(socket, "AF_UNIX") or not hasattr(os, "getuid"):
            raise BusInitError("hilbus needs Unix domain sockets (not available on this OS)")
        name = check_channel(DEFAULT_CHANNEL if channel is None else channel)
        path = new_member_path(bus_root() / name)
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        try:
            set_buffers(sock)
            inbox = Inbox(sock, os.fsencode(path), name)
            join(sock, path)
        except BaseException:
            sock.close()
            raise
        try:
            peers = Peers(path.parent, path.name, sock.fileno())
        except BaseException:
            sock.close()
            leave(path)
            raise
        sweep(path.parent.parent)  # what dead processes left behind (see transport.channel)
        self.channel = name
        self.channel_info = f"hilbus channel {name!r} ({path})"
        self.directory = path.parent
        self.path = path
        self.receive_own_messages = bool(receive_own_messages)
        #: frames this member did not deliver to an overrun member (see the module docstring).
        self.overrun_drops = 0
        #: the same, per overrun member's socket name (``<pid>-<hex>.sock``)
        self.overrun_drops_to: dict[str, int] = {}
        self.member_stall_s = member_stall_s
        self._state = BusState.ACTIVE
        self._can_protocol = CanProtocol.CAN_FD
        self._closed = False
        self._inbox = inbox
        self._tx_lock = threading.Lock()  # guards the send side: _peers and the counters
        self._peers = peers
        super().__init__(channel=name, can_filters=can_filters)

    @property
    def malformed_records(self) -> int:
        """Datagrams received that were not valid records (dropped)."""
        return self._inbox.malformed_records

    # ---------------------------------------------------------------- sending

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Send ``msg`` to every other member; blocks while a receiver's queue is full.

        ``timeout``: None waits as long as it takes, 0 never waits, > 0 waits at most that
        long in total; on expiry raises :class:`~dbc.errors.BusTimeoutError` (the frame may
        have reached some members). Raises :class:`~dbc.errors.BusOperationError` for a
        frame that cannot exist (data > 64 bytes, or > 8 without ``is_fd``), on a bus shut
        down or listen-only, or if a member's socket fails. Both are
        :class:`can.CanOperationError`.
        """
        self._check_can_send()
        record = encode(msg, time.time())
        self._fan_out(record, deadline_of(timeout))
        if self.receive_own_messages:
            self._inbox.deliver_own(own_copy(record))

    def send_burst(self, msgs: Sequence[can.Message], timeout: float | None = None) -> None:
        """Send ``msgs``, in order, as one datagram per member (up to
        :data:`BURST_MAX_RECORDS` frames each): frames of one instant handed over together.

        Every member receives them one ``recv()`` at a time, in this order, as if sent one by
        one; a member's queue counts a burst as one entry. ``timeout`` as in :meth:`send`,
        for the whole burst. Every frame is checked before any is sent.
        """
        self._check_can_send()
        records = [encode(m, time.time()) for m in msgs]
        deadline = deadline_of(timeout)
        for i in range(0, len(records), BURST_MAX_RECORDS):
            self._fan_out(b"".join(records[i:i + BURST_MAX_RECORDS]), deadline)
        if self.receive_own_messages:
            for record in records:
                self._inbox.deliver_own(own_copy(record))

    def _check_can_send(self) -> None:
        if self._closed:
            raise BusOperationError("hilbus: send on a bus that was shut down")
        if self._state is BusState.PASSIVE:
            raise BusOperationError("hilbus: send on a listen-only (passive) bus")

    def _fan_out(self, datagram: bytes, deadline: float | None) -> None:
        """One datagram to every other member."""
        with self._tx_lock:
            for peer in self._peers.refresh(self._inbox.received):
                self._send_to(peer, datagram, deadline)

    @property
    def overrun_drops_by_pid(self) -> dict[int, int]:
        """:attr:`overrun_drops_to` by the overrun member's process id (from its socket name)."""
        out: dict[int, int] = {}
        for name, n in self.overrun_drops_to.items():
            pid = member_pid(name)
            if pid is not None:
                out[pid] = out.get(pid, 0) + n
        return out

    def _send_to(self, peer: Peer, record: bytes, deadline: float | None) -> None:
        """``record`` to one member: wait while its queue is full (draining our own), up to
        ``deadline``; overrun it after member_stall_s; forget it if it is gone."""
        spurious = 0
        stall = self.member_stall_s
        stall_deadline = None if stall is None else time.monotonic() + stall
        while True:
            try:
                peer.sock.send(record, socket.MSG_DONTWAIT)
                peer.overrun = False
                return
            except BlockingIOError:
                full_retry = spurious >= SPURIOUS_WRITABLE_LIMIT
            except OSError as exc:
                if exc.errno in STALE_ERRNOS:
                    self._peers.stale(peer.name)
                    return
                if exc.errno != errno.ENOBUFS:
                    raise BusOperationError(
                        f"hilbus: send to member {peer.name} failed: {exc}"
                    ) from exc
                full_retry = True  # macOS: receiver full, no way to wait for room
            if self._closed:  # set before shutdown() wakes us, so checked after any drain
                raise BusOperationError("hilbus: bus shut down during send")
            if peer.overrun or poll_ms(stall_deadline) == 0:
                peer.overrun = True  # it has not read for member_stall_s: drop, as a CAN
                self.overrun_drops += 1  # controller's full receive buffer does
                self.overrun_drops_to[peer.name] = self.overrun_drops_to.get(peer.name, 0) + 1
                return
            wait_ms = poll_ms(deadline)
            if wait_ms == 0:
                raise BusTimeoutError(
                    f"hilbus: send timed out: member {peer.name} on channel "
                    f"{self.channel!r} is not reading"
                )
            stall_ms = poll_ms(stall_deadline)
            if stall_ms is not None:
                wait_ms = stall_ms if wait_ms is None else min(wait_ms, stall_ms)
            if full_retry:  # only our own socket can wake us: cap the wait
                wait_ms = FULL_RETRY_MS if wait_ms is None else min(wait_ms, FULL_RETRY_MS)
                events = dict(self._peers.own_poller.poll(wait_ms))  # never the inbox's
            else:
                events = dict(peer.poller.poll(wait_ms))
            if events.get(self._inbox.fileno, 0) & select.POLLIN:
                self._inbox.drain()  # keep our own queue moving: no deadlock between bursters
            if events.get(peer.sock.fileno(), 0) & select.POLLOUT:
                spurious += 1

    # ---------------------------------------------------------------- receiving

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        return self._inbox.next_frame(deadline_of(timeout)), False

    # ---------------------------------------------------------------- python-can API

    def fileno(self) -> int:
        """The member socket: readable whenever a frame is waiting (for select/asyncio)."""
        self._inbox.watched()
        return self._inbox.fileno

    def flush_tx_buffer(self) -> None:
        """Nothing to flush: a send returns only once every member has the frame queued."""

    @property
    def state(self) -> BusState:
        """ACTIVE (sends allowed) or PASSIVE (listen-only: sends raise)."""
        return self._state

    @state.setter
    def state(self, new_state: BusState) -> None:
        if new_state not in (BusState.ACTIVE, BusState.PASSIVE):
            raise BusOperationError(f"hilbus: state {new_state} unsupported (ACTIVE or PASSIVE)")
        self._state = new_state

    def shutdown(self) -> None:
        """Leave the channel: unlink this member's socket file, close every socket, and
        remove the channel directory if no member is left in it.

        Threads blocked in ``recv()`` or in a ``send()`` waiting for a full member wake and
        raise :class:`~dbc.errors.BusOperationError` (releasing the send lock)."""
        if self._closed:
            return
        self._closed = True
        try:
            super().shutdown()
        finally:
            self._inbox.close()
            with contextlib.suppress(OSError):
                os.unlink(self.path)
            with self._tx_lock:
                self._peers.close()
            self._inbox.release()
            remove_if_empty(self.directory)  # the last member leaving removes the channel

    @staticmethod
    def _detect_available_configs() -> Sequence[AutoDetectedConfig]:
        """Channels of this user that have at least one member whose process is alive."""
        return [{"interface": INTERFACE_NAME, "channel": ch} for ch in live_channels()]
