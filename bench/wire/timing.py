"""Bus timing model: bit-exact frame length, priority arbitration, errors, bus-off, load.

What. vcan and the portable bus deliver frames instantly; a real CAN bus does not. This
module gives lockstep runs a physical layer: a frame handed to the bus at ``ready_ns``
starts when the bus is idle and it wins arbitration (lowest ID among the frames waiting),
occupies the wire for its exact length in bits / bitrate, and its :class:`Delivery`
reports when it was on the wire. On top of that: CAN FD frames (two bitrates), link-level
errors (a corrupted attempt costs its bits, an error frame, and a re-arbitration),
bus-off (a node's frames are held for the recovery time), and bus load per window.

Units. Lengths in bits, bitrates in bit/s, times in integer nanoseconds (``*_ns``); a
wire time is rounded up to the next ns once per frame (or per failed attempt).

Classic CAN frame length (CAN 2.0 / ISO 11898-1:2015 "Classical" frames): SOF,
arbitration field, control field, data, CRC-15 are bit-stuffed (a complemented bit after
five equal bits, stuff bits counting towards the next run; ISO 11898-1:2015 §10.5); CRC
delimiter, ACK slot and delimiter, EOF (7) and the intermission (3) are not. Lengths
include the intermission, so back-to-back frames start one length apart. Worst case
(Davis, Burns, Bril, Lukkien 2007, transmission time C_m): 55 + 10 n bits for 11-bit IDs
and 80 + 10 n for 29-bit IDs, including the intermission.

CAN FD frame length (ISO 11898-1:2015 FD frames, "ISO CAN FD"): SOF, base ID, RRS, IDE
(and SRR, ID extension for 29-bit IDs), FDF, res, BRS, ESI, DLC, data (0..64 bytes, DLC
9..15 = 12, 16, 20, 24, 32, 48, 64 bytes; shorter payloads are padded up) are dynamically
stuffed, except that no dynamic stuff bit is inserted after the last data bit: the fixed
stuff bit that always precedes the stuff count takes its place (§10.5: "even if the last
bits of the preceding field are not a sequence of 5 equal bits"). The CRC field is the
stuff count (3-bit Gray code of the dynamic stuff bits mod 8, plus a parity bit) and
CRC-17 (data <= 16 bytes) or CRC-21 (> 16 bytes), with a fixed stuff bit before the stuff
count and after every 4th bit of the field: 6 fixed stuff bits with CRC-17, 7 with
CRC-21. Their values never change the length, so neither CRC is computed here. With BRS
set, the bitrate switches at the sample point of BRS and back at the sample point of the
CRC delimiter; :class:`FdBits` books BRS at the nominal rate and the CRC delimiter at the
data rate, which makes the two together last exactly one nominal plus one data bit
whatever the sample points (see :class:`FdBits`).

Errors and bus-off. :data:`ERROR_FRAME_BITS` (20) is the worst-case error frame: error
flag 6, superposition of the other nodes' flags up to 6 more, delimiter 8; it is followed
by the 3-bit intermission. A failed attempt is assumed to be detected at the end of the
frame, the error flag starting at the ACK delimiter (an ACK error seen by the
transmitter): it costs the frame's bits up to the ACK slot, the error frame and the
intermission. Error counters are not modelled: failures and bus-off periods are given.
Bus-off recovery takes 128 occurrences of 11 consecutive recessive bits (1408 bit times,
ISO 11898-1:2015 §12.1.4.2 fault confinement rules), assuming a quiet bus.

Pure functions plus one small stateful :class:`BusArbiter` with time as an argument.

Sources: ISO 11898-1:2015 (frame layout, stuffing, error frames, fault confinement);
Davis, Burns, Bril and Lukkien, "Controller Area Network (CAN) schedulability analysis:
Refuted, revisited and revised", Real-Time Systems 35 (2007) (worst-case frame lengths);
Linux ``include/linux/can/length.h`` (kernel >= 6.5, ``can_frame_bits()``: its figures are
the known answers of the tests; see the note before :func:`frame_bits_fd_worst_case` for
what it counts differently).
"""

