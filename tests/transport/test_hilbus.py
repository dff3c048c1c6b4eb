"""Tests of the portable bus :mod:`transport.hilbus`: frames, bursts and receive semantics.

Every test runs in its own private runtime directory (``$XDG_RUNTIME_DIR`` pointed at a
fresh short temporary directory) on a channel of its own, so nothing touches the user's
real channels. Waits are bounded by deadlines on real events (frames), never by sleeping.
"""

from __future__ import annotations

import copy
import os
import select
import socket
import sys
import threading
import time

import can
import pytest

from dbc.errors import BusError
from tests.transport.helpers import (
    DEADLINE_S,
    QUEUE_OVERFILL_N,
    Collector,
    frame_key,
    recv_n,
    variety,
)
from transport.hilbus import HilBus, HilMessage, tx_timestamp_of
from transport.wire import BURST_MAX_RECORDS, HEADER

TIMEOUT_SLACK_S = 0.5
BURST_N = 10_000


def test_frames_of_every_kind_round_trip(pair: tuple[HilBus, HilBus]) -> None:
    """DLC 0..8, standard/extended IDs, remote, error and FD frames arrive unchanged."""
    a, b = pair
    sent = variety()
    collector = Collector(b, len(sent))
    collector.start()
    before = time.time()
    for m in sent:
        a.send(m)
    got = collector.result()
    assert [frame_key(m) for m in got] == [frame_key(m) for m in sent]
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
    assert bytes(recv_n(b, 1)[0].data) == b"a"
    assert bytes(recv_n(a, 1)[0].data) == b"b"


def test_burst_is_ordered_and_complete(pair: tuple[HilBus, HilBus]) -> None:
    """A 10 000-frame burst arrives complete and in order (a slow reader blocks the sender)."""
    a, b = pair
    collector = Collector(b, BURST_N)
    collector.start()
    for i in range(BURST_N):
        a.send(can.Message(arbitration_id=i & 0x7FF, data=i.to_bytes(4, "little")))
    got = collector.result()
    assert [int.from_bytes(m.data, "little") for m in got] == list(range(BURST_N))
    assert b.recv(timeout=0) is None


def test_send_burst_arrives_as_single_frames_in_order(pair: tuple[HilBus, HilBus]) -> None:
    """send_burst: every kind of frame arrives unchanged, in order, one recv() each."""
    a, b = pair
    sent = variety()
    a.send_burst(sent)
    got = recv_n(b, len(sent))
    assert [frame_key(m) for m in got] == [frame_key(m) for m in sent]
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
            datagrams.append(b._inbox.sock.recv(1 << 16, socket.MSG_DONTWAIT))
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
    assert [m.arbitration_id for m in recv_n(b, 8)] == list(range(8))


def test_burst_with_receive_own_messages(channel: str) -> None:
    """A burst is delivered to its sender too, frame by frame, marked as sent (is_rx False)."""
    with HilBus(channel, receive_own_messages=True) as a, HilBus(channel) as b:
        a.send_burst([can.Message(arbitration_id=i) for i in range(3)])
        own = recv_n(a, 3)
        assert [m.arbitration_id for m in own] == [0, 1, 2]
        assert not any(m.is_rx for m in own)
        assert [m.arbitration_id for m in recv_n(b, 3)] == [0, 1, 2]


def test_fileno_stays_readable_while_a_burst_is_being_read(pair: tuple[HilBus, HilBus]) -> None:
    """After the first frame of a burst is read, fileno() still reads as readable."""
    a, b = pair
    fd = b.fileno()
    a.send_burst([can.Message(arbitration_id=i) for i in range(3)])
    for i in range(3):
        r, _, _ = select.select([fd], [], [], DEADLINE_S)
        assert r == [fd], f"fileno not readable before frame {i}"
        assert recv_n(b, 1)[0].arbitration_id == i
    assert b.recv(timeout=0) is None


def test_burst_with_trailing_garbage_keeps_whole_records(pair: tuple[HilBus, HilBus]) -> None:
    """A datagram of records plus a torn one: the whole records arrive, the rest is counted."""
    _a, b = pair
    rec = HEADER.pack(0.0, 0x12, 0, 2, 2) + b"\x01\x02"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as raw:
        raw.sendto(rec + rec + rec[:5], os.fspath(b.path))
    got = recv_n(b, 2)
    assert [bytes(m.data) for m in got] == [b"\x01\x02", b"\x01\x02"]
    assert b.recv(timeout=0) is None
    assert b.malformed_records == 1


