"""End-to-end protection of every frame: CRC-8 and alive counter, AUTOSAR E2E profile 1 style.

Layout (fixed for every message of ``thruster_hil.dbc``): byte 0 holds the CRC, the low
nibble of byte 1 holds the alive counter (0..14, +1 per transmission, 15 is never sent).
The CRC is CRC-8/SAE-J1850 (polynomial 0x1D, initial value 0xFF, final XOR 0xFF; check
value 0x4B over the ASCII bytes ``123456789``) computed over the message's data ID (low
byte, then high byte: profile 1 "both" mode) followed by payload bytes 1..DLC-1.

Pure functions: bytes in, ints/bytes out; no state.
"""

from __future__ import annotations

CRC8_POLY = 0x1D
CRC8_INIT = 0xFF
CRC8_XOR_OUT = 0xFF
COUNTER_MODULUS = 15  # alive counter runs 0..14 (E2E profile 1)
CRC_BYTE = 0
COUNTER_BYTE = 1
COUNTER_MASK = 0x0F


def _make_table(poly: int) -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ poly) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return tuple(table)


_TABLE = _make_table(CRC8_POLY)


def crc8_sae_j1850(data: bytes | bytearray, init: int = CRC8_INIT) -> int:
    """CRC-8/SAE-J1850 of ``data`` (poly 0x1D, init 0xFF, xor-out 0xFF)."""
    crc = init
    for b in data:
        crc = _TABLE[crc ^ b]
    return crc ^ CRC8_XOR_OUT


def frame_crc(data_id: int, payload: bytes | bytearray) -> int:
    """CRC of a frame: over the data ID (low, high byte) and payload bytes 1..end.

    The same as ``crc8_sae_j1850(bytes((lo, hi)) + payload[1:])``, without building it.
    """
    t = _TABLE
    crc = t[t[CRC8_INIT ^ (data_id & 0xFF)] ^ ((data_id >> 8) & 0xFF)]
    for b in payload[1:]:
        crc = t[crc ^ b]
    return crc ^ CRC8_XOR_OUT


def protect(data_id: int, payload: bytearray, counter: int) -> bytearray:
    """Write ``counter`` and the CRC into ``payload`` in place and return it."""
    payload[COUNTER_BYTE] = (payload[COUNTER_BYTE] & 0xF0) | (counter & COUNTER_MASK)
    payload[CRC_BYTE] = frame_crc(data_id, payload)
    return payload


def crc_ok(data_id: int, payload: bytes | bytearray) -> bool:
    """True if the CRC byte of ``payload`` matches its content."""
    return len(payload) > COUNTER_BYTE and payload[CRC_BYTE] == frame_crc(data_id, payload)


def counter_of(payload: bytes | bytearray) -> int:
    """The alive counter carried by ``payload``."""
    return payload[COUNTER_BYTE] & COUNTER_MASK


def counter_delta(previous: int, current: int) -> int:
    """Steps from ``previous`` to ``current`` modulo the counter range (0 = repeated)."""
    return (current - previous) % COUNTER_MODULUS