from __future__ import annotations

import bisect
import functools
import heapq
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from operator import itemgetter
from typing import NamedTuple

NS_PER_S = 1_000_000_000
BITS_PER_BYTE = 8
STUFF_RUN = 5  # equal bits after which a stuff bit is inserted

# -- field sizes, ISO 11898-1:2015 §10.4 (bits) -------------------------------------------
SOF_BITS = 1
BASE_ID_BITS = 11
EXT_ID_BITS = 18  # identifier extension of a 29-bit ID
DLC_BITS = 4
CRC15_BITS = 15
CRC15_POLY = 0x4599
CRC_DELIMITER_BITS = 1
ACK_SLOT_BITS = 1
ACK_DELIMITER_BITS = 1
EOF_BITS = 7
INTERMISSION_BITS = 3
CAN_MAX_DATA_BYTES = 8
FLAG_BITS = 1  # each one-bit field: RTR, SRR, IDE, r0, r1, FDF, res, RRS, BRS, ESI
UNSTUFFED_TAIL_BITS = (  # CRC delimiter, ACK slot + delimiter, EOF, intermission = 13
    CRC_DELIMITER_BITS + ACK_SLOT_BITS + ACK_DELIMITER_BITS + EOF_BITS + INTERMISSION_BITS
)
# bits SOF..DLC ("header", Linux CAN_FRAME_HEADER_*_BITS): SFF = SOF, ID, RTR, IDE, r0, DLC
CAN_HEADER_SFF_BITS = SOF_BITS + BASE_ID_BITS + 3 * FLAG_BITS + DLC_BITS  # 19
CAN_HEADER_EFF_BITS = (  # SOF, ID, SRR, IDE, ID ext, RTR, r1, r0, DLC = 39
    SOF_BITS + BASE_ID_BITS + 2 * FLAG_BITS + EXT_ID_BITS + 3 * FLAG_BITS + DLC_BITS
)

# -- CAN FD ---------------------------------------------------------------------------------
CANFD_MAX_DATA_BYTES = 64
FD_DATA_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)  # by DLC 0..15
# arbitration phase SOF..BRS: SFF = SOF, ID, RRS, IDE, FDF, res, BRS (17)
FD_ARBITRATION_SFF_BITS = SOF_BITS + BASE_ID_BITS + 5 * FLAG_BITS
# EFF = SOF, ID, SRR, IDE, ID ext, RRS, FDF, res, BRS (36)
FD_ARBITRATION_EFF_BITS = SOF_BITS + BASE_ID_BITS + 2 * FLAG_BITS + EXT_ID_BITS + 4 * FLAG_BITS
FD_HEADER_SFF_BITS = FD_ARBITRATION_SFF_BITS + FLAG_BITS + DLC_BITS  # 22 (SOF..DLC, + ESI)
FD_HEADER_EFF_BITS = FD_ARBITRATION_EFF_BITS + FLAG_BITS + DLC_BITS  # 41
FD_STUFF_COUNT_BITS = 4  # 3-bit Gray code of (dynamic stuff bits mod 8) + parity
CRC17_BITS = 17
CRC21_BITS = 21
FD_CRC17_MAX_DATA_BYTES = 16  # CRC-17 up to 16 data bytes, CRC-21 above
FD_FIXED_STUFF_INTERVAL = 4  # a fixed stuff bit after every 4th bit of the CRC field
# after the CRC delimiter, always at the nominal rate: ACK slot + delimiter, EOF, intermission
FD_NOMINAL_TAIL_BITS = ACK_SLOT_BITS + ACK_DELIMITER_BITS + EOF_BITS + INTERMISSION_BITS

