"""Bus timing model: bit-exact frame length, priority arbitration, errors, bus-off, load.

What. vcan and the portable bus deliver frames instantly; a real CAN bus does not. This
package gives lockstep runs a physical layer: a frame handed to the bus at ``ready_ns``
starts when the bus is idle and it wins arbitration (lowest ID among the frames waiting),
occupies the wire for its exact length in bits / bitrate, and its
:class:`~bench.wire.timing.arbiter.Delivery` reports when it was on the wire. On top of
that: CAN FD frames (two bitrates), link-level errors (a corrupted attempt costs its bits,
an error frame, and a re-arbitration), bus-off (a node's frames are held for the recovery
time), and bus load per window.

Units. Lengths in bits, bitrates in bit/s, times in integer nanoseconds (``*_ns``); a
wire time is rounded up to the next ns once per frame (or per failed attempt).

Modules (pure functions plus one small stateful ``BusArbiter`` with time as an argument):

- :mod:`~bench.wire.timing.classic`: classic CAN frame length (field sizes, CRC-15, bit
  stuffing, worst case) and :func:`~bench.wire.timing.classic.wire_time_ns`;
- :mod:`~bench.wire.timing.fd`: CAN FD frame length split by bitrate (``FdBits``) and its
  wire time;
- :mod:`~bench.wire.timing.arbiter`: errors and bus-off, ``Delivery`` and ``BusArbiter``;
- :mod:`~bench.wire.timing.load`: bus load per window from deliveries.

The names below are re-exported, so ``from bench.wire.timing import frame_bits`` keeps
working; the bench's own modules import from the module that defines a name.

Sources: ISO 11898-1:2015 (frame layout, stuffing, error frames, fault confinement);
Davis, Burns, Bril and Lukkien, "Controller Area Network (CAN) schedulability analysis:
Refuted, revisited and revised", Real-Time Systems 35 (2007) (worst-case frame lengths);
Linux ``include/linux/can/length.h`` (kernel >= 6.5, ``can_frame_bits()``: its figures are
the known answers of the tests; see the note in :mod:`~bench.wire.timing.fd` for what it
counts differently).
"""

from __future__ import annotations

from bench.wire.timing.arbiter import (
    BUS_OFF_RECOVERY_BITS,
    ERROR_FRAME_BITS,
    BusArbiter,
    Delivery,
    bus_off_recovery_ns,
    failed_attempt_bits,
)
from bench.wire.timing.classic import (
    CAN_MAX_DATA_BYTES,
    INTERMISSION_BITS,
    NS_PER_S,
    crc15,
    frame_bits,
    frame_bits_worst_case,
    frame_bitstream,
    stuff_count,
    wire_time_ns,
)
from bench.wire.timing.fd import (
    CANFD_MAX_DATA_BYTES,
    FD_DATA_LENGTHS,
    FdBits,
    fd_dlc2len,
    fd_len2dlc,
    frame_bits_fd,
    frame_bits_fd_worst_case,
    wire_time_fd_ns,
)
from bench.wire.timing.load import (
    busy_ns_per_window,
    load_per_window,
    load_per_window_by_node,
    mean_peak_load,
)

__all__ = [
    "BUS_OFF_RECOVERY_BITS",
    "CANFD_MAX_DATA_BYTES",
    "CAN_MAX_DATA_BYTES",
    "ERROR_FRAME_BITS",
    "FD_DATA_LENGTHS",
    "INTERMISSION_BITS",
    "NS_PER_S",
    "BusArbiter",
    "Delivery",
    "FdBits",
    "bus_off_recovery_ns",
    "busy_ns_per_window",
    "crc15",
    "failed_attempt_bits",
    "fd_dlc2len",
    "fd_len2dlc",
    "frame_bits",
    "frame_bits_fd",
    "frame_bits_fd_worst_case",
    "frame_bits_worst_case",
    "frame_bitstream",
    "load_per_window",
    "load_per_window_by_node",
    "mean_peak_load",
    "stuff_count",
    "wire_time_fd_ns",
    "wire_time_ns",
]
