"""Tests of the portable cross-process CAN bus :mod:`transport.hilbus`.

Every test runs in its own private runtime directory (``$XDG_RUNTIME_DIR`` pointed at a
fresh short temporary directory), so nothing touches the user's real channels. Waits are
bounded by deadlines on real events (frames, output lines), never by sleeping.
"""

from __future__ import annotations

import copy
import os
import queue
import select
import signal
import socket
import stat
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import can
import pytest

from dbc.errors import BusError
from transport.hilbus import (
    BURST_MAX_RECORDS,
    HEADER,
    HilBus,
    HilMessage,
    bus_root,
    channel_dir,
    tx_timestamp_of,
)

DEADLINE_S = 30.0
TIMEOUT_SLACK_S = 0.5
BURST_N = 10_000
QUEUE_OVERFILL_N = 200  # well past Linux's default of 10 queued datagrams per socket


@pytest.fixture
def channel(runtime: Path) -> str:
    """A channel name unique to the test."""
    return f"t-{uuid.uuid4().hex[:8]}"


@pytest.fixture
def pair(channel: str) -> Iterator[tuple[HilBus, HilBus]]:
    """Two members A and B of one channel."""
    with HilBus(channel) as a, HilBus(channel) as b:
        yield a, b


def _env(runtime: Path) -> dict[str, str]:
    return {**os.environ, "XDG_RUNTIME_DIR": str(runtime), "PYTHONUNBUFFERED": "1"}


def _key(m: can.Message) -> tuple[object, ...]:
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


def _variety() -> list[can.Message]:
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


def _recv_n(bus: can.BusABC, n: int, deadline_s: float = DEADLINE_S) -> list[can.Message]:
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


class _Collector(threading.Thread):
    """Receives n frames on a bus in the background (senders block without a reader)."""

    def __init__(self, bus: can.BusABC, n: int) -> None:
        super().__init__(daemon=True)
        self.bus = bus
        self.n = n
        self.got: list[can.Message] = []
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.got = _recv_n(self.bus, self.n)
        except BaseException as exc:  # reported by result()
            self.error = exc

    def result(self) -> list[can.Message]:
        self.join(DEADLINE_S)
        assert not self.is_alive(), "collector still running"
        if self.error is not None:
            raise self.error
        return self.got


class _Lines:
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
        seen = []
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


def test_frames_of_every_kind_round_trip(pair: tuple[HilBus, HilBus]) -> None:
    """DLC 0..8, standard/extended IDs, remote, error and FD frames arrive unchanged."""
    a, b = pair
    sent = _variety()
    collector = _Collector(b, len(sent))
    collector.start()
    before = time.time()
    for m in sent:
        a.send(m)
    got = collector.result()
    assert [_key(m) for m in got] == [_key(m) for m in sent]
    for m in got:
        assert isinstance(m, HilMessage)
        assert m.is_rx and m.channel == b.channel
        assert m.tx_timestamp is not None
        assert before <= m.tx_timestamp <= m.timestamp


def test_both_directions(pair: tuple[HilBus, HilBus]) -> None:
    """B's frames reach A just as A's reach B."""
    a, b = pair
    a.send(can.Message(arbitration_id=0x10, data=b"a"))
    b.send(can.Message(arbitration_id=0x11, data=b"b"))
    assert bytes(_recv_n(b, 1)[0].data) == b"a"
    assert bytes(_recv_n(a, 1)[0].data) == b"b"


def test_burst_is_ordered_and_complete(pair: tuple[HilBus, HilBus]) -> None:
    """A 10 000-frame burst arrives complete and in order (a slow reader blocks the sender)."""
    a, b = pair
    collector = _Collector(b, BURST_N)
    collector.start()
    for i in range(BURST_N):
        a.send(can.Message(arbitration_id=i & 0x7FF, data=i.to_bytes(4, "little")))
    got = collector.result()
    assert [int.from_bytes(m.data, "little") for m in got] == list(range(BURST_N))
    assert b.recv(timeout=0) is None


def test_send_burst_arrives_as_single_frames_in_order(pair: tuple[HilBus, HilBus]) -> None:
    """send_burst: every kind of frame arrives unchanged, in order, one recv() each."""
    a, b = pair
    sent = _variety()
    a.send_burst(sent)
    got = _recv_n(b, len(sent))
    assert [_key(m) for m in got] == [_key(m) for m in sent]
    assert len({m.timestamp for m in got}) == 1  # one datagram: one arrival time
    assert b.recv(timeout=0) is None and b.malformed_records == 0