# -- errors and bus-off, ISO 11898-1:2015 §10.4.4 and §12.1.4 -----------------------------------
ERROR_FLAG_BITS = 6
ERROR_FLAG_SUPERPOSITION_MAX_BITS = 6  # other nodes' flags overlapping, worst case
ERROR_DELIMITER_BITS = 8
ERROR_FRAME_BITS = ERROR_FLAG_BITS + ERROR_FLAG_SUPERPOSITION_MAX_BITS + ERROR_DELIMITER_BITS
# bits of a frame not sent when the error flag starts at the ACK delimiter (worst case
# assumed by the arbiter): ACK delimiter, EOF, intermission
ERROR_UNSENT_TAIL_BITS = ACK_DELIMITER_BITS + EOF_BITS + INTERMISSION_BITS
BUS_OFF_RECOVERY_SEQUENCES = 128
BUS_OFF_RECOVERY_SEQUENCE_BITS = 11  # consecutive recessive bits
BUS_OFF_RECOVERY_BITS = BUS_OFF_RECOVERY_SEQUENCES * BUS_OFF_RECOVERY_SEQUENCE_BITS  # 1408


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


_CRC15_TABLE = _crc15_table()


_RUNS = re.compile(r"0+|1+")


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
        t8 = _STUFF8
        for byte in data:
            crc = ((crc << 8) & 0x7FFF) ^ _CRC15_TABLE[((crc >> 7) ^ byte) & 0xFF]
            state, k = t8[state][byte]
            stuff += k
        n_bits += 8 * dlc
    state, k = _STUFF8[state][crc >> 7]  # CRC-15: its top 8 bits, then the low 7
    stuff += k
    state, k = _STUFF7[state][crc & 0x7F]
    stuff += k
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


# -- CAN FD ---------------------------------------------------------------------------------


class FdBits(NamedTuple):
    """Length of a frame in bits, split by bitrate.

    ``nominal_bits`` are sent at the nominal (arbitration) bitrate, ``data_bits`` at the data
    bitrate. With BRS set: nominal = SOF..BRS with their dynamic stuff bits, then ACK slot,
    ACK delimiter, EOF and intermission; data = ESI..CRC sequence with all their stuff bits
    (dynamic and fixed), plus the CRC delimiter. The switch happens at the sample point of
    BRS and back at the sample point of the CRC delimiter, so BRS lasts sp_n*Tn +
    (1-sp_d)*Td and the CRC delimiter sp_d*Td + (1-sp_n)*Tn: booking BRS as nominal and the
    delimiter as data gives their exact sum Tn + Td (booking both nominal would overstate
    every frame by Tn - Td). Without BRS, or for a classic frame, ``data_bits`` is 0.
    """

    nominal_bits: int
    data_bits: int = 0

    @property
    def total_bits(self) -> int:
        """All bits of the frame, whatever their rate."""
        return self.nominal_bits + self.data_bits


def fd_len2dlc(length: int) -> int:
    """Smallest CAN FD DLC whose data length holds ``length`` bytes (Linux can_fd_len2dlc)."""
    if not 0 <= length <= CANFD_MAX_DATA_BYTES:
        raise ValueError(f"length={length}: CAN FD carries 0..{CANFD_MAX_DATA_BYTES} bytes")
    return bisect.bisect_left(FD_DATA_LENGTHS, length)


def fd_dlc2len(dlc: int) -> int:
    """Data length in bytes of CAN FD DLC ``dlc`` (0..15)."""
    return FD_DATA_LENGTHS[dlc]


def _fd_crc_field_bits(data_len: int) -> int:
    """Stuff count + CRC-17/21 + their fixed stuff bits (the CRC delimiter excluded)."""
    crc_bits = CRC17_BITS if data_len <= FD_CRC17_MAX_DATA_BYTES else CRC21_BITS
    field = FD_STUFF_COUNT_BITS + crc_bits
    fixed_stuff = 1 + field // FD_FIXED_STUFF_INTERVAL  # one before the stuff count
    return field + fixed_stuff


