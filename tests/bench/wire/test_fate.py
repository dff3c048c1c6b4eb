"""Bus faults' fate of a frame: probability, targeting, and the corruption of one bit."""

from __future__ import annotations

import can
import numpy as np

from bench.station.faults import FaultSpec, parse_faults
from bench.wire.fate import NO_FATE, PAYLOAD_BITS, flip, frame_fate
from dbc.schema import Table

MESSAGES = frozenset({"IMU_RATE", "THR_CMD_0"})
NODES = frozenset({"BENCH", "FSW"})
N_FATES = 20_000
P = 0.3
SIGMAS = 5.0


def _parse(entry: dict[str, object]) -> FaultSpec:
    return parse_faults([Table(entry, "f.toml", "faults[0]")], 60.0, 8, MESSAGES, NODES)[0]


def test_frame_fate_probability_and_targeting() -> None:
    """A drop at p hits about p of matching frames and never a frame of another message."""
    spec = _parse({"t_s": 0.0, "kind": "drop", "message": "IMU_RATE", "probability": P})
    rng = np.random.default_rng(1)
    hits = sum(frame_fate([spec], "IMU_RATE", "BENCH", rng).drop for _ in range(N_FATES))
    sigma = (N_FATES * P * (1 - P)) ** 0.5
    assert abs(hits - P * N_FATES) <= SIGMAS * sigma
    assert frame_fate([spec], "THR_CMD_0", "FSW", rng) is NO_FATE


def test_flip_changes_exactly_one_payload_bit_and_never_the_crc_byte() -> None:
    """Every corruptible bit index flips one bit of bytes 1..7 and leaves byte 0 alone."""
    data = bytes(range(8))
    for bit in range(PAYLOAD_BITS):
        msg = can.Message(arbitration_id=0x40, is_extended_id=False, data=data)
        flip(msg, bit)
        diff = [a ^ b for a, b in zip(data, bytes(msg.data), strict=True)]
        assert diff[0] == 0
        assert sum(bin(x).count("1") for x in diff) == 1