def test_send_burst_is_one_datagram_per_member_up_to_the_record_limit(
    pair: tuple[HilBus, HilBus],
) -> None:
    """A burst of N frames queues ceil(N / BURST_MAX_RECORDS) datagrams at the receiver."""
    a, b = pair
    n = 2 * BURST_MAX_RECORDS + 1
    a.send_burst([can.Message(arbitration_id=i, data=i.to_bytes(2, "little")) for i in range(n)])
    datagrams = []
    while True:  # read b's socket raw: what the sender queued, datagram by datagram
        try:
            datagrams.append(b._sock.recv(1 << 16, socket.MSG_DONTWAIT))
        except BlockingIOError:
            break
    assert len(datagrams) == 3
    assert [len(d) for d in datagrams] == [(HEADER.size + 2) * BURST_MAX_RECORDS] * 2 + [
        HEADER.size + 2]


def test_burst_then_single_frames_keep_their_order(pair: tuple[HilBus, HilBus]) -> None:
    """Frames sent after a burst are received after all of the burst's frames."""
    a, b = pair
    a.send_burst([can.Message(arbitration_id=i) for i in range(5)])
    a.send(can.Message(arbitration_id=5))
    a.send_burst([can.Message(arbitration_id=i) for i in (6, 7)])
    assert [m.arbitration_id for m in _recv_n(b, 8)] == list(range(8))


def test_burst_with_receive_own_messages(channel: str) -> None:
    """A burst is delivered to its sender too, frame by frame, marked as sent (is_rx False)."""
    with HilBus(channel, receive_own_messages=True) as a, HilBus(channel) as b:
        a.send_burst([can.Message(arbitration_id=i) for i in range(3)])
        own = _recv_n(a, 3)
        assert [m.arbitration_id for m in own] == [0, 1, 2]
        assert not any(m.is_rx for m in own)
        assert [m.arbitration_id for m in _recv_n(b, 3)] == [0, 1, 2]


def test_fileno_stays_readable_while_a_burst_is_being_read(pair: tuple[HilBus, HilBus]) -> None:
    """After the first frame of a burst is read, fileno() still reads as readable."""
    a, b = pair
    fd = b.fileno()
    a.send_burst([can.Message(arbitration_id=i) for i in range(3)])
    for i in range(3):
        r, _, _ = select.select([fd], [], [], DEADLINE_S)
        assert r == [fd], f"fileno not readable before frame {i}"
        assert _recv_n(b, 1)[0].arbitration_id == i
    assert b.recv(timeout=0) is None


def test_burst_with_trailing_garbage_keeps_whole_records(pair: tuple[HilBus, HilBus]) -> None:
    """A datagram of records plus a torn one: the whole records arrive, the rest is counted."""
    _a, b = pair
    rec = HEADER.pack(0.0, 0x12, 0, 2, 2) + b"\x01\x02"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as raw:
        raw.sendto(rec + rec + rec[:5], os.fspath(b.path))
    got = _recv_n(b, 2)
    assert [bytes(m.data) for m in got] == [b"\x01\x02", b"\x01\x02"]
    assert b.recv(timeout=0) is None
    assert b.malformed_records == 1


