"""Live timing of a running CAN bus: listen for a while, then measure as for a run folder.

What: opens any python-can bus (``socketcan:vcan0``, ``hilbus:<channel>``,
``pcan:PCAN_USBBUS1?bitrate=1000000`` ...), waits for the first frame, records every
frame for ``duration_s`` seconds and turns the capture into a
:class:`~bench.operator.analysis.tables.FrameTable`, so
:class:`~bench.operator.analysis.timing.RunTiming`
measures per-ID count, period mean and jitter, missed cycles, cycle-time violations
against the DBC and bus load exactly as for a run folder (mode ``live``).

Times: ``t_rx`` is the interface's receive timestamp (``msg.timestamp``: the kernel's on
SocketCAN, the receiver's :func:`time.time` on hilbus) minus the first frame's; ``t_ready``
is the sender's transmission time where the interface carries it (hilbus's
``tx_timestamp``, same host and clock), so latency is measured there, ``nan`` elsewhere.
Bus load: each frame's exact stuffed length (:func:`bench.wire.timing.classic.frame_bits`) at the
DBC's ``Baudrate`` (or a given bitrate), ending at its receive time: an estimate, since a
listener does not see the wire itself (error frames are counted, not timed).

Assumptions: classic CAN (FD frames are counted and left out). Alive counters are read
only from IDs of the DBC. This module reads the clock, to stop listening; the
measurements themselves are the pure functions of :mod:`bench.operator.analysis.measures`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import can

from bench.operator.analysis.defaults import DEFAULT_FIRST_FRAME_TIMEOUT_S
from bench.operator.analysis.records import TimingOptions
from bench.operator.analysis.tables import FrameTable
from bench.operator.analysis.timing import RunTiming, dbc_bitrate_bps
from bench.wire.timing.classic import frame_bits
from dbc.database import load_database
from dbc.e2e import COUNTER_BYTE, COUNTER_MASK
from dbc.errors import ConfigError, RunError
from transport.hilbus import tx_timestamp_of
from transport.spec import open_bus

LIVE_SOURCE = "timing --live"
NAN = float("nan")
NO_COUNTER = -1


@dataclass(frozen=True)
class LiveOptions:
    """How long to listen: ``duration_s`` from the first frame, which must come within
    ``first_frame_timeout_s``; ``bitrate_bps`` for the load estimate (None: the DBC's)."""

    duration_s: float
    first_frame_timeout_s: float = DEFAULT_FIRST_FRAME_TIMEOUT_S
    bitrate_bps: int | None = None

    def __post_init__(self) -> None:
        for key in ("duration_s", "first_frame_timeout_s"):
            v = getattr(self, key)
            if (
                isinstance(v, bool)
                or not isinstance(v, (int, float))
                or not math.isfinite(v)
                or v <= 0
            ):
                raise ConfigError(LIVE_SOURCE, key, v, "a finite number of seconds > 0")
        b = self.bitrate_bps
        if b is not None and (isinstance(b, bool) or not isinstance(b, int) or b <= 0):
            raise ConfigError(LIVE_SOURCE, "bitrate_bps", b, "None or a positive integer")


@dataclass(frozen=True)
class Capture:
    """What a listener heard: the frames, and what it could not time."""

    frames: FrameTable
    error_frames: int
    fd_frames: int


def frames_from_messages(messages: Sequence[can.Message], db: Any) -> Capture:
    """Received python-can messages -> a :class:`FrameTable` (times relative to the first).

    Error frames and CAN FD frames are counted and left out.
    """
    known = {m.frame_id for m in db.messages}
    cols: dict[str, list[float]] = {
        k: [] for k in ("t_ready_s", "t_start_s", "t_rx_s", "id", "dlc", "bits", "tx", "counter")
    }
    errors = fd = 0
    t0: float | None = None
    for msg in messages:
        if msg.is_error_frame:
            errors += 1
            continue
        if msg.is_fd:
            fd += 1
            continue
        if t0 is None:
            t0 = msg.timestamp
        data = bytes(msg.data)
        tx = tx_timestamp_of(msg)
        counter = (
            data[COUNTER_BYTE] & COUNTER_MASK
            if msg.arbitration_id in known and len(data) > COUNTER_BYTE
            else NO_COUNTER
        )
        cols["t_ready_s"].append(NAN if tx is None else tx - t0)
        cols["t_start_s"].append(NAN)
        cols["t_rx_s"].append(msg.timestamp - t0)
        cols["id"].append(msg.arbitration_id)
        cols["dlc"].append(msg.dlc)
        cols["bits"].append(
            frame_bits(msg.arbitration_id, data, msg.is_extended_id, msg.is_remote_frame)
        )
        cols["tx"].append(0)
        cols["counter"].append(counter)
    return Capture(FrameTable.from_columns(cols), errors, fd)


def capture(
    bus: can.BusABC,
    opts: LiveOptions,
    db: Any,
    clock: Callable[[], float] = time.monotonic,
) -> Capture:
    """Listen on ``bus``: wait for a first frame, then record for ``opts.duration_s``.

    Raises :class:`RunError` if nothing arrives within ``opts.first_frame_timeout_s``.
    """
    first_deadline = clock() + opts.first_frame_timeout_s
    first: can.Message | None = None
    while first is None:
        remaining = first_deadline - clock()
        if remaining <= 0:
            raise RunError(
                f"no frame on the bus within {opts.first_frame_timeout_s} s "
                "(is a bench or a device sending?)"
            )
        first = bus.recv(timeout=remaining)
    msgs = [first]
    end = clock() + opts.duration_s
    while (remaining := end - clock()) > 0:
        msg = bus.recv(timeout=remaining)
        if msg is not None:
            msgs.append(msg)
    return frames_from_messages(msgs, db)


def live_timing(
    bus_spec: str,
    opts: LiveOptions,
    options: TimingOptions | None = None,
    db: Any = None,
    listening: Callable[[], None] | None = None,
) -> tuple[RunTiming, Capture]:
    """Open ``bus_spec``, capture, and measure; ``listening`` is called once the bus is open."""
    db = load_database() if db is None else db
    bitrate = opts.bitrate_bps or dbc_bitrate_bps(db)
    bus = open_bus(bus_spec)
    try:
        if listening is not None:
            listening()
        cap = capture(bus, opts, db)
    finally:
        bus.shutdown()
    return RunTiming(
        cap.frames, None, mode="live", bitrate_bps=bitrate, db=db, options=options
    ), cap
