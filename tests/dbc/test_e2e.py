"""Known answers and invariants of the end-to-end protection (CRC-8 and alive counter)."""

from __future__ import annotations

import random

from dbc import e2e

CRC8_SAE_J1850_CHECK = 0x4B  # catalogue check value of CRC-8/SAE-J1850 over b"123456789"
RANDOM_FRAMES = 2000


def test_crc8_catalogue_check_value() -> None:
    """CRC-8/SAE-J1850 of '123456789' is the catalogue's 0x4B."""
    assert e2e.crc8_sae_j1850(b"123456789") == CRC8_SAE_J1850_CHECK


def test_crc8_known_answers_from_autosar_spec() -> None:
    """AUTOSAR SWS CRC Library examples for the 8-bit SAE J1850 CRC."""
    assert e2e.crc8_sae_j1850(bytes([0x00, 0x00, 0x00, 0x00])) == 0x59
    assert e2e.crc8_sae_j1850(bytes([0xF2, 0x01, 0x83])) == 0x37
    assert e2e.crc8_sae_j1850(bytes([0x0F, 0xAA, 0x00, 0x55])) == 0x79
    assert e2e.crc8_sae_j1850(bytes([0xFF, 0xFF, 0xFF, 0xFF])) == 0x74


def test_protect_then_check_round_trip() -> None:
    """A protected payload passes its check and carries its counter."""
    rng = random.Random(1)
    for _ in range(RANDOM_FRAMES):
        payload = bytearray(rng.randbytes(8))
        counter = rng.randrange(e2e.COUNTER_MODULUS)
        did = rng.randrange(1 << 16)
        e2e.protect(did, payload, counter)
        assert e2e.crc_ok(did, payload)
        assert e2e.counter_of(payload) == counter


def test_every_single_bit_flip_is_detected() -> None:
    """Any one flipped bit in bytes 0..7 fails the CRC."""
    payload = e2e.protect(0x1040, bytearray(b"\x00\x00\x12\x34\x56\x78\x9a\xbc"), 7)
    for bit in range(64):
        bad = bytearray(payload)
        bad[bit // 8] ^= 1 << (bit % 8)
        assert not e2e.crc_ok(0x1040, bad), bit


def test_data_id_is_covered_by_the_crc() -> None:
    """The same payload under another data ID fails: frames cannot be confused."""
    payload = e2e.protect(0x1040, bytearray(8), 3)
    assert not e2e.crc_ok(0x1041, payload)


def test_counter_delta_wraps_at_15() -> None:
    """Counter steps are taken modulo 15 (0..14), 0 meaning repeated."""
    assert e2e.counter_delta(14, 0) == 1
    assert e2e.counter_delta(3, 3) == 0
    assert e2e.counter_delta(13, 2) == 4


def test_frame_crc_is_the_crc_over_data_id_then_payload_tail() -> None:
    """frame_crc(id, p) == CRC-8 over (id low, id high, p[1:]) on random frames."""
    rng = random.Random(2)
    for _ in range(RANDOM_FRAMES):
        payload = rng.randbytes(rng.randrange(1, 65))
        did = rng.randrange(1 << 16)
        expected = e2e.crc8_sae_j1850(bytes((did & 0xFF, did >> 8)) + payload[1:])
        assert e2e.frame_crc(did, payload) == expected
        assert e2e.frame_crc(did, bytearray(payload)) == expected
