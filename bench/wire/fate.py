"""The fate of one frame under the active bus faults: dropped, delayed, corrupted, doubled.

In: the active faults (:class:`~bench.station.faults.FaultSpec`, in the order they
started), the frame's message name and sender node, the wire's random generator. Out: a
:class:`Fate`: drop it, deliver it ``delay_ns`` late, flip one payload bit (bytes 1..7:
after the sender's E2E protection, so the receiver's CRC must catch it), deliver it twice
(the copy repeats the alive counter), or fail ``failed_attempts`` times on the wire first
(link errors: error frame, retransmission). :func:`flip` applies a corruption.

Determinism: random numbers are drawn only for faults that match the frame, in the order
the faults started, so the same seed gives the same fates (lockstep runs are
bit-identical). Pure apart from the generator it is handed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import can

from bench.station.faults import FaultSpec
from dbc.faults import CORRUPT, DELAY, DROP, DUPLICATE, FRAME_KINDS

NS_PER_S = 1e9


@dataclass(frozen=True)
class Fate:
    """What the active faults do to one frame."""

    drop: bool = False
    delay_ns: int = 0
    corrupt_bit: int | None = None  # bit index in bytes 1..7 to flip
    duplicate: bool = False
    failed_attempts: int = 0


NO_FATE = Fate()
PAYLOAD_BITS = 56  # bytes 1..7: the CRC byte itself is not flipped, the CRC must catch it


def frame_fate(active: list[FaultSpec], name: str, sender: str, rng: Any) -> Fate:
    """Fate of one frame of ``name`` from ``sender`` under the ``active`` faults.

    Draws from ``rng`` only for matching faults, in the order they were started, so the
    same seed gives the same fates (lockstep determinism).
    """
    drop = dup = False
    delay = fails = 0
    bit = None
    for f in active:
        if f.kind not in FRAME_KINDS or not (f.message == name or f.node == sender):
            continue
        if rng.random() >= f.params["probability"]:
            continue
        if f.kind == DROP:
            drop = True
        elif f.kind == DELAY:
            delay += round(f.params["delay_s"] * NS_PER_S)
        elif f.kind == CORRUPT:
            bit = int(rng.integers(PAYLOAD_BITS))
        elif f.kind == DUPLICATE:
            dup = True
        else:
            fails += 1
    if not (drop or dup or delay or fails or bit is not None):
        return NO_FATE
    return Fate(drop, delay, bit, dup, fails)


def flip(msg: can.Message, bit: int) -> None:
    """Flip payload bit ``bit`` (0..55) of bytes 1..7 of ``msg`` in place."""
    data = bytearray(msg.data)
    data[1 + bit // 8] ^= 1 << (bit % 8)
    msg.data = data
