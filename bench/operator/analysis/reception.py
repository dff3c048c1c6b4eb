"""Reception times of the bench's realtime frames, from the flight software's receive log.

What
----
In a realtime run the bench records when it sent each frame (``t_ready_s`` in
``frames.csv``) but cannot know when the flight software received it (``t_rx_s`` is nan).
The flight software can say: ours logs the receive timestamp, ID and alive counter of every
frame it reads into the run folder's ``fsw_rx.csv`` (``flight_sw/rx_log.py``; other flight
software may write the same file through the ``{rx_log}`` placeholder of ``--fsw-cmd``).
:func:`fill_reception` pairs those rows with the bench's transmissions and fills in their
``t_rx_s``, so the latency, periods and jitter of bench frames are measured at the receiver
as they are for the flight software's frames.

Inputs and outputs
------------------
``fsw_rx.csv``: header ``t_rx_wall_s,id,counter``; ``t_rx_wall_s`` in seconds of the host's
wall clock (``time.time()``), converted to the run's time base (seconds since the bench's
realtime t = 0) with summary.json's ``wall_clock_origin_s``. Out: a
``t_rx_s`` column equal to the input but for the paired bench rows (known ones are kept).

Pairing
-------
Per CAN ID, transmissions and receptions are each in order (one sender, FIFO transport).
A reception pairs with the first unpaired transmission of its ID among the next
``COUNTER_MODULUS`` ones (all alive counters differ there) that carries the same alive
counter and was sent no later than ``PAIRING_TOLERANCE_S`` after the reception. So up to
14 lost frames in a row are skipped, and a reception without a partner (a frame of another
sender under the same ID, or one sent before the run's origin) is left out.

Assumptions
-----------
Both processes run on one host: the bench's monotonic run clock and the wall clock keep
the offset they had at ``wall_clock_origin_s`` for the length of a run (an NTP step during
a run would show as a latency offset). No clock is read here.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from dbc.e2e import COUNTER_MODULUS

RX_LOG_FILE = "fsw_rx.csv"
RX_LOG_COLUMNS = ("t_rx_wall_s", "id", "counter")
PAIRING_TOLERANCE_S = 1e-3  # a reception may carry a timestamp this much before its sending


@dataclasses.dataclass(frozen=True, eq=False)
class ReceiveLog:
    """A receiver's log: per row the reception time [s, run time base], CAN ID, alive counter."""

    t_rx_s: np.ndarray
    can_id: np.ndarray
    counter: np.ndarray


def receive_log(cols: Mapping[str, np.ndarray], wall_clock_origin_s: float) -> ReceiveLog:
    """The columns of ``fsw_rx.csv`` (as read), times put on the run's time base."""
    return ReceiveLog(
        cols["t_rx_wall_s"] - wall_clock_origin_s,
        cols["id"].astype(np.int64),
        cols["counter"].astype(np.int64),
    )


def fill_reception(
    t_ready_s: np.ndarray,
    t_rx_s: np.ndarray,
    can_id: np.ndarray,
    tx: np.ndarray,
    counter: np.ndarray,
    log: ReceiveLog,
) -> np.ndarray:
    """``t_rx_s`` of ``frames.csv``'s columns with the bench's transmissions filled from ``log``.

    Pure: returns a new array; rows already known, and rows the bench received, are kept.
    """
    t_rx = np.array(t_rx_s, dtype=float)
    rows_of: dict[int, list[int]] = {}
    for row in np.flatnonzero(np.asarray(tx) == 1).tolist():
        rows_of.setdefault(int(can_id[row]), []).append(row)
    next_of = dict.fromkeys(rows_of, 0)
    counters = np.asarray(counter).tolist()
    ready = np.asarray(t_ready_s, dtype=float).tolist()
    for t_s, rx_id, rx_counter in zip(
        log.t_rx_s.tolist(), log.can_id.tolist(), log.counter.tolist(), strict=True
    ):
        rows = rows_of.get(rx_id)
        if rows is None:
            continue
        first = next_of[rx_id]
        for k in range(first, min(first + COUNTER_MODULUS, len(rows))):
            row = rows[k]
            if counters[row] == rx_counter and ready[row] <= t_s + PAIRING_TOLERANCE_S:
                if np.isnan(t_rx[row]):
                    t_rx[row] = t_s
                next_of[rx_id] = k + 1
                break
    return t_rx