def test_bursters_in_one_thread_each_do_not_deadlock(pair: tuple[HilBus, HilBus]) -> None:
    """Two members that each send a long burst before reading both finish."""
    results: dict[str, list[int]] = {}

    def burst_then_read(me: HilBus, tag: str) -> None:
        for i in range(QUEUE_OVERFILL_N):
            me.send(can.Message(arbitration_id=i, data=b"x"), timeout=DEADLINE_S)
        results[tag] = [m.arbitration_id for m in _recv_n(me, QUEUE_OVERFILL_N)]

    threads = [
        threading.Thread(target=burst_then_read, args=(bus, tag), daemon=True)
        for bus, tag in zip(pair, "ab", strict=True)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join(DEADLINE_S)
    assert results == {"a": list(range(QUEUE_OVERFILL_N)), "b": list(range(QUEUE_OVERFILL_N))}


def test_permissions_of_directories_and_socket(channel: str) -> None:
    """Channel directories are 0700 and owned by us; member sockets are 0600."""
    with HilBus(channel) as bus:
        for d in (bus_root(), channel_dir(channel)):
            st = os.lstat(d)
            assert stat.S_ISDIR(st.st_mode)
            assert stat.S_IMODE(st.st_mode) == 0o700
            assert st.st_uid == os.getuid()
        st = os.lstat(bus.path)
        assert stat.S_ISSOCK(st.st_mode)
        assert stat.S_IMODE(st.st_mode) == 0o600
        assert bus.path.parent == channel_dir(channel)
        assert bus.path.name.startswith(f"{os.getpid()}-")


def test_permissive_directory_is_refused(runtime: Path, channel: str) -> None:
    """An existing bus directory with group/other permissions is refused, naming it."""
    root = bus_root()
    root.mkdir(mode=0o700)
    root.chmod(0o755)
    with pytest.raises(BusError, match=str(root)):
        HilBus(channel)


def test_symlinked_directory_is_refused(runtime: Path, channel: str) -> None:
    """A symlink in place of the bus directory is refused, naming it."""
    target = runtime / "elsewhere"
    target.mkdir(mode=0o700)
    bus_root().symlink_to(target)
    with pytest.raises(BusError, match=str(bus_root())):
        HilBus(channel)


@pytest.mark.parametrize("bad", ["", "a/b", ".", "..", "x y", "ch\u00e9", "a\0b", "../up"])
def test_bad_channel_name_raises(runtime: Path, bad: str) -> None:
    """A channel name outside [A-Za-z0-9_.-]+ (or . / ..) raises BusError naming it."""
    with pytest.raises(BusError, match="channel") as info:
        HilBus(bad)
    assert repr(bad) in str(info.value)


def test_too_long_socket_path_raises(channel: str) -> None:
    """A channel name too long for a Unix socket path raises BusError."""
    with pytest.raises(BusError, match="longer than"):
        HilBus("c" * 120)


def test_receive_own_messages(channel: str) -> None:
    """With receive_own_messages a sent frame also arrives locally (is_rx False)."""
    with HilBus(channel, receive_own_messages=True) as a, HilBus(channel) as b:
        a.send(can.Message(arbitration_id=0x42, data=b"own"))
        mine = _recv_n(a, 1)[0]
        assert (mine.arbitration_id, bytes(mine.data), mine.is_rx) == (0x42, b"own", False)
        theirs = _recv_n(b, 1)[0]
        assert theirs.is_rx
        b.send(can.Message(arbitration_id=0x43))
        assert _recv_n(a, 1)[0].arbitration_id == 0x43
        assert b.recv(timeout=0) is None  # b does not receive its own


def test_receive_own_messages_beyond_queue_size(channel: str) -> None:
    """Own frames beyond the socket's queue are kept, in order, without blocking."""
    with HilBus(channel, receive_own_messages=True) as a:
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i))
        r, _, _ = select.select([a.fileno()], [], [], 0)
        assert r, "fileno() not readable while own frames wait"
        got = _recv_n(a, QUEUE_OVERFILL_N)
        assert [m.arbitration_id for m in got] == list(range(QUEUE_OVERFILL_N))
        assert a.recv(timeout=0) is None


def test_recv_timeouts(pair: tuple[HilBus, HilBus]) -> None:
    """recv(0) returns None at once, recv(t) returns None after about t, a frame at once."""
    a, b = pair
    t0 = time.monotonic()
    assert b.recv(timeout=0) is None
    assert time.monotonic() - t0 < TIMEOUT_SLACK_S
    t0 = time.monotonic()
    assert b.recv(timeout=0.1) is None
    assert 0.1 <= time.monotonic() - t0 < 0.1 + TIMEOUT_SLACK_S
    a.send(can.Message(arbitration_id=1))
    assert b.recv(timeout=0) is not None


def test_send_timeout_when_a_member_does_not_read(pair: tuple[HilBus, HilBus]) -> None:
    """A member that never reads makes send(timeout=t) fail after t, not hang."""
    a, _b = pair
    t0 = time.monotonic()
    with pytest.raises(can.CanOperationError, match="not reading"):
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i), timeout=0.1)
    assert time.monotonic() - t0 < DEADLINE_S


