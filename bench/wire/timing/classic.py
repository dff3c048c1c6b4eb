"""Classic CAN frame length, bit-exact: field sizes, CRC-15, bit stuffing, wire time.

In: an identifier, the data bytes, the extended and remote flags. Out: the frame's length
on the wire in bits (:func:`frame_bits`, exact; :func:`frame_bits_worst_case`, the bound)
and the time of a number of bits at a bitrate (:func:`wire_time_ns`).

Units. Lengths in bits, bitrates in bit/s, times in integer nanoseconds (``*_ns``); a
wire time is rounded up to the next ns.

Classic CAN frame length (CAN 2.0 / ISO 11898-1:2015 "Classical" frames): SOF,
arbitration field, control field, data, CRC-15 are bit-stuffed (a complemented bit after
five equal bits, stuff bits counting towards the next run; ISO 11898-1:2015 §10.5); CRC
delimiter, ACK slot and delimiter, EOF (7) and the intermission (3) are not. Lengths
include the intermission, so back-to-back frames start one length apart. Worst case
(Davis, Burns, Bril, Lukkien 2007, transmission time C_m): 55 + 10 n bits for 11-bit IDs
and 80 + 10 n for 29-bit IDs, including the intermission.

The field sizes below are shared with :mod:`bench.wire.timing.fd` and
:mod:`bench.wire.timing.arbiter`.

Sources: ISO 11898-1:2015 (frame layout, stuffing); Davis, Burns, Bril and Lukkien,
"Controller Area Network (CAN) schedulability analysis: Refuted, revisited and revised",
Real-Time Systems 35 (2007) (worst-case frame lengths); Linux
``include/linux/can/length.h`` (kernel >= 6.5, ``can_frame_bits()``: its figures are the
known answers of the tests).
"""

from __future__ import annotations

import functools
from typing import Final

NS_PER_S = 1_000_000_000
BITS_PER_BYTE = 8
STUFF_RUN = 5  # equal bits after which a stuff bit is inserted

# -- field sizes, ISO 11898-1:2015 §10.4 (bits) -------------------------------------------
SOF_BITS = 1
BASE_ID_BITS = 11
EXT_ID_BITS = 18  # identifier extension of a 29-bit ID
DLC_BITS = 4
CRC15_BITS: Final = 15
CRC15_POLY = 0x4599
CRC_DELIMITER_BITS = 1
ACK_SLOT_BITS = 1
ACK_DELIMITER_BITS = 1
EOF_BITS = 7
INTERMISSION_BITS = 3
CAN_MAX_DATA_BYTES = 8
FLAG_BITS = 1  # each one-bit field: RTR, SRR, IDE, r0, r1, FDF, res, RRS, BRS, ESI
UNSTUFFED_TAIL_BITS: Final = (  # CRC delimiter, ACK slot + delimiter, EOF, intermission = 13
    CRC_DELIMITER_BITS + ACK_SLOT_BITS + ACK_DELIMITER_BITS + EOF_BITS + INTERMISSION_BITS
)
# bits SOF..DLC ("header", Linux CAN_FRAME_HEADER_*_BITS): SFF = SOF, ID, RTR, IDE, r0, DLC
CAN_HEADER_SFF_BITS = SOF_BITS + BASE_ID_BITS + 3 * FLAG_BITS + DLC_BITS  # 19
CAN_HEADER_EFF_BITS = (  # SOF, ID, SRR, IDE, ID ext, RTR, r1, r0, DLC = 39
    SOF_BITS + BASE_ID_BITS + 2 * FLAG_BITS + EXT_ID_BITS + 3 * FLAG_BITS + DLC_BITS
)


def _bits(value: int, width: int) -> list[int]:
    return [(value >> (width - 1 - i)) & 1 for i in range(width)]


def crc15(bits: list[int]) -> int:
    """CAN CRC-15 (polynomial 0x4599) over a bit sequence, as ISO 11898-1 specifies."""
    crc = 0
    for b in bits:
        nxt = b ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if nxt:
            crc ^= CRC15_POLY
    return crc


def frame_bitstream(
    can_id: int, data: bytes, extended: bool = False, remote: bool = False
) -> list[int]:
    """The unstuffed bits SOF..CRC of a classic CAN data/remote frame."""
    dlc = len(data)
    bits = [0]  # SOF
    if extended:
        bits += _bits(can_id >> 18, 11) + [1, 1] + _bits(can_id & 0x3FFFF, 18)  # SRR, IDE
        bits += [1 if remote else 0, 0, 0]  # RTR, r1, r0
    else:
        bits += _bits(can_id, 11) + [1 if remote else 0, 0, 0]  # RTR, IDE, r0
    bits += _bits(dlc, 4)
    if not remote:
        for byte in data:
            bits += _bits(byte, 8)
    return bits + _bits(crc15(bits), 15)


def stuff_count(bits: list[int]) -> int:
    """Number of stuff bits a transmitter inserts into ``bits``."""
    count, run, last = 0, 0, -1
    for b in bits:
        if b == last:
            run += 1
        else:
            run, last = 1, b
        if run == STUFF_RUN:
            count += 1
            last, run = 1 - b, 1  # the stuff bit starts a new run
    return count


def _crc15_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 7
        for _ in range(8):
            crc = ((crc << 1) ^ CRC15_POLY) if crc & 0x4000 else (crc << 1)
            crc &= 0x7FFF
        table.append(crc)
    return tuple(table)


