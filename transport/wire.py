"""hilbus's wire record: CAN frames <-> bytes, as pure functions (no sockets, no state).

Record: a little-endian header :data:`HEADER` (``<dIBBB``: transmission time [s] from the
sender's :func:`time.time`, arbitration ID, flags, DLC, data length [bytes]) followed by
0..64 data bytes. Flags: extended ID, remote, error, FD, bit-rate switch, error-state
indicator, and :data:`FLAG_OWN` on records a member delivers to itself.

A datagram carries one record (``HilBus.send``) or, from ``HilBus.send_burst``, up to
:data:`BURST_MAX_RECORDS` records back to back (:func:`split_burst` takes them apart).

Decoded frames are :class:`HilMessage` objects: a :class:`can.Message` whose
``timestamp`` is the receiver's arrival time [s, wall clock] and whose ``tx_timestamp`` is
the sender's transmission time [s, wall clock]; :func:`tx_timestamp_of` reads the latter
from any message. A record that is not valid decodes to None (the receiver counts it);
nothing here raises on received bytes. Encoding a frame that cannot exist (more than 8
data bytes without FD, more than 64 with) raises :class:`~dbc.errors.BusOperationError`
(python-can: the driver rejected a message that was meant to be sent).
"""

from __future__ import annotations

import struct
from typing import Any

import can

from dbc.errors import BusOperationError

#: wire header: tx time (s), arbitration ID, flags, DLC, data length.
HEADER = struct.Struct("<dIBBB")
#: offset of the flags byte in a record (after the tx time and the arbitration ID)
FLAGS_OFFSET = struct.calcsize("<dI")
#: offset of the data-length byte (the header's last)
LENGTH_OFFSET = HEADER.size - 1
DATA_MAX_B = 64
CLASSIC_DATA_MAX_B = 8
RECORD_MAX_B = HEADER.size + DATA_MAX_B
#: records per datagram of a burst (a longer burst goes out as several datagrams)
BURST_MAX_RECORDS = 32
DATAGRAM_MAX_B = BURST_MAX_RECORDS * RECORD_MAX_B
ARBITRATION_ID_MASK = 0xFFFFFFFF
DLC_MASK = 0xFF

FLAG_EXTENDED = 0x01
FLAG_REMOTE = 0x02
FLAG_ERROR = 0x04
FLAG_FD = 0x08
FLAG_BRS = 0x10
FLAG_ESI = 0x20
#: set only in records a member sends to itself (receive_own_messages).
FLAG_OWN = 0x80


class HilMessage(can.Message):
    """A received hilbus frame: a :class:`can.Message` plus the sender's ``tx_timestamp``.

    ``timestamp`` is the receiver's arrival time; ``tx_timestamp`` is the sender's
    :func:`time.time` at transmission (None for messages not from a hilbus).
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


def encode(msg: can.Message, tx_time_s: float) -> bytes:
    """The record of ``msg`` sent at ``tx_time_s``; raises BusOperationError for a frame that
    cannot exist (data longer than 8 bytes without ``is_fd``, or than 64)."""
    data = b"" if msg.is_remote_frame or msg.data is None else bytes(msg.data)
    limit = DATA_MAX_B if msg.is_fd else CLASSIC_DATA_MAX_B
    if len(data) > limit:
        raise BusOperationError(
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
        HEADER.pack(tx_time_s, msg.arbitration_id & ARBITRATION_ID_MASK, flags, dlc & DLC_MASK,
                    len(data))
        + data
    )


def own_copy(record: bytes) -> bytes:
    """``record`` marked as this member's own (decodes with ``is_rx`` False)."""
    return (
        record[:FLAGS_OFFSET]
        + bytes((record[FLAGS_OFFSET] | FLAG_OWN,))
        + record[FLAGS_OFFSET + 1 :]
    )


def is_burst(datagram: bytes) -> bool:
    """True if ``datagram`` holds more bytes than its first record: a burst (or garbage
    behind a record, which :func:`split_burst` tells apart)."""
    return len(datagram) > HEADER.size and len(datagram) > HEADER.size + datagram[LENGTH_OFFSET]


def split_burst(datagram: bytes) -> tuple[list[bytes], bool]:
    """The whole records of a burst datagram, in order, and whether bytes were left over
    that do not make a whole record (a torn tail: the records before it are good)."""
    records = []
    start = 0
    size = len(datagram)
    while start + HEADER.size <= size:
        end = start + HEADER.size + datagram[start + LENGTH_OFFSET]
        if end > size:
            break
        records.append(datagram[start:end])
        start = end
    return records, start != size


def decode(record: bytes, rx_time_s: float, channel: str) -> HilMessage | None:
    """The frame of one record that arrived at ``rx_time_s`` on ``channel``; None if the
    record is malformed (too short, or its length byte disagrees with its size)."""
    if len(record) < HEADER.size:
        return None
    tx_time, arbitration_id, flags, dlc, length = HEADER.unpack_from(record)
    if len(record) != HEADER.size + length or length > DATA_MAX_B:
        return None
    # the receive hot path: can.Message.__init__ with its parameters in their documented
    # order (python-can 4), which costs a quarter of the keyword call through __init__
    msg = HilMessage.__new__(HilMessage)
    can.Message.__init__(
        msg, rx_time_s, arbitration_id, bool(flags & FLAG_EXTENDED), bool(flags & FLAG_REMOTE),
        bool(flags & FLAG_ERROR), channel, dlc, record[HEADER.size :],
        bool(flags & FLAG_FD), not flags & FLAG_OWN, bool(flags & FLAG_BRS),
        bool(flags & FLAG_ESI),
    )
    msg.tx_timestamp = tx_time
    return msg
