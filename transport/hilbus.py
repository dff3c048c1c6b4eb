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
  ``<runtime>/thruster-hil-<uid>/<channel>/``, where ``<runtime>`` is ``$XDG_RUNTIME_DIR``
  if set and writable, else the system temporary directory.
* Sending a frame writes one datagram to every *other* member's socket (through a socket
  connected to it, so no path lookup per frame). The member list is cached and rescanned
  only when the directory's ``st_mtime_ns`` changes (and, because file systems stamp
  directories with a coarse clock, on every send for :data:`MTIME_SETTLE_S` after a change).
* A member whose socket refuses (``ECONNREFUSED``/``ENOENT``; its process died without
  shutting down) is stale: it is dropped, and its socket file unlinked if the pid in its
  name is no longer alive.
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

Permissions
-----------
Only the owning user can see or join a bus: both directories are created with mode 0o700
and, when they already exist, must be real directories (not symlinks) owned by the current
uid with no group/other permission bits, else :class:`~dbc.errors.BusError` names the path
(someone else pre-creating ``/tmp/thruster-hil-<uid>`` cannot hijack it, only block it).
Socket files are mode 0o600. Channel names are restricted to ``[A-Za-z0-9_.-]+`` (and not
``.``/``..``) so they cannot escape the directory.

