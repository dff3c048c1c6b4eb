"""Classic CAN frame length vs an independent stuffer; CRC-15."""

from __future__ import annotations

import random

from bench.wire.timing.classic import (
    crc15,
    frame_bits,
    frame_bits_worst_case,
    frame_bitstream,
    stuff_count,
)

N_RANDOM = 10_000  # the issue asks for 10 000 random frames
SEED = 5
TAIL_BITS = 13  # CRC delimiter, ACK slot + delimiter, EOF 7, intermission 3


def _reference_stuffed_length(bits: list[int]) -> int:
    """Independent stuffer: emit bits, inserting the complement after 5 equal bits."""
    out: list[int] = []
    for b in bits:
        out.append(b)
        if len(out) >= 5 and len(set(out[-5:])) == 1:
            out.append(1 - out[-1])
    return len(out)


def test_frame_length_matches_independent_stuffer() -> None:
    """frame_bits == reference stuffing of the same bit stream, both ID lengths, all DLCs."""
    rng = random.Random(SEED)
    for _ in range(N_RANDOM):
        ext = rng.random() < 0.5
        can_id = rng.randrange(1 << (29 if ext else 11))
        data = rng.randbytes(rng.randrange(9))
        ref = _reference_stuffed_length(frame_bitstream(can_id, data, ext)) + TAIL_BITS
        assert frame_bits(can_id, data, ext) == ref
        assert frame_bits(can_id, data, ext) <= frame_bits_worst_case(len(data), ext)


def test_payload_changes_length() -> None:
    """An all-zero payload needs more stuff bits than an alternating 0x55 payload."""
    zeros, alt = frame_bits(0x123, bytes(8)), frame_bits(0x123, bytes([0x55] * 8))
    assert zeros > alt
    assert (
        alt
        == len(frame_bitstream(0x123, bytes([0x55] * 8)))
        + stuff_count(frame_bitstream(0x123, bytes([0x55] * 8)))
        + TAIL_BITS
    )


def test_crc15_detects_single_bit_errors() -> None:
    """CRC-15 changes for every single flipped bit of a stream."""
    bits = frame_bitstream(0x2A5, b"\x01\x02\x03")[:-15]
    ref = crc15(bits)
    for i in range(len(bits)):
        flipped = bits.copy()
        flipped[i] ^= 1
        assert crc15(flipped) != ref