def _stuff_runs(bits: str) -> tuple[int, int]:
    """(stuff bits inserted into ``bits``, 1 if the last one comes after the final bit)."""
    stuff = carry = 0
    for run in _RUNS.findall(bits):
        e = len(run) + carry
        stuff += e // STUFF_RUN
        carry = 1 if e % STUFF_RUN == 0 else 0
    return stuff, carry


@functools.lru_cache(maxsize=4096)
def _fd_header(can_id: int, dlc: int, extended: bool, brs: bool, esi: bool) -> tuple[str, int, int]:
    """Bits SOF..DLC of an FD frame, the length of SOF..BRS, and the stuff bits inside it.

    Stuffing is causal, so the prefix's stuff bits are those of the full frame. A stuff
    bit after BRS would be sent at the data rate and is excluded; it cannot occur with BRS
    set (res = 0, BRS = 1), and without BRS the split is not used.
    """
    if not 0 <= can_id < 1 << (BASE_ID_BITS + (EXT_ID_BITS if extended else 0)):
        raise ValueError(f"can_id={can_id:#x} does not fit a {'29' if extended else '11'}-bit ID")
    b = 1 if brs else 0
    if extended:  # SOF, base ID, SRR=1, IDE=1, ID ext, RRS=0, FDF=1, res=0, BRS
        arb = f"0{can_id >> EXT_ID_BITS:011b}11{can_id & ((1 << EXT_ID_BITS) - 1):018b}010{b}"
    else:  # SOF, ID, RRS=0, IDE=0, FDF=1, res=0, BRS
        arb = f"0{can_id:011b}0010{b}"
    stuff, trailing = _stuff_runs(arb)
    return arb + f"{1 if esi else 0}{dlc:04b}", len(arb), stuff - trailing


def frame_bits_fd(
    can_id: int,
    data: bytes,
    extended: bool = False,
    brs: bool = True,
    *,
    esi: bool = False,
    padding_byte: int = 0,
) -> FdBits:
    """Exact length of an ISO CAN FD data frame, including intermission, split by bitrate.

    ``data`` of a length that is not a DLC length (9..11, 13..15, ...) is padded with
    ``padding_byte`` up to the next one (12, 16, 20, 24, 32, 48, 64), as a controller
    sends it; padding is stuffed like data. ``esi`` = the transmitter is error-passive
    (ESI recessive). Dynamic stuff bits are counted per run, as in :func:`frame_bits`,
    without the one after the last data bit (replaced by the fixed stuff bit); the CRC
    field has a fixed length (see the module docstring).
    """
    n_bytes = len(data)
    dlc = fd_len2dlc(n_bytes)
    data_len = FD_DATA_LENGTHS[dlc]
    head, arb_bits, arb_stuff = _fd_header(can_id, dlc, extended, brs, esi)
    if data_len:
        payload = int.from_bytes(data, "big")
        if data_len > n_bytes:
            pad_bits = BITS_PER_BYTE * (data_len - n_bytes)
            payload = (payload << pad_bits) | int.from_bytes(
                bytes([padding_byte]) * (data_len - n_bytes), "big"
            )
        bits = head + f"{payload:0{BITS_PER_BYTE * data_len}b}"
    else:
        bits = head
    stuff, trailing = _stuff_runs(bits)
    stuffed = len(bits) + stuff - trailing  # SOF..data with dynamic stuff bits
    fd_tail = _fd_crc_field_bits(data_len) + CRC_DELIMITER_BITS
    if not brs:
        return FdBits(stuffed + fd_tail + FD_NOMINAL_TAIL_BITS, 0)
    nominal = arb_bits + arb_stuff
    return FdBits(nominal + FD_NOMINAL_TAIL_BITS, stuffed - nominal + fd_tail)


