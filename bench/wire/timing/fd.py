"""CAN FD frame length, bit-exact and split by bitrate (:class:`FdBits`), and its wire time.

In: an identifier, the data bytes (padded up to a DLC length), the extended, BRS and ESI
flags. Out: :class:`FdBits` (bits at the nominal rate, bits at the data rate) from
:func:`frame_bits_fd` (exact) or :func:`frame_bits_fd_worst_case` (the bound), and the time
of a frame at two bitrates (:func:`wire_time_fd_ns`).

Units. Lengths in bits, bitrates in bit/s, times in integer nanoseconds, rounded up once
per frame.

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

Sources: ISO 11898-1:2015 (FD frame layout, stuffing, CRC field); Davis, Burns, Bril and
Lukkien (2007) (worst-case stuffing); Linux ``include/linux/can/length.h`` (kernel >= 6.5,
``can_frame_bits()``: its figures are the known answers of the tests; see the note before
:func:`frame_bits_fd_worst_case` for what it counts differently).
"""

from __future__ import annotations

import bisect
import functools
import re
from typing import NamedTuple

from bench.wire.timing.classic import (
    ACK_DELIMITER_BITS,
    ACK_SLOT_BITS,
    BASE_ID_BITS,
    BITS_PER_BYTE,
    CRC_DELIMITER_BITS,
    DLC_BITS,
    EOF_BITS,
    EXT_ID_BITS,
    FLAG_BITS,
    INTERMISSION_BITS,
    NS_PER_S,
    SOF_BITS,
    STUFF_RUN,
    _worst_case_stuffed,
)

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


_RUNS = re.compile(r"0+|1+")


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