def test_shutdown_wakes_blocked_send_and_recv(pair: tuple[HilBus, HilBus]) -> None:
    """shutdown() in one thread ends a send blocked on a full member and a recv(None)."""
    a, _b = pair
    with pytest.raises(can.CanOperationError, match="not reading"):
        for i in range(QUEUE_OVERFILL_N):  # fill B's queue (B never reads)
            a.send(can.Message(arbitration_id=i), timeout=0.05)
    errors: dict[str, BaseException] = {}

    def call(tag: str, fn: Callable[[], object]) -> None:
        try:
            fn()
        except BaseException as exc:  # inspected below
            errors[tag] = exc

    threads = [
        threading.Thread(target=call, args=("send", lambda: a.send(can.Message())), daemon=True),
        threading.Thread(target=call, args=("recv", lambda: a.recv(timeout=None)), daemon=True),
    ]
    for t in threads:
        t.start()
    a.shutdown()
    for t in threads:
        t.join(DEADLINE_S)
        assert not t.is_alive(), "a thread stayed blocked after shutdown()"
    assert sorted(errors) == ["recv", "send"]
    assert all(isinstance(e, can.CanOperationError) for e in errors.values()), errors


def test_member_joining_after_a_send_receives(channel: str) -> None:
    """A member that joins right after another's send gets that member's next frame."""
    with HilBus(channel) as a:
        a.send(can.Message(arbitration_id=1))  # scans: nobody there
        with HilBus(channel) as b:
            a.send(can.Message(arbitration_id=2))
            assert _recv_n(b, 1)[0].arbitration_id == 2


def test_filters(channel: str) -> None:
    """python-can software filters apply."""
    with (
        HilBus(channel) as a,
        HilBus(channel, can_filters=[{"can_id": 0x10, "can_mask": 0x7F0, "extended": False}]) as b,
    ):
        for ident in (0x20, 0x13, 0x21, 0x1F):
            a.send(can.Message(arbitration_id=ident, is_extended_id=False))
        assert [m.arbitration_id for m in _recv_n(b, 2)] == [0x13, 0x1F]
        assert b.recv(timeout=0) is None


def test_notifier_and_select_use_fileno(pair: tuple[HilBus, HilBus]) -> None:
    """fileno() turns readable on a frame, and can.Notifier delivers it."""
    a, b = pair
    a.send(can.Message(arbitration_id=5))
    r, _, _ = select.select([b.fileno()], [], [], DEADLINE_S)
    assert r == [b.fileno()]
    assert _recv_n(b, 1)[0].arbitration_id == 5
    reader = can.BufferedReader()
    notifier = can.Notifier(b, [reader], timeout=0.1)
    try:
        a.send(can.Message(arbitration_id=6))
        m = reader.get_message(timeout=DEADLINE_S)
        assert m is not None and m.arbitration_id == 6
    finally:
        notifier.stop()


def test_tx_timestamp_survives_copies(pair: tuple[HilBus, HilBus]) -> None:
    """tx_timestamp_of reads the sender's time; copy and deepcopy keep it."""
    a, b = pair
    a.send(can.Message(arbitration_id=7, data=b"\x01"))
    m = _recv_n(b, 1)[0]
    tx = tx_timestamp_of(m)
    assert tx is not None and tx <= m.timestamp
    for c in (copy.copy(m), copy.deepcopy(m)):
        assert tx_timestamp_of(c) == tx and _key(c) == _key(m)
    assert tx_timestamp_of(can.Message()) is None


def test_malformed_datagram_is_dropped_and_counted(pair: tuple[HilBus, HilBus]) -> None:
    """A datagram that is not a valid record is counted and skipped, never raised."""
    a, b = pair
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as raw:
        raw.sendto(b"junk", os.fspath(b.path))
        raw.sendto(HEADER.pack(0.0, 1, 0, 8, 8) + b"\x00", os.fspath(b.path))
    a.send(can.Message(arbitration_id=9))
    assert _recv_n(b, 1)[0].arbitration_id == 9
    assert b.malformed_records == 2


def test_oversized_frame_is_refused(pair: tuple[HilBus, HilBus]) -> None:
    """Nine data bytes without FD (or 65 with) raise BusError."""
    a, _b = pair
    with pytest.raises(BusError, match="9 data bytes"):
        a.send(can.Message(arbitration_id=1, data=bytes(9)))
    with pytest.raises(BusError, match="65 data bytes"):
        a.send(can.Message(arbitration_id=1, is_fd=True, data=bytes(65)))


def test_passive_state_is_listen_only(pair: tuple[HilBus, HilBus]) -> None:
    """state PASSIVE refuses sends but still receives; ERROR is not a settable state."""
    a, b = pair
    assert a.state is can.BusState.ACTIVE
    a.state = can.BusState.PASSIVE
    with pytest.raises(can.CanOperationError, match="listen-only"):
        a.send(can.Message(arbitration_id=1))
    b.send(can.Message(arbitration_id=2))
    assert _recv_n(a, 1)[0].arbitration_id == 2
    with pytest.raises(BusError):
        a.state = can.BusState.ERROR