# What Linux can/length.h (can_frame_bits, kernel >= 6.5) counts, compared with this module:
# * it includes the intermission when asked (our lengths always do) and counts the ACK slot
#   as 1 bit (a CAN FD receiver tolerates a 2-bit ACK; a transmitter sends 1);
# * its "bitstuffing" figure is the worst case (L - 1) // 4 over the dynamically stuffed
#   bits, not the stuffing of a given frame; for classic frames it puts the CRC delimiter
#   into the stuffed region (L one larger), which gives the same count as Davis et al.
#   because L = 34 + 8n or 54 + 8n is 2 mod 4, so CAN_FRAME_LEN_MAX-style figures agree:
#   classic 111 / 131 bits unstuffed, 135 / 160 worst case (SFF / EFF, 8 bytes);
# * for FD it ignores that no dynamic stuff bit follows the last data bit, so its worst
#   case (712 / 736 bits with 64 bytes) can exceed the reachable maximum by one bit; we
#   keep its formula, a valid bound; its unstuffed FD figures (579 / 598) are exact;
# * kernels 5.12 .. 6.4 had CANFD_FRAME_OVERHEAD_SFF/EFF = DIV_ROUND_UP(61 / 80, 8) bytes:
#   they counted a 5-bit stuff count with CRC-21 and no fixed stuff bits (fixed in 6.5,
#   67 / 86 bits: 4-bit stuff count, 6 or 7 fixed stuff bits).


def frame_bits_fd_worst_case(data_len: int, extended: bool = False, brs: bool = True) -> FdBits:
    """Upper bound on an FD frame's length (incl. intermission), split by bitrate.

    Total = Linux ``can_frame_bits(true, eff, true, true, len)``: the L = 22/41 + 8n
    dynamically stuffed bits get (L - 1) // 4 stuff bits (as Davis et al. 2007 for classic
    frames), plus the fixed-length CRC field and tail. Of those stuff bits, as many as fit
    (one after the 5th bit then every 4th, before BRS) are booked at the nominal rate, the
    rest at the data rate: with a data rate >= the nominal rate this also bounds the time.
    ``data_len`` is rounded up to a DLC length.
    """
    data_len = FD_DATA_LENGTHS[fd_len2dlc(data_len)]
    header = FD_HEADER_EFF_BITS if extended else FD_HEADER_SFF_BITS
    dynamic = header + BITS_PER_BYTE * data_len
    total = (
        _worst_case_stuffed(dynamic)
        + _fd_crc_field_bits(data_len)
        + CRC_DELIMITER_BITS
        + FD_NOMINAL_TAIL_BITS
    )
    if not brs:
        return FdBits(total, 0)
    arb = FD_ARBITRATION_EFF_BITS if extended else FD_ARBITRATION_SFF_BITS
    # stuff bits strictly inside SOF..BRS: after bits 5, 9, ..., up to bit arb - 1
    arb_stuff = (arb - 2) // (STUFF_RUN - 1)
    nominal = arb + arb_stuff + FD_NOMINAL_TAIL_BITS
    return FdBits(nominal, total - nominal)