Frames in and out
-----------------
Wire record: a little-endian header :data:`HEADER` (``<dIBBB``: transmission time from the
sender's :func:`time.time`, arbitration ID, flags, DLC, data length) followed by 0..64 data
bytes. Flags: extended ID, remote, error, FD, bit-rate switch, error-state indicator.
A datagram carries one record (:meth:`HilBus.send`) or, from :meth:`HilBus.send_burst`,
up to :data:`BURST_MAX_RECORDS` records back to back: frames of one instant that a sender
hands over together (a lockstep bench's sensor samples and SYNC; a flight software's
command frames), one system call and one receiver wake-up instead of one per frame. The
receiver still returns them one ``recv()`` at a time, in order, with the same arrival time.
Received frames are :class:`HilMessage` objects (a :class:`can.Message`):
``timestamp`` is the wall-clock time the frame arrived in the receiver's queue, stamped by
the kernel (``SO_TIMESTAMPNS``, as SocketCAN's receive timestamps are; elsewhere than Linux
the receiver's :func:`time.time` when it reads the frame), and ``tx_timestamp`` the
sender's time of transmission, so one-way latency is ``msg.timestamp - msg.tx_timestamp``
(same host, same clock) and does not include how long the receiver took to read.
:func:`tx_timestamp_of` reads it from any message (None when it is not a hilbus frame).
Filters are python-can's standard software filters. Malformed datagrams are dropped and counted in
:attr:`HilBus.malformed_records`; they never raise. ``state = BusState.PASSIVE`` makes a
member listen-only (``send`` raises); ``fileno()`` is readable whenever a frame waits, so
:class:`can.Notifier` (threads or asyncio) works. ``send`` may be called from several
threads (periodic tasks); ``recv`` from one thread at a time, as with any python-can bus.

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
  (they raise :class:`can.CanOperationError`).
* Path length: the socket path must fit ``sun_path`` (107 bytes on Linux, 103 elsewhere);
  a long ``$XDG_RUNTIME_DIR``/``$TMPDIR`` plus a long channel name is refused.
* macOS queues datagrams by bytes (``SO_RCVBUF``) and answers a full receiver with
  ``ENOBUFS`` instead of blocking; hilbus then retries every millisecond (untested here).
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import re
import select
import socket
import struct
import sys
import tempfile
import threading
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import can
from can import BusState, CanProtocol
from can.typechecking import AutoDetectedConfig, CanFilters

from dbc.errors import BusError

INTERFACE_NAME = "hilbus"
DEFAULT_CHANNEL = "default"
CHANNEL_RE = re.compile(r"[A-Za-z0-9_.-]+")
DIR_PREFIX = "thruster-hil-"
SOCKET_SUFFIX = ".sock"
MEMBER_RE = re.compile(r"([0-9]+)-[0-9a-f]+\.sock")
MEMBER_TOKEN_BYTES = 4

DIR_MODE = 0o700
SOCKET_MODE = 0o600
#: size asked for SO_SNDBUF/SO_RCVBUF; the kernel clamps it to its maximum.
SOCKET_BUFFER_B = 4 * 1024 * 1024
#: a directory changed less than this long ago may change again with the same mtime
#: (coarse file-system clocks: a jiffy on Linux, 1 s on old file systems): rescan.
MTIME_SETTLE_S = 1.1
# While unsettled, rescan on send at most this often, unless a frame arrived since the last
# scan (its sender may be a member not seen yet; it bound its socket before sending).
UNSETTLED_RESCAN_NS = 1_000_000
#: wait between retries where the OS cannot tell when a full receiver has room (macOS).
FULL_RETRY_S = 0.001
#: consecutive "peer writable, send still would block" before falling back to retries.
SPURIOUS_WRITABLE_LIMIT = 3
# a member whose queue stays full this long is overrun (its frames dropped until it reads):
# far beyond a busy process's scheduling delay, and below the bench's default lockstep
# stall timeout (2 s), so a paused monitor holds a run up once without costing it a stall
MEMBER_STALL_S = 1.0

#: wire header: tx time (s), arbitration ID, flags, DLC, data length.
# Linux stamps a datagram as it is queued to a socket that asked for SO_TIMESTAMPNS
# (<asm-generic/socket.h>; Python's socket module does not name it); the stamp comes back
# as an SCM_TIMESTAMPNS control message carrying a struct timespec.
SO_TIMESTAMPNS = 35
TIMESPEC = struct.Struct("@qq")
TIMESTAMP_CMSG_B = socket.CMSG_SPACE(TIMESPEC.size)
NS_PER_S = 1_000_000_000
HEADER = struct.Struct("<dIBBB")
DATA_MAX_B = 64
CLASSIC_DATA_MAX_B = 8
RECORD_MAX_B = HEADER.size + DATA_MAX_B
#: records per datagram of a burst (a longer burst goes out as several datagrams)
BURST_MAX_RECORDS = 32
DATAGRAM_MAX_B = BURST_MAX_RECORDS * RECORD_MAX_B

FLAG_EXTENDED = 0x01
FLAG_REMOTE = 0x02
FLAG_ERROR = 0x04
FLAG_FD = 0x08
FLAG_BRS = 0x10
FLAG_ESI = 0x20
#: set only in records a member sends to itself (receive_own_messages).
FLAG_OWN = 0x80

_STALE_ERRNOS = frozenset(
    {
        errno.ECONNREFUSED,
        errno.ECONNRESET,
        errno.ENOENT,
        errno.ENOTCONN,
        errno.ENOTSOCK,
        errno.EPIPE,
    }
)


class HilMessage(can.Message):
    """A received hilbus frame: a :class:`can.Message` plus the sender's ``tx_timestamp``.

    ``timestamp`` is the receiver's :func:`time.time` at receipt; ``tx_timestamp`` is the
    sender's :func:`time.time` at transmission (None for messages not from a hilbus).
    """

    __slots__ = ("tx_timestamp",)

    def __init__(self, *args: Any, tx_timestamp: float | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.tx_timestamp = tx_timestamp

    def __copy__(self) -> HilMessage:
        return _with_tx(super().__copy__(), self.tx_timestamp)

    def __deepcopy__(self, memo: dict[int, Any] | None) -> HilMessage:
        return _with_tx(super().__deepcopy__(memo), self.tx_timestamp)


def _with_tx(m: can.Message, tx_timestamp: float | None) -> HilMessage:
    return HilMessage(
        timestamp=m.timestamp,
        arbitration_id=m.arbitration_id,
        is_extended_id=m.is_extended_id,
        is_remote_frame=m.is_remote_frame,
        is_error_frame=m.is_error_frame,
        channel=m.channel,
        dlc=m.dlc,
        data=m.data,
        is_fd=m.is_fd,
        is_rx=m.is_rx,
        bitrate_switch=m.bitrate_switch,
        error_state_indicator=m.error_state_indicator,
        tx_timestamp=tx_timestamp,
    )


def tx_timestamp_of(msg: can.Message) -> float | None:
    """The sender's transmission time of a frame received from a hilbus, else None."""
    return getattr(msg, "tx_timestamp", None)


def runtime_dir() -> Path:
    """``$XDG_RUNTIME_DIR`` if set and writable, else the system temporary directory."""
    xdg = os.environ.get("XDG_RUNTIME_DIR")
    if xdg and os.path.isdir(xdg) and os.access(xdg, os.W_OK | os.X_OK):
        return Path(xdg)
    return Path(tempfile.gettempdir())


def bus_root() -> Path:
    """The per-user directory holding one directory per channel."""
    return runtime_dir() / f"{DIR_PREFIX}{os.getuid()}"


def check_channel(channel: object) -> str:
    """Return ``channel`` as a valid channel name; raises BusError naming a bad value."""
    name = str(channel) if isinstance(channel, int) and not isinstance(channel, bool) else channel
    if not isinstance(name, str) or not CHANNEL_RE.fullmatch(name) or name in (".", ".."):
        raise BusError(
            f"hilbus channel {channel!r}: expected a name of letters, digits, '_', '.', '-' "
            "(not '.' or '..')"
        )
    return name


def channel_dir(channel: str) -> Path:
    """The directory of ``channel``'s member sockets (not created)."""
    return bus_root() / check_channel(channel)


def _secure_dir(path: Path) -> None:
    """Create ``path`` with mode 0o700, or check an existing one is ours and private."""
    try:
        os.mkdir(path, DIR_MODE)
    except FileExistsError:
        pass
    except OSError as exc:
        raise BusError(f"hilbus: cannot create directory {path}: {exc.strerror}") from exc
    else:
        os.chmod(path, DIR_MODE)  # the umask may have taken bits away
    try:
        st = os.lstat(path)
    except OSError as exc:
        raise BusError(f"hilbus: cannot inspect directory {path}: {exc.strerror}") from exc
    if not _is_private_dir(st):
        raise BusError(
            f"hilbus: refusing directory {path}: it must be a directory (not a symlink) "
            f"owned by uid {os.getuid()} with mode 0700 (found uid {st.st_uid}, "
            f"mode {st.st_mode & 0o7777:o}, type {'dir' if _isdir(st) else 'other'})"
        )


def _isdir(st: os.stat_result) -> bool:
    return (st.st_mode & 0o170000) == 0o040000


def _is_private_dir(st: os.stat_result) -> bool:
    return _isdir(st) and st.st_uid == os.getuid() and (st.st_mode & 0o077) == 0


def _sun_path_max_b() -> int:
    return 107 if sys.platform.startswith("linux") else 103


def _member_pid(name: str) -> int | None:
    m = MEMBER_RE.fullmatch(name)
    return int(m.group(1)) if m else None


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _ask_for_timestamps(sock: socket.socket) -> bool:
    """Ask the kernel to stamp each datagram's arrival (Linux); True if it will."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    except OSError:
        return False
    return True


def _set_buffers(sock: socket.socket) -> None:
    for opt in (socket.SO_SNDBUF, socket.SO_RCVBUF):
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, opt, SOCKET_BUFFER_B)


def _deadline(timeout: float | None) -> float | None:
    return None if timeout is None else time.monotonic() + max(timeout, 0.0)


def _poll_ms(deadline: float | None) -> int | None:
    """Milliseconds left until ``deadline`` rounded up (None: forever); 0 when past."""
    if deadline is None:
        return None
    left_s = deadline - time.monotonic()
    return math.ceil(left_s * 1000) if left_s > 0 else 0


@dataclass
class _Peer:
    name: str
    sock: socket.socket
    #: waits for room in the peer's queue or for a datagram in our own (see _send_to)
    poller: Any
    #: its queue stayed full for member_stall_s: frames to it are dropped until it has room
    overrun: bool = False


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
            raise BusError(f"hilbus: member_stall_s = {member_stall_s!r}: expected seconds >= 0 "
                           "or None")
        if not hasattr(socket, "AF_UNIX") or not hasattr(os, "getuid"):
            raise BusError("hilbus needs Unix domain sockets (not available on this OS)")
        name = check_channel(DEFAULT_CHANNEL if channel is None else channel)
        root = bus_root()
        directory = root / name
        token = os.urandom(MEMBER_TOKEN_BYTES).hex()
        path = directory / f"{os.getpid()}-{token}{SOCKET_SUFFIX}"
        if len(os.fsencode(path)) > _sun_path_max_b():
            raise BusError(
                f"hilbus channel {name!r}: socket path {path} is longer than the OS allows "
                f"({_sun_path_max_b()} bytes); use a shorter channel name or "
                "a shorter $XDG_RUNTIME_DIR"
            )
        _secure_dir(root)
        _secure_dir(directory)

        try:
            dir_fd = os.open(directory, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError as exc:
            raise BusError(f"hilbus: cannot open directory {directory}: {exc}") from exc
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        try:
            _set_buffers(sock)
            self._kernel_stamps = _ask_for_timestamps(sock)
            sock.bind(os.fspath(path))
            os.chmod(path, SOCKET_MODE)
        except OSError as exc:
            sock.close()
            os.close(dir_fd)
            with contextlib.suppress(OSError):
                os.unlink(path)
            raise BusError(f"hilbus: cannot bind {path}: {exc}") from exc

        self.channel = name
        self.channel_info = f"hilbus channel {name!r} ({path})"
        self.directory = directory
        self.path = path
        self.receive_own_messages = bool(receive_own_messages)
        #: datagrams received that were not valid records (dropped).
        self.malformed_records = 0
        #: frames this member did not deliver to an overrun member (see the module docstring).
        self.overrun_drops = 0
        #: the same, per overrun member's socket name (``<pid>-<hex>.sock``)
        self.overrun_drops_to: dict[str, int] = {}
        self.member_stall_s = member_stall_s
        self._name = path.name
        self._path_b = os.fsencode(path)
        self._sock = sock
        self._dir_fd = dir_fd  # fstat() of it is the cheapest change check per send
        self._state = BusState.ACTIVE
        self._can_protocol = CanProtocol.CAN_FD
        self._closed = False
        # tx side (guarded by _tx_lock): connected peers and the directory scan cache
        self._tx_lock = threading.Lock()
        self._peers: dict[str, _Peer] = {}
        self._scan_mtime_ns: int | None = None
        self._scan_unsettled = True
        self._scan_mono_ns = 0
        self._rx_since_scan = False
        # rx side (guarded by _rx_lock): records drained from the socket while a send was
        # blocked, or own frames that found the socket full, as (rx time, record)
        self._rx_lock = threading.Lock()
        self._backlog: deque[tuple[float, bytes]] = deque()
        self._fileno_used = False  # someone waits on fileno(): see _split
        self._poller = select.poll()
        self._poller.register(sock.fileno(), select.POLLIN)
        super().__init__(channel=name, can_filters=can_filters)

    # ---------------------------------------------------------------- membership

    def _refresh_peers(self) -> None:
        """Rescan the channel directory if it changed (or may have) since the last scan."""
        mtime = os.fstat(self._dir_fd).st_mtime_ns
        if mtime == self._scan_mtime_ns:
            if not self._scan_unsettled:
                return
            # unsettled: rescan after a receive (its sender may be new) or every 1 ms
            mono_ns = time.monotonic_ns()
            if not self._rx_since_scan and mono_ns - self._scan_mono_ns < UNSETTLED_RESCAN_NS:
                return
        self._rx_since_scan = False
        self._scan_mono_ns = time.monotonic_ns()
        now_ns = time.time_ns()
        try:
            listing = os.listdir(self.directory)
        except OSError as exc:
            raise can.CanOperationError(
                f"hilbus: cannot list channel directory {self.directory}: {exc}"
            ) from exc
        names = {n for n in listing if n != self._name and MEMBER_RE.fullmatch(n) is not None}
        for gone in set(self._peers) - names:
            self._peers.pop(gone).sock.close()
        for new in sorted(names - set(self._peers)):
            self._connect(new)
        self._scan_mtime_ns = mtime
        self._scan_unsettled = now_ns - mtime < MTIME_SETTLE_S * 1e9

    def _connect(self, name: str) -> None:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        try:
            _set_buffers(s)
            s.connect(os.fspath(self.directory / name))
        except OSError as exc:
            s.close()
            if exc.errno in _STALE_ERRNOS:
                self._stale(name)
                return
            raise can.CanOperationError(f"hilbus: cannot reach member {name}: {exc}") from exc
        poller = select.poll()
        poller.register(self._sock.fileno(), select.POLLIN)
        poller.register(s.fileno(), select.POLLOUT)
        self._peers[name] = _Peer(name, s, poller)

    def _stale(self, name: str) -> None:
        """Forget a member whose socket refused; unlink its file if its process is dead."""
        peer = self._peers.pop(name, None)
        if peer is not None:
            peer.sock.close()
        pid = _member_pid(name)
        if pid is not None and not _pid_alive(pid):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.directory / name)

    # ---------------------------------------------------------------- sending

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Send ``msg`` to every other member; blocks while a receiver's queue is full.

        ``timeout``: None waits as long as it takes, 0 never waits, > 0 waits at most that
        long in total; on expiry raises :class:`can.CanOperationError` (the frame may have
        reached some members). Raises BusError for a frame that cannot exist
        (data > 64 bytes, or > 8 without ``is_fd``).
        """
        self._check_can_send()
        record = self._encode(msg)
        self._fan_out(record, _deadline(timeout))
        if self.receive_own_messages:
            self._deliver_own(record)

    def send_burst(self, msgs: Sequence[can.Message], timeout: float | None = None) -> None:
        """Send ``msgs``, in order, as one datagram per member (up to
        :data:`BURST_MAX_RECORDS` frames each): frames of one instant handed over together.

        Every member receives them one ``recv()`` at a time, in this order, as if sent one by
        one; a member's queue counts a burst as one entry. ``timeout`` as in :meth:`send`,
        for the whole burst. Every frame is checked before any is sent.
        """
        self._check_can_send()
        records = [self._encode(m) for m in msgs]
        deadline = _deadline(timeout)
        for i in range(0, len(records), BURST_MAX_RECORDS):
            self._fan_out(b"".join(records[i:i + BURST_MAX_RECORDS]), deadline)
        if self.receive_own_messages:
            for record in records:
                self._deliver_own(record)

    def _check_can_send(self) -> None:
        if self._closed:
            raise can.CanOperationError("hilbus: send on a bus that was shut down")
        if self._state is BusState.PASSIVE:
            raise can.CanOperationError("hilbus: send on a listen-only (passive) bus")

    def _fan_out(self, datagram: bytes, deadline: float | None) -> None:
        """One datagram to every other member."""
        with self._tx_lock:
            self._refresh_peers()
            for peer in list(self._peers.values()):
                self._send_to(peer, datagram, deadline)

    @staticmethod
    def _encode(msg: can.Message) -> bytes:
        data = b"" if msg.is_remote_frame or msg.data is None else bytes(msg.data)
        limit = DATA_MAX_B if msg.is_fd else CLASSIC_DATA_MAX_B
        if len(data) > limit:
            raise BusError(
                f"hilbus: frame 0x{msg.arbitration_id:X} has {len(data)} data bytes, "
                f"more than {limit} ({'CAN FD' if msg.is_fd else 'classic CAN'})"
            )
        flags = (
            (FLAG_EXTENDED if msg.is_extended_id else 0)
            | (FLAG_REMOTE if msg.is_remote_frame else 0)
            | (FLAG_ERROR if msg.is_error_frame else 0)
            | (FLAG_FD if msg.is_fd else 0)
            | (FLAG_BRS if msg.bitrate_switch else 0)
            | (FLAG_ESI if msg.error_state_indicator else 0)
        )
        dlc = msg.dlc if msg.dlc is not None else len(data)
        return (
            HEADER.pack(time.time(), msg.arbitration_id & 0xFFFFFFFF, flags, dlc & 0xFF, len(data))
            + data
        )

    @property
    def overrun_drops_by_pid(self) -> dict[int, int]:
        """:attr:`overrun_drops_to` by the overrun member's process id (from its socket name)."""
        out: dict[int, int] = {}
        for name, n in self.overrun_drops_to.items():
            pid = _member_pid(name)
            if pid is not None:
                out[pid] = out.get(pid, 0) + n
        return out

    def _send_to(self, peer: _Peer, record: bytes, deadline: float | None) -> None:
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
                if exc.errno in _STALE_ERRNOS:
                    self._stale(peer.name)
                    return
                if exc.errno != errno.ENOBUFS:
                    raise can.CanOperationError(
                        f"hilbus: send to member {peer.name} failed: {exc}"
                    ) from exc
                full_retry = True  # macOS: receiver full, no way to wait for room
            if self._closed:  # set before shutdown() wakes us, so checked after any drain
                raise can.CanOperationError("hilbus: bus shut down during send")
            if peer.overrun or _poll_ms(stall_deadline) == 0:
                peer.overrun = True  # it has not read for member_stall_s: drop, as a CAN
                self.overrun_drops += 1  # controller's full receive buffer does
                self.overrun_drops_to[peer.name] = self.overrun_drops_to.get(peer.name, 0) + 1
                return
            wait_ms = _poll_ms(deadline)
            if wait_ms == 0:
                raise can.CanOperationError(
                    f"hilbus: send timed out: member {peer.name} on channel "
                    f"{self.channel!r} is not reading"
                )
            stall_ms = _poll_ms(stall_deadline)
            if stall_ms is not None:
                wait_ms = stall_ms if wait_ms is None else min(wait_ms, stall_ms)
            if full_retry:  # only our own socket can wake us: cap the wait
                cap_ms = max(1, int(FULL_RETRY_S * 1000))
                wait_ms = cap_ms if wait_ms is None else min(wait_ms, cap_ms)
                events = dict(self._poller.poll(wait_ms))
            else:
                events = dict(peer.poller.poll(wait_ms))
            if events.get(self._sock.fileno(), 0) & select.POLLIN:
                self._drain()  # keep our own queue moving: no deadlock between bursters
            if events.get(peer.sock.fileno(), 0) & select.POLLOUT:
                spurious += 1

    def _drain(self) -> None:
        """Move every queued datagram of our socket to the backlog (keeping order)."""
        with self._rx_lock:
            self._drain_locked()
            if self._backlog:
                self._wake_self()

    def _drain_locked(self) -> None:
        # after shutdown() the socket reads as end-of-file (empty records) for ever: stop
        while not self._closed:
            try:
                record, rx_time = self._recv_record()
            except BlockingIOError:
                break
            if record:
                self._backlog.append((rx_time, record))

    def _recv_record(self) -> tuple[bytes, float]:
        """One datagram of our socket (non-blocking) and its time of arrival.

        The arrival time is the kernel's stamp of when the datagram was queued to us (as
        SocketCAN's receive timestamps are), else :func:`time.time` now. Raises
        BlockingIOError when nothing is queued.
        """
        if not self._kernel_stamps:
            return self._sock.recv(DATAGRAM_MAX_B, socket.MSG_DONTWAIT), time.time()
        record, ancillary, _flags, _addr = self._sock.recvmsg(
            DATAGRAM_MAX_B, TIMESTAMP_CMSG_B, socket.MSG_DONTWAIT
        )
        for level, kind, data in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and len(data) >= TIMESPEC.size:
                sec, nsec = TIMESPEC.unpack_from(data)
                return record, sec + nsec / NS_PER_S
        return record, time.time()

    def _wake_self(self) -> None:
        """Queue an empty datagram so fileno() reads as readable while a backlog waits."""
        with contextlib.suppress(OSError):  # full: readable anyway
            self._sock.sendto(b"", socket.MSG_DONTWAIT, self._path_b)

    def _deliver_own(self, record: bytes) -> None:
        own = record[:12] + bytes((record[12] | FLAG_OWN,)) + record[13:]
        with self._rx_lock:
            try:
                self._sock.sendto(own, socket.MSG_DONTWAIT, self._path_b)
                return
            except OSError:
                pass  # our queue is full: move it to the backlog, then append behind it
            self._drain_locked()
            self._backlog.append((time.time(), own))
            self._wake_self()

    # ---------------------------------------------------------------- receiving

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        deadline = _deadline(timeout)
        record: bytes | None
        while True:
            if self._closed:
                raise can.CanOperationError("hilbus: receive on a bus that was shut down")
            with self._rx_lock:
                if self._backlog:
                    rx_time, record = self._backlog.popleft()
                else:
                    try:
                        record, rx_time = self._recv_record()
                    except BlockingIOError:
                        record = None
                    except OSError as exc:
                        raise can.CanOperationError(f"hilbus: receive failed: {exc}") from exc
            if record is None:
                wait_ms = _poll_ms(deadline)
                if wait_ms == 0 or not self._poller.poll(wait_ms):
                    return None, False
                continue
            if not record:
                continue  # a wake-up datagram
            self._rx_since_scan = True
            msg = self._decode(self._split(record, rx_time), rx_time)
            if msg is None:
                self.malformed_records += 1
                continue
            return msg, False

    def _split(self, datagram: bytes, rx_time: float) -> bytes:
        """The first record of a burst datagram; the others go to the front of the backlog.

        A datagram of one record is returned as it is (it may be malformed: _decode says).
        In a longer one the first record is whole (its length is below the datagram's);
        trailing bytes that do not make a whole record are counted as malformed.
        """
        end = HEADER.size + (datagram[HEADER.size - 1] if len(datagram) >= HEADER.size else 0)
        if len(datagram) <= end:
            return datagram
        records = []
        start = 0
        while start + HEADER.size <= len(datagram):
            end = start + HEADER.size + datagram[start + HEADER.size - 1]
            if end > len(datagram):
                break
            records.append(datagram[start:end])
            start = end
        if start != len(datagram):
            self.malformed_records += 1  # the trailing bytes; the records before are good
        with self._rx_lock:
            self._backlog.extendleft((rx_time, r) for r in reversed(records[1:]))
        if self._fileno_used and len(records) > 1:
            self._wake_self()  # fileno() must read as readable while these wait
        return records[0]

    def _decode(self, record: bytes, rx_time: float) -> HilMessage | None:
        if len(record) < HEADER.size:
            return None
        tx_time, arbitration_id, flags, dlc, length = HEADER.unpack_from(record)
        if len(record) != HEADER.size + length or length > DATA_MAX_B:
            return None
        # the receive hot path: can.Message.__init__ with its parameters in their documented
        # order (python-can 4), which costs a quarter of the keyword call through __init__
        msg = HilMessage.__new__(HilMessage)
        can.Message.__init__(
            msg, rx_time, arbitration_id, bool(flags & FLAG_EXTENDED), bool(flags & FLAG_REMOTE),
            bool(flags & FLAG_ERROR), self.channel, dlc, record[HEADER.size :],
            bool(flags & FLAG_FD), not flags & FLAG_OWN, bool(flags & FLAG_BRS),
            bool(flags & FLAG_ESI),
        )
        msg.tx_timestamp = tx_time
        return msg

    # ---------------------------------------------------------------- python-can API

    def fileno(self) -> int:
        """The member socket: readable whenever a frame is waiting (for select/asyncio)."""
        self._fileno_used = True  # from now on, records of a burst left waiting wake it
        return self._sock.fileno()

    def flush_tx_buffer(self) -> None:
        """Nothing to flush: a send returns only once every member has the frame queued."""

    @property
    def state(self) -> BusState:
        """ACTIVE (sends allowed) or PASSIVE (listen-only: sends raise)."""
        return self._state

    @state.setter
    def state(self, new_state: BusState) -> None:
        if new_state not in (BusState.ACTIVE, BusState.PASSIVE):
            raise BusError(f"hilbus: state {new_state} unsupported (ACTIVE or PASSIVE)")
        self._state = new_state

    def shutdown(self) -> None:
        """Leave the channel: unlink this member's socket file and close every socket."""
        if self._closed:
            return
        self._closed = True
        try:
            super().shutdown()
        finally:
            # wake threads blocked in recv() or in a send() waiting for a full member: they
            # see _closed and raise CanOperationError (and release the tx lock). SHUT_RD
            # leaves the socket readable for every waiter (a wake-up datagram could be
            # consumed by one before another saw it); members sending to us get EPIPE.
            try:
                self._sock.shutdown(socket.SHUT_RD)
            except OSError:
                self._wake_self()
            with contextlib.suppress(OSError):
                os.unlink(self.path)
            with self._tx_lock:
                for peer in self._peers.values():
                    peer.sock.close()
                self._peers.clear()
            with contextlib.suppress(KeyError, ValueError):
                self._poller.unregister(self._sock.fileno())
            self._sock.close()
            os.close(self._dir_fd)

    @staticmethod
    def _detect_available_configs() -> Sequence[AutoDetectedConfig]:
        """Channels of this user that have at least one member whose process is alive."""
        root = bus_root()
        try:
            if not _is_private_dir(os.lstat(root)):
                return []
            channels = sorted(os.listdir(root))
        except OSError:
            return []
        found: list[AutoDetectedConfig] = []
        for ch in channels:
            if not CHANNEL_RE.fullmatch(ch) or ch in (".", ".."):
                continue
            try:
                members = os.listdir(root / ch)
            except OSError:
                continue
            pids = (_member_pid(n) for n in members)
            if any(pid is not None and _pid_alive(pid) for pid in pids):
                found.append({"interface": INTERFACE_NAME, "channel": ch})
        return found