def test_shutdown_unlinks_socket_and_is_idempotent(channel: str) -> None:
    """shutdown() removes the member's socket file; a second shutdown is harmless."""
    bus = HilBus(channel)
    assert bus.path.exists()
    bus.shutdown()
    assert not bus.path.exists()
    bus.shutdown()
    with pytest.raises(can.CanOperationError):
        bus.send(can.Message())


def test_python_can_entry_point_and_detect_configs(channel: str) -> None:
    """can.Bus(interface='hilbus') works and detect_available_configs lists live channels."""
    with can.Bus(interface="hilbus", channel=channel) as bus:
        assert isinstance(bus, HilBus)
        configs = can.detect_available_configs(interfaces=["hilbus"])
        assert {"interface": "hilbus", "channel": channel} in configs
    assert {"interface": "hilbus", "channel": channel} not in can.detect_available_configs(
        interfaces=["hilbus"]
    )


def test_stale_socket_of_killed_process_is_removed(runtime: Path, channel: str) -> None:
    """A member killed without shutdown is dropped and its socket file unlinked on send."""
    code = (
        "import sys; from transport.hilbus import HilBus; "
        f"b = HilBus({channel!r}); print(b.path, flush=True); sys.stdin.read()"
    )
    with HilBus(channel) as a, HilBus(channel) as b:
        with subprocess.Popen(
            [sys.executable, "-c", code],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=_env(runtime),
            cwd=runtime,
        ) as child:
            assert child.stdout is not None
            stale = Path(_Lines(child.stdout).wait_for(channel).strip())
            assert stale.exists()
            child.send_signal(signal.SIGKILL)
            child.wait(DEADLINE_S)
        assert stale.exists()
        a.send(can.Message(arbitration_id=0x55))
        assert not stale.exists()
        assert _recv_n(b, 1)[0].arbitration_id == 0x55


def test_stale_socket_of_live_process_is_skipped_not_unlinked(channel: str) -> None:
    """A refusing socket whose pid is alive is skipped but left in place."""
    with HilBus(channel) as a, HilBus(channel) as b:
        orphan = channel_dir(channel) / f"{os.getpid()}-0badcafe.sock"
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.bind(os.fspath(orphan))
        a.send(can.Message(arbitration_id=0x56))
        assert _recv_n(b, 1)[0].arbitration_id == 0x56
        assert orphan.exists()
        orphan.unlink()


ECHO_CODE = """
import can
from transport.hilbus import HilBus
with HilBus({channel!r}) as bus:
    bus.send(can.Message(arbitration_id=0x700))  # ready
    while True:
        m = bus.recv(timeout=30)
        if m is None or m.arbitration_id == 0x7FF:
            break
        bus.send(can.Message(arbitration_id=m.arbitration_id + 1, data=m.data[::-1],
                             is_extended_id=m.is_extended_id))
"""


def test_cross_process_exchange(runtime: Path, channel: str) -> None:
    """Frames go to a second OS process and its replies come back, in order."""
    with (
        HilBus(channel) as bus,
        subprocess.Popen(
            [sys.executable, "-c", ECHO_CODE.format(channel=channel)],
            env=_env(runtime),
            cwd=runtime,
        ) as child,
    ):
        try:
            assert _recv_n(bus, 1)[0].arbitration_id == 0x700
            for i in range(QUEUE_OVERFILL_N):
                bus.send(can.Message(arbitration_id=0x100 + 2 * i, data=bytes([i, 1, 2])))
            got = _recv_n(bus, QUEUE_OVERFILL_N)
            assert [(m.arbitration_id, bytes(m.data)) for m in got] == [
                (0x101 + 2 * i, bytes([2, 1, i])) for i in range(QUEUE_OVERFILL_N)
            ]
            assert all(m.is_rx and tx_timestamp_of(m) is not None for m in got)
            bus.send(can.Message(arbitration_id=0x7FF))
            assert child.wait(DEADLINE_S) == 0
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()


