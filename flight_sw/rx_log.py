"""The flight software's receive log: when each frame reached it (realtime timing).

In realtime the bench knows when it sent a sensor frame but not when the flight software
received it; this log closes that gap. One CSV row per frame read from the bus, checked or
not: ``t_rx_wall_s`` (the interface's receive timestamp, ``msg.timestamp``: the kernel's on
SocketCAN, the reader's :func:`time.time` at receipt on the portable bus; seconds of the
host's wall clock, microsecond resolution), ``id`` (arbitration ID) and ``counter`` (the
E2E alive counter, ``-1`` for a frame too short to carry one). The bench's timing analysis
pairs the rows with its own transmissions by ID and alive counter
(:mod:`bench.operator.analysis.reception`); the file is the only link, so neither side imports the
other.

Flushed by the caller once per control cycle, so a crash loses at most one cycle.
No clock is read here: the timestamp comes with the frame.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO

import can

from dbc.e2e import COUNTER_BYTE, COUNTER_MASK

RX_LOG_COLUMNS = ("t_rx_wall_s", "id", "counter")
NO_COUNTER = -1


class ReceiveLog:
    """Appends one row per received frame to a CSV file."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file: IO[str] = open(path, "w", encoding="utf-8")  # noqa: SIM115 - kept open
        self._file.write(",".join(RX_LOG_COLUMNS) + "\n")
        self.rows = 0

    def row(self, msg: can.Message) -> None:
        """Log ``msg``'s receive timestamp, ID and alive counter."""
        data = msg.data
        counter = data[COUNTER_BYTE] & COUNTER_MASK if len(data) > COUNTER_BYTE else NO_COUNTER
        self._file.write(f"{msg.timestamp:.6f},{msg.arbitration_id},{counter}\n")
        self.rows += 1

    def flush(self) -> None:
        """Flush the rows written so far to disk."""
        self._file.flush()

    def close(self) -> None:
        """Close the file."""
        self._file.close()