_CRC15_TABLE: Final = _crc15_table()


# Bit-stuffing as a state machine over whole bytes: state = 5 * last_bit + run (run =
# equal bits so far, 0..4), plus START; STUFF_TABLES[k][state][value] = (state', stuffs)
# for the k-bit chunk ``value`` sent MSB first.
STUFF_START = 2 * STUFF_RUN


def _stuff_step(state: int, bit: int) -> tuple[int, int]:
    last, run = divmod(state, STUFF_RUN) if state != STUFF_START else (-1, 0)
    if bit == last:
        run += 1
        if run == STUFF_RUN:  # stuff bit (the complement) starts a new run of one
            return STUFF_RUN * (1 - bit) + 1, 1
        return STUFF_RUN * bit + run, 0
    return STUFF_RUN * bit + 1, 0


def _stuff_tables(width: int) -> tuple[tuple[tuple[int, int], ...], ...]:
    tables = []
    for state in range(STUFF_START + 1):
        row = []
        for value in range(1 << width):
            st, n = state, 0
            for i in range(width - 1, -1, -1):
                st, k = _stuff_step(st, (value >> i) & 1)
                n += k
            row.append((st, n))
        tables.append(tuple(row))
    return tuple(tables)


_STUFF8 = _stuff_tables(8)
_STUFF7 = _stuff_tables(7)


def _flat(tables: tuple[tuple[tuple[int, int], ...], ...], width: int) -> tuple[int, ...]:
    """The same table flat, for the per-frame loop: entry ``(state << width) | value`` is
    ``(state' << STUFF_COUNT_BITS) | stuffs`` (one integer lookup instead of two tuples)."""
    return tuple((st << STUFF_COUNT_BITS) | n for row in tables for st, n in row)


STUFF_COUNT_BITS: Final = 4  # stuff bits of one chunk of <= 8 bits: at most 2, held in 4 bits
STUFF_COUNT_MASK: Final = (1 << STUFF_COUNT_BITS) - 1
_FLAT8: Final = _flat(_STUFF8, 8)
_FLAT7: Final = _flat(_STUFF7, 7)


@functools.lru_cache(maxsize=4096)
def _header(can_id: int, dlc: int, extended: bool, remote: bool) -> tuple[int, int, int, int]:
    """(bits, CRC-15 register, stuffing state, stuff bits) after SOF..DLC of a frame."""
    rtr = 1 if remote else 0
    if extended:
        head = f"0{can_id >> 18:011b}11{can_id & 0x3FFFF:018b}{rtr}00{dlc:04b}"
    else:
        head = f"0{can_id:011b}{rtr}00{dlc:04b}"
    state, stuff = STUFF_START, 0
    for c in head:
        state, k = _stuff_step(state, int(c))
        stuff += k
    return len(head), crc15([int(c) for c in head]), state, stuff


def frame_bits(can_id: int, data: bytes, extended: bool = False, remote: bool = False) -> int:
    """Exact length of a classic CAN frame on the wire in bits, including intermission.

    Same result as ``len(frame_bitstream) + stuff_count(...) + tail`` (tested against an
    independent stuffer on 10 000 random frames), computed fast because the bench calls it
    per frame: the header's CRC and stuffing state are cached, and data bytes go through a
    byte-wise CRC-15 table and a byte-wise stuffing state machine.
    """
    dlc = len(data)
    n_bits, crc, state, stuff = _header(can_id, dlc, extended, remote)
    if not remote:
        t8, table = _FLAT8, _CRC15_TABLE
        for byte in data:
            crc = ((crc << 8) & 0x7FFF) ^ table[((crc >> 7) ^ byte) & 0xFF]
            entry = t8[(state << 8) | byte]
            state = entry >> STUFF_COUNT_BITS
            stuff += entry & STUFF_COUNT_MASK
        n_bits += 8 * dlc
    entry = _FLAT8[(state << 8) | (crc >> 7)]  # CRC-15: its top 8 bits, then the low 7
    stuff += entry & STUFF_COUNT_MASK
    entry = _FLAT7[((entry >> STUFF_COUNT_BITS) << 7) | (crc & 0x7F)]
    stuff += entry & STUFF_COUNT_MASK
    return n_bits + CRC15_BITS + stuff + UNSTUFFED_TAIL_BITS


def _worst_case_stuffed(unstuffed_bits: int) -> int:
    """Length of ``unstuffed_bits`` after worst-case stuffing: one stuff bit after the 5th
    bit, then one every 4 bits (``1111o 0000i 1111o ...``), i.e. + (L - 1) // 4 (Davis et
    al. 2007; Linux ``can_bitstuffing_len``)."""
    return unstuffed_bits + (unstuffed_bits - 1) // (STUFF_RUN - 1)


def frame_bits_worst_case(dlc: int, extended: bool = False) -> int:
    """Upper bound on frame length (Davis et al. 2007): 55+10n (11-bit) or 80+10n (29-bit).

    Stuffable bits g + 8n (g = 34 or 54: SOF..DLC and CRC-15) get (g + 8n - 1) // 4 stuff
    bits, plus the 13-bit unstuffed tail; the closed form is exact for every n.
    """
    return (80 if extended else 55) + 10 * dlc


def wire_time_ns(bits: int, bitrate_bps: int) -> int:
    """Time on the wire of ``bits`` at ``bitrate_bps``, in integer nanoseconds (rounded up)."""
    return -(-bits * NS_PER_S // bitrate_bps)