def wire_time_fd_ns(bits: FdBits, nominal_bps: int, data_bps: int) -> int:
    """Time on the wire of an FD frame, in integer ns rounded up once for the whole frame.

    Equals :func:`wire_time_ns` when ``bits.data_bits`` is 0.
    """
    if nominal_bps <= 0 or data_bps <= 0:
        raise ValueError(f"bitrates {nominal_bps}, {data_bps}: must be positive")
    num = (bits.nominal_bits * data_bps + bits.data_bits * nominal_bps) * NS_PER_S
    return -(-num // (nominal_bps * data_bps))


# -- errors and bus-off ------------------------------------------------------------------------


def failed_attempt_bits(bits: int | FdBits) -> FdBits:
    """Bus time of one failed attempt of a frame of ``bits``, error frame included.

    The frame is sent up to its ACK slot (error flag at the ACK delimiter, worst case of an
    error detected at the end of the frame: ``bits - ERROR_UNSENT_TAIL_BITS``), then the
    error frame (:data:`ERROR_FRAME_BITS`) and the intermission, all at the nominal rate;
    an FD frame's data phase was sent in full.
    """
    fd = bits if isinstance(bits, FdBits) else FdBits(bits, 0)
    sent = fd.nominal_bits - ERROR_UNSENT_TAIL_BITS
    if sent <= 0:
        raise ValueError(f"bits={bits}: shorter than the frame tail")
    return FdBits(sent + ERROR_FRAME_BITS + INTERMISSION_BITS, fd.data_bits)


def bus_off_recovery_ns(bitrate_bps: int) -> int:
    """Bus-off recovery: 128 occurrences of 11 recessive bits = 1408 bit times, in ns."""
    return wire_time_ns(BUS_OFF_RECOVERY_BITS, bitrate_bps)


# -- arbitration ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Delivery:
    """When one frame was on the wire.

    ``start_ns``/``end_ns`` bound the successful attempt (``end_ns`` includes the
    intermission). ``failed_ns`` lists the [start, end) of each failed attempt, error frame
    and intermission included; ``attempts`` = len(failed_ns) + 1.
    """

    ready_ns: int
    start_ns: int
    end_ns: int
    can_id: int
    seq: int
    attempts: int = 1
    node: str = ""
    failed_ns: tuple[tuple[int, int], ...] = ()

    @property
    def first_start_ns(self) -> int:
        """Start of the first attempt (= ``start_ns`` without errors)."""
        return self.failed_ns[0][0] if self.failed_ns else self.start_ns

    @property
    def error_ns(self) -> int:
        """Bus time lost to this frame's failed attempts and their error frames."""
        return sum(end - start for start, end in self.failed_ns)

    def busy_intervals(self) -> tuple[tuple[int, int], ...]:
        """Every [start, end) during which this frame (or its error frames) held the bus."""
        return (*self.failed_ns, (self.start_ns, self.end_ns))


class _Retry:
    """Failed attempts still to come for one frame, their bus time, and their intervals."""

    __slots__ = ("failed", "left", "wire_ns")

    def __init__(self, left: int, wire_ns: int) -> None:
        self.left = left
        self.wire_ns = wire_ns
        self.failed: list[tuple[int, int]] = []


_PRIORITY = itemgetter(1, 2)  # (can_id, seq): lowest ID wins, then first submitted


class BusArbiter:
    """Non-pre-emptive priority arbitration of frames handed to one bus.

    ``submit`` frames in any order, then ``resolve(until_ns)`` returns every frame whose
    successful attempt starts before ``until_ns``, in wire order. Frames submitted later
    must not be ready earlier than the last resolved horizon (causality), else they start
    when the bus is next free. Counters: ``busy_ns_total`` = all bus time used (frames,
    failed attempts, error frames), ``error_ns_total`` = the part lost to errors.

    CAN FD: give ``data_bitrate_bps`` and submit :class:`FdBits`; classic and FD frames mix.
    """

    def __init__(self, bitrate_bps: int, *, data_bitrate_bps: int | None = None) -> None:
        if bitrate_bps <= 0:
            raise ValueError(f"bitrate_bps={bitrate_bps}: must be positive")
        if data_bitrate_bps is not None and data_bitrate_bps <= 0:
            raise ValueError(f"data_bitrate_bps={data_bitrate_bps}: must be positive")
        self.bitrate_bps = bitrate_bps
        self.data_bitrate_bps = data_bitrate_bps
        self._busy_until_ns = 0
        # heap of (eligible_ns, can_id, seq, ready_ns, wire_ns, node)
        self._pending: list[tuple[int, int, int, int, int, str]] = []
        self._retries: dict[int, _Retry] = {}  # frames submitted with failed_attempts
        self._bus_off: dict[str, list[tuple[int, int]]] = {}
        self._seq = 0
        self.busy_ns_total = 0
        self.error_ns_total = 0

    def _wire_ns(self, bits: FdBits) -> int:
        if not bits.data_bits:
            return wire_time_ns(bits.nominal_bits, self.bitrate_bps)
        if self.data_bitrate_bps is None:
            raise ValueError("an FD frame with a data phase needs data_bitrate_bps")
        return wire_time_fd_ns(bits, self.bitrate_bps, self.data_bitrate_bps)

    def submit(
        self,
        ready_ns: int,
        can_id: int,
        bits: int | FdBits,
        *,
        failed_attempts: int = 0,
        node: str = "",
    ) -> int:
        """Queue a frame; returns its sequence number (to match the :class:`Delivery`).

        ``bits``: a classic length (:func:`frame_bits`) or :class:`FdBits`. The first
        ``failed_attempts`` attempts hit an error (see :func:`failed_attempt_bits`); after
        each, the frame re-arbitrates against everything then pending. ``node`` names the
        transmitter, for :meth:`bus_off` and per-node load.
        """
        seq = self._seq
        self._seq += 1
        if isinstance(bits, FdBits):
            wire_ns = self._wire_ns(bits)
        else:
            wire_ns = -(-bits * NS_PER_S // self.bitrate_bps)
        if failed_attempts:
            if failed_attempts < 0:
                raise ValueError(f"failed_attempts={failed_attempts}: must be >= 0")
            self._retries[seq] = _Retry(failed_attempts, self._wire_ns(failed_attempt_bits(bits)))
        heapq.heappush(self._pending, (ready_ns, can_id, seq, ready_ns, wire_ns, node))
        return seq

    def bus_off(self, node: str, from_ns: int, to_ns: int | None = None) -> int:
        """Hold ``node``'s frames in [from_ns, to_ns); returns ``to_ns``.

        ``to_ns`` defaults to ``from_ns`` + :func:`bus_off_recovery_ns`. A frame of the node
        that would start in the window waits for its end, then arbitrates normally (its
        ``ready_ns`` is kept, so the wait shows as latency). A real driver may instead
        drop or abort queued frames on bus-off (Linux: the netdev queue is stopped, and
        ``restart-ms`` decides when it recovers); model that by not submitting them. A
        frame already on the wire at ``from_ns`` completes (arbitration is not pre-empted).
        """
        if not node:
            raise ValueError("bus_off needs a node name (frames are submitted with node=...)")
        if to_ns is None:
            to_ns = from_ns + bus_off_recovery_ns(self.bitrate_bps)
        if to_ns < from_ns:
            raise ValueError(f"bus-off window [{from_ns}, {to_ns}) ends before it starts")
        self._bus_off.setdefault(node, []).append((from_ns, to_ns))
        return to_ns

    def _held_until(self, node: str, t: int) -> int | None:
        """End of a bus-off window of ``node`` containing ``t``, or None."""
        for start, end in self._bus_off.get(node, ()):
            if start <= t < end:
                return end
        return None

    def resolve(self, until_ns: int | None = None) -> list[Delivery]:
        """Deliveries of the frames that start before ``until_ns`` (all if None)."""
        out: list[Delivery] = []
        pending = self._pending
        while pending:
            t = max(self._busy_until_ns, pending[0][0])
            if until_ns is not None and t >= until_ns:
                break
            # every frame eligible by t contends; lowest ID wins, then FIFO
            ready = []
            while pending and pending[0][0] <= t:
                ready.append(heapq.heappop(pending))
            if self._bus_off:
                contenders = []
                for f in ready:
                    held = self._held_until(f[5], t)
                    if held is None:
                        contenders.append(f)
                    else:  # re-enter the queue when the node has recovered
                        heapq.heappush(pending, (held, *f[1:]))
                if not contenders:
                    continue
                ready = contenders
            win = min(ready, key=_PRIORITY)
            seq = win[2]
            for f in ready:
                if f[2] != seq:  # by sequence number, not identity (compiled tuples are values)
                    heapq.heappush(pending, f)
            retry = self._retries.get(seq)
            if retry is not None and retry.left > 0:  # this attempt fails
                retry.left -= 1
                end = t + retry.wire_ns
                retry.failed.append((t, end))
                self._busy_until_ns = end
                self.busy_ns_total += retry.wire_ns
                self.error_ns_total += retry.wire_ns
                heapq.heappush(pending, (end, *win[1:]))
                continue
            failed: tuple[tuple[int, int], ...] = ()
            if retry is not None:
                failed = tuple(retry.failed)
                del self._retries[seq]
            end = t + win[4]
            self._busy_until_ns = end
            self.busy_ns_total += win[4]
            out.append(Delivery(win[3], t, end, win[1], seq, len(failed) + 1, win[5], failed))
        return out


# -- bus load -----------------------------------------------------------------------------------


def _window_starts(window_ns: int, t0_ns: int, t1_ns: int) -> range:
    if window_ns <= 0:
        raise ValueError(f"window_ns={window_ns}: must be positive")
    if t1_ns <= t0_ns:
        raise ValueError(f"[{t0_ns}, {t1_ns}): empty interval")
    return range(t0_ns, t1_ns, window_ns)


def busy_ns_per_window(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> list[tuple[int, int]]:
    """(window start, ns the bus was held) for windows of ``window_ns`` tiling [t0, t1).

    Busy = every interval of :meth:`Delivery.busy_intervals` (failed attempts and error
    frames included), clipped to the window; the last window ends at ``t1_ns``.
    """
    starts = _window_starts(window_ns, t0_ns, t1_ns)
    busy = [0] * len(starts)
    for d in deliveries:
        for a, b in d.busy_intervals():
            a, b = max(a, t0_ns), min(b, t1_ns)
            k = (a - t0_ns) // window_ns
            while a < b:
                seg_end = min(b, t0_ns + (k + 1) * window_ns)
                busy[k] += seg_end - a
                a, k = seg_end, k + 1
    return list(zip(starts, busy, strict=True))


def load_per_window(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> list[tuple[int, float]]:
    """(window start, busy fraction 0..1) for windows of ``window_ns`` tiling [t0, t1).

    The fraction of a last, shorter window is relative to its own length.
    """
    return [
        (start, busy / (min(start + window_ns, t1_ns) - start))
        for start, busy in busy_ns_per_window(deliveries, window_ns, t0_ns, t1_ns)
    ]


def load_per_window_by_node(
    deliveries: Iterable[Delivery],
    window_ns: int,
    t0_ns: int,
    t1_ns: int,
    node_of: Mapping[int, str] | None = None,
) -> dict[str, list[tuple[int, float]]]:
    """:func:`load_per_window` per transmitting node.

    The node of a delivery is ``node_of[seq]`` if given, else ``Delivery.node``. A frame's
    failed attempts and error frames count for its transmitter.
    """
    by_node: dict[str, list[Delivery]] = {}
    for d in deliveries:
        name = node_of[d.seq] if node_of is not None else d.node
        by_node.setdefault(name, []).append(d)
    return {name: load_per_window(ds, window_ns, t0_ns, t1_ns) for name, ds in by_node.items()}


def mean_peak_load(
    deliveries: Iterable[Delivery], window_ns: int, t0_ns: int, t1_ns: int
) -> tuple[float, float]:
    """(mean load over [t0, t1), peak load of a ``window_ns`` window)."""
    windows = busy_ns_per_window(deliveries, window_ns, t0_ns, t1_ns)
    mean = sum(busy for _, busy in windows) / (t1_ns - t0_ns)
    peak = max(busy / (min(start + window_ns, t1_ns) - start) for start, busy in windows)
    return mean, peak