def test_can_logger_prints_frames(runtime: Path, channel: str) -> None:
    """python -m can.logger -i hilbus -c CHANNEL prints frames sent on the channel."""
    with subprocess.Popen(
        [sys.executable, "-m", "can.logger", "-i", "hilbus", "-c", channel],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**_env(runtime), "PYTHONFAULTHANDLER": "1"},  # SIGABRT dumps its stacks
        cwd=runtime,
        # Ctrl-C reaches it as from a terminal, even when this run's SIGINT is ignored (a
        # background job inherits SIG_IGN, and so would the logger: seen in CI)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    ) as logger:
        try:
            assert logger.stdout is not None
            lines = _Lines(logger.stdout)
            lines.wait_for("Connected to HilBus")
            with HilBus(channel) as bus:
                bus.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\xca\xfe"))
                bus.send(can.Message(arbitration_id=0x1BADBEE, data=b"\x01\x02\x03"))
                first = lines.wait_for("ID:")
                second = lines.wait_for("ID:")
            assert "123" in first and "ca fe" in first and channel in first
            assert "1badbee" in second.lower() and "01 02 03" in second
            logger.send_signal(signal.SIGINT)  # can.logger shuts the bus down on Ctrl-C
            try:
                logger.wait(DEADLINE_S)
            except subprocess.TimeoutExpired:
                logger.send_signal(signal.SIGABRT)  # where is it stuck? (faulthandler)
                pytest.fail("can.logger ignored Ctrl-C for "
                            f"{DEADLINE_S} s; its stacks:\n{''.join(lines.rest())}")
        finally:
            if logger.poll() is None:
                logger.kill()
                logger.wait()
    assert list(channel_dir(channel).iterdir()) == []


READ_LATER_S = 0.2  # how long the frame waits in the queue before it is read


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="kernel stamps are Linux's")
def test_timestamp_is_the_arrival_not_the_read(pair: tuple[HilBus, HilBus]) -> None:
    """A frame read late keeps the kernel's arrival time: latency excludes the reader's delay."""
    a, b = pair
    a.send(can.Message(arbitration_id=0x40, data=b"\x01\x02", is_extended_id=False))
    time.sleep(READ_LATER_S)  # the stimulus: the frame waits unread in b's queue
    read_s = time.time()
    m = b.recv(timeout=DEADLINE_S)
    assert m is not None and m.tx_timestamp is not None
    assert m.tx_timestamp <= m.timestamp < m.tx_timestamp + READ_LATER_S / 2
    assert read_s - m.timestamp >= READ_LATER_S / 2


STALL_S = 0.25  # member_stall_s of the sender in the overrun tests


def _drain_all(bus: HilBus) -> list[can.Message]:
    """Every frame queued for ``bus`` now (it has stopped receiving new ones)."""
    got = []
    while (m := bus.recv(timeout=0)) is not None:
        got.append(m)
    return got


def test_member_that_stops_reading_is_overrun_while_others_get_every_frame(channel: str) -> None:
    """A non-reading member holds the sender up once, then loses frames; the others lose none."""
    with HilBus(channel, member_stall_s=STALL_S) as a, HilBus(channel) as b, \
            HilBus(channel) as stuck:
        collector = _Collector(b, QUEUE_OVERFILL_N)
        collector.start()
        t0 = time.monotonic()
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i))
        # one stall, not one per frame (that would be QUEUE_OVERFILL_N * STALL_S = 50 s)
        assert time.monotonic() - t0 < DEADLINE_S
        assert [m.arbitration_id for m in collector.result()] == list(range(QUEUE_OVERFILL_N))
        kept = _drain_all(stuck)
        assert 0 < a.overrun_drops < QUEUE_OVERFILL_N
        assert len(kept) + a.overrun_drops == QUEUE_OVERFILL_N  # each frame delivered or counted
        ids = [m.arbitration_id for m in kept]
        assert ids == sorted(ids) and ids[0] == 0  # the oldest were kept, in order
        # it reads again: the next frame reaches it, and nothing more is dropped
        a.send(can.Message(arbitration_id=0x7FF))
        m = stuck.recv(timeout=DEADLINE_S)
        assert m is not None and m.arbitration_id == 0x7FF
        drops = a.overrun_drops
        a.send(can.Message(arbitration_id=0x7FE))
        assert a.overrun_drops == drops


@pytest.mark.parametrize("bad", [-1.0, "soon", float("nan")])
def test_bad_member_stall_is_refused(channel: str, bad: object) -> None:
    """member_stall_s must be seconds >= 0 or None; the error names the value."""
    with pytest.raises(BusError, match="member_stall_s"):
        HilBus(channel, member_stall_s=bad)  # type: ignore[arg-type]
