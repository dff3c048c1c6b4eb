"""Tests of :mod:`transport.wire`: hilbus's record format as pure functions (no sockets)."""

from __future__ import annotations

import can
import pytest

from dbc.errors import BusError
from tests.transport.helpers import frame_key, variety
from transport.wire import (
    HEADER,
    decode,
    encode,
    is_burst,
    own_copy,
    split_burst,
)

TX_TIME_S = 1_700_000_000.25
RX_TIME_S = TX_TIME_S + 0.001
CHANNEL = "wire-test"


@pytest.mark.parametrize("msg", variety(), ids=lambda m: f"{m.arbitration_id:x}")
def test_every_kind_of_frame_decodes_to_what_was_encoded(msg: can.Message) -> None:
    """encode then decode gives the frame back, received, with both times and the channel."""
    got = decode(encode(msg, TX_TIME_S), RX_TIME_S, CHANNEL)
    assert got is not None
    assert frame_key(got) == frame_key(msg)
    assert (got.timestamp, got.tx_timestamp, got.channel, got.is_rx) == (
        RX_TIME_S, TX_TIME_S, CHANNEL, True)


def test_own_copy_decodes_as_sent_not_received() -> None:
    """A record marked as our own decodes with is_rx False and is otherwise the same frame."""
    msg = can.Message(arbitration_id=0x123, data=b"\x01\x02")
    got = decode(own_copy(encode(msg, TX_TIME_S)), RX_TIME_S, CHANNEL)
    assert got is not None and not got.is_rx and frame_key(got) == frame_key(msg)


@pytest.mark.parametrize(("is_fd", "n"), [(False, 9), (True, 65)])
def test_a_frame_that_cannot_exist_is_refused(is_fd: bool, n: int) -> None:
    """More than 8 data bytes without FD, or more than 64 with, raise BusError naming them."""
    with pytest.raises(BusError, match=f"{n} data bytes"):
        encode(can.Message(arbitration_id=1, is_fd=is_fd, data=bytes(n)), TX_TIME_S)


@pytest.mark.parametrize(
    "record",
    [b"", b"junk", HEADER.pack(0.0, 1, 0, 8, 8) + b"\x00", HEADER.pack(0.0, 1, 0, 0, 65)],
    ids=["empty", "short", "length-disagrees", "too-long"],
)
def test_malformed_records_decode_to_none(record: bytes) -> None:
    """A record too short, or whose length byte disagrees with its size, is None, no error."""
    assert decode(record, RX_TIME_S, CHANNEL) is None


def test_a_burst_splits_into_its_records_in_order() -> None:
    """Records back to back come apart in order; a single record is not a burst."""
    records = [encode(can.Message(arbitration_id=i, data=bytes(i)), TX_TIME_S) for i in range(4)]
    assert not is_burst(records[0])
    datagram = b"".join(records)
    assert is_burst(datagram)
    assert split_burst(datagram) == (records, False)


def test_a_torn_tail_keeps_the_whole_records_and_is_reported() -> None:
    """Bytes after the last whole record are reported as torn; the records before are kept."""
    record = encode(can.Message(arbitration_id=7, data=b"\x01\x02"), TX_TIME_S)
    assert split_burst(record + record + record[:5]) == ([record, record], True)