def test_bursters_in_one_thread_each_do_not_deadlock(pair: tuple[HilBus, HilBus]) -> None:
    """Two members that each send a long burst before reading both finish."""
    results: dict[str, list[int]] = {}

    def burst_then_read(me: HilBus, tag: str) -> None:
        for i in range(QUEUE_OVERFILL_N):
            me.send(can.Message(arbitration_id=i, data=b"x"), timeout=DEADLINE_S)
        results[tag] = [m.arbitration_id for m in recv_n(me, QUEUE_OVERFILL_N)]

    threads = [
        threading.Thread(target=burst_then_read, args=(bus, tag), daemon=True)
        for bus, tag in zip(pair, "ab", strict=True)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join(DEADLINE_S)
    assert results == {"a": list(range(QUEUE_OVERFILL_N)), "b": list(range(QUEUE_OVERFILL_N))}


def test_receive_own_messages(channel: str) -> None:
    """With receive_own_messages a sent frame also arrives locally (is_rx False)."""
    with HilBus(channel, receive_own_messages=True) as a, HilBus(channel) as b:
        a.send(can.Message(arbitration_id=0x42, data=b"own"))
        mine = recv_n(a, 1)[0]
        assert (mine.arbitration_id, bytes(mine.data), mine.is_rx) == (0x42, b"own", False)
        theirs = recv_n(b, 1)[0]
        assert theirs.is_rx
        b.send(can.Message(arbitration_id=0x43))
        assert recv_n(a, 1)[0].arbitration_id == 0x43
        assert b.recv(timeout=0) is None  # b does not receive its own


def test_receive_own_messages_beyond_queue_size(channel: str) -> None:
    """Own frames beyond the socket's queue are kept, in order, without blocking."""
    with HilBus(channel, receive_own_messages=True) as a:
        for i in range(QUEUE_OVERFILL_N):
            a.send(can.Message(arbitration_id=i))
        r, _, _ = select.select([a.fileno()], [], [], 0)
        assert r, "fileno() not readable while own frames wait"
        got = recv_n(a, QUEUE_OVERFILL_N)
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


def test_filters(channel: str) -> None:
    """python-can software filters apply."""
    with (
        HilBus(channel) as a,
        HilBus(channel, can_filters=[{"can_id": 0x10, "can_mask": 0x7F0, "extended": False}]) as b,
    ):
        for ident in (0x20, 0x13, 0x21, 0x1F):
            a.send(can.Message(arbitration_id=ident, is_extended_id=False))
        assert [m.arbitration_id for m in recv_n(b, 2)] == [0x13, 0x1F]
        assert b.recv(timeout=0) is None


def test_notifier_and_select_use_fileno(pair: tuple[HilBus, HilBus]) -> None:
    """fileno() turns readable on a frame, and can.Notifier delivers it."""
    a, b = pair
    a.send(can.Message(arbitration_id=5))
    r, _, _ = select.select([b.fileno()], [], [], DEADLINE_S)
    assert r == [b.fileno()]
    assert recv_n(b, 1)[0].arbitration_id == 5
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
    m = recv_n(b, 1)[0]
    tx = tx_timestamp_of(m)
    assert tx is not None and tx <= m.timestamp
    for c in (copy.copy(m), copy.deepcopy(m)):
        assert tx_timestamp_of(c) == tx and frame_key(c) == frame_key(m)
    assert tx_timestamp_of(can.Message()) is None


def test_malformed_datagram_is_dropped_and_counted(pair: tuple[HilBus, HilBus]) -> None:
    """A datagram that is not a valid record is counted and skipped, never raised."""
    a, b = pair
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as raw:
        raw.sendto(b"junk", os.fspath(b.path))
        raw.sendto(HEADER.pack(0.0, 1, 0, 8, 8) + b"\x00", os.fspath(b.path))
    a.send(can.Message(arbitration_id=9))
    assert recv_n(b, 1)[0].arbitration_id == 9
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
    assert recv_n(a, 1)[0].arbitration_id == 2
    with pytest.raises(BusError):
        a.state = can.BusState.ERROR


READ_LATER_S = 0.2  # how long the frame waits in the queue before it is read


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="kernel stamps are Linux's")
def test_timestamp_is_the_arrival_not_the_read(pair: tuple[HilBus, HilBus]) -> None:
    """A frame read late keeps the kernel's arrival time: latency excludes the reader's delay."""
    a, b = pair
    a.send(can.Message(arbitration_id=0x40, data=b"\x01\x02", is_extended_id=False))
    time.sleep(READ_LATER_S)  # the stimulus: the frame waits unread in b's queue
    read_s = time.time()
    m = b.recv(timeout=DEADLINE_S)
    assert m is not None
    tx_s = tx_timestamp_of(m)
    assert tx_s is not None and tx_s <= m.timestamp < tx_s + READ_LATER_S / 2
    assert read_s - m.timestamp >= READ_LATER_S / 2
