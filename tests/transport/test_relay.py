"""The relay: a bus read by a process of its own keeps every frame for a reader that pauses."""

from __future__ import annotations

import time

import can
import pytest

from dbc.errors import BusInitError
from tests.transport.helpers import QUEUE_OVERFILL_N, frame_key, recv_n, variety
from transport.hilbus import HilBus
from transport.relay import RelayBus, pack, unpack

REALTIME_STALL_S = 0.010  # transport.spec's realtime member_stall_s


def test_record_round_trips_every_kind_of_frame() -> None:
    """pack/unpack keep ID, flags, DLC, data and the bus timestamp; the receive time too."""
    for k, msg in enumerate(variety()):
        msg.timestamp = 12.5 + k
        got = unpack(pack(msg, 1000 + k), 0)
        assert got is not None
        back, rx_ns, end = got
        assert frame_key(back) == frame_key(msg) and back.timestamp == msg.timestamp
        assert rx_ns == 1000 + k and end == len(pack(msg, 0))


def test_a_cut_record_waits_for_the_rest() -> None:
    """Part of a record is not a frame yet."""
    record = pack(can.Message(arbitration_id=0x123, data=b"\x01\x02"), 7)
    assert unpack(record[:-1], 0) is None and unpack(record[:5], 0) is None


def test_relay_delivers_frames_in_order_with_receive_times(channel: str) -> None:
    """Frames sent on the channel come out of the relay in order, unchanged, each with a
    non-decreasing receive time on this machine's monotonic clock."""
    frames = variety()
    with HilBus(channel) as sender:
        relay = RelayBus(spec=f"hilbus:{channel}")
        try:
            t0 = time.monotonic_ns()
            for m in frames:
                sender.send(m)
            got, stamps = [], []
            for _ in frames:
                got += recv_n(relay, 1)
                stamps.append(relay.last_rx_monotonic_ns)
        finally:
            relay.shutdown()
    assert [frame_key(m) for m in got] == [frame_key(m) for m in frames]
    assert t0 <= stamps[0] and stamps == sorted(stamps) and stamps[-1] <= time.monotonic_ns()


def test_a_reader_that_pauses_loses_nothing_through_the_relay(channel: str) -> None:
    """A sender with the realtime stall limit overruns a member that does not read, but not
    the relay: the frames wait in its pipe until the reader comes back."""
    with HilBus(channel, member_stall_s=REALTIME_STALL_S) as sender:
        relay = RelayBus(spec=f"hilbus:{channel}")
        idle = HilBus(channel)  # a member that never reads
        try:
            for k in range(QUEUE_OVERFILL_N):
                sender.send(can.Message(arbitration_id=0x100, data=k.to_bytes(2, "little")))
            got = recv_n(relay, QUEUE_OVERFILL_N)  # read only now, after every send
        finally:
            relay.shutdown()
            idle.shutdown()
        drops = sender.overrun_drops_by_pid
    assert [int.from_bytes(m.data, "little") for m in got] == list(range(QUEUE_OVERFILL_N))
    assert drops.get(relay._proc.pid, 0) == 0
    assert sum(drops.values()) > 0  # the idle member was overrun: the test can fail


def test_a_bus_that_cannot_be_opened_is_named(runtime) -> None:
    """A spec the relay cannot open raises BusInitError naming it, with the relay's reason."""
    with pytest.raises(BusInitError, match="nosuchinterface:x"):
        RelayBus(spec="nosuchinterface:x")


def test_relay_is_read_only_and_ends_on_shutdown(channel: str) -> None:
    """Sending is refused; after shutdown the relay process has ended."""
    relay = RelayBus(spec=f"hilbus:{channel}")
    with pytest.raises(can.CanOperationError, match="read-only"):
        relay.send(can.Message(arbitration_id=1))
    relay.shutdown()
    assert relay._proc.returncode is not None
