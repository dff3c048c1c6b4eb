"""bench.operator.flood: the hostile-input generator's frames, counts and manners on the bus."""

from __future__ import annotations

import uuid

import can

from bench.operator.flood import CAUSES, build_flood, send_flood

N_FRAMES = 400
N_QUEUED = 50
FAST_RATE_HZ = 1e6
SEED = 4


def test_counts_add_up_to_the_frames_built() -> None:
    """Every frame built is counted once, under one receiver and one cause."""
    frames, counts = build_flood(N_FRAMES, SEED)
    assert len(frames) == N_FRAMES
    assert sum(counts[r][c] for r in counts for c in CAUSES) == N_FRAMES


def test_same_seed_same_flood() -> None:
    """The flood is seeded: the same seed gives the same frames."""
    a, _ = build_flood(N_FRAMES, SEED)
    b, _ = build_flood(N_FRAMES, SEED)
    assert [(m.arbitration_id, bytes(m.data), m.is_error_frame) for m in a] == [
        (m.arbitration_id, bytes(m.data), m.is_error_frame) for m in b
    ]


def test_flooder_reads_what_the_bus_delivers_to_it() -> None:
    """Frames queued for the flooder are read while it floods: it never holds the bus up."""
    channel = f"flood-{uuid.uuid4().hex[:8]}"
    with (
        can.Bus(interface="virtual", channel=channel) as flooder,
        can.Bus(interface="virtual", channel=channel) as other,
    ):
        for i in range(N_QUEUED):
            other.send(can.Message(arbitration_id=0x40, is_extended_id=False, data=bytes([i])))
        frames, _ = build_flood(10, SEED)
        send_flood(flooder, frames, FAST_RATE_HZ)
        assert flooder.recv(timeout=0.0) is None
        got = [other.recv(timeout=0.0) for _ in frames]
        assert all(m is not None for m in got)
