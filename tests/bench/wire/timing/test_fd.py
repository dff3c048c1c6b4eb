"""CAN FD frame length against an independent ISO 11898-1:2015 bit builder; Linux figures."""

from __future__ import annotations

import itertools
import random

import pytest

from bench.wire.timing.classic import (
    frame_bits,
    frame_bits_worst_case,
    frame_bitstream,
    stuff_count,
    wire_time_ns,
)
from bench.wire.timing.fd import (
    FdBits,
    fd_dlc2len,
    fd_len2dlc,
    frame_bits_fd,
    frame_bits_fd_worst_case,
    wire_time_fd_ns,
)

N_RANDOM_FD = 2500
SEED = 11
STUFF_RUN = 5
BITRATE_500K = 500_000
BITRATE_2M = 2_000_000
BITRATE_8M = 8_000_000
CANFD_MAX_LEN = 64
CAN_MAX_LEN = 8
ID_2AA = 0x2AA  # 01010101010: no stuff bits in the identifier
EXT_ID_ALTERNATING = 0x2AAAAAA  # 29-bit ID whose arbitration field needs no stuff bit
ALTERNATING_BYTE = 0x55

# --- Independent reference: the FD bit stream built field by field (ISO 11898-1:2015) -----
REF_FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
REF_GRAY3 = (0b000, 0b001, 0b011, 0b010, 0b110, 0b111, 0b101, 0b100)  # stuff count mod 8
REF_CRC17 = (17, 0x1685B)  # x^17+x^16+x^14+x^13+x^11+x^6+x^4+x^3+x+1, without x^17
REF_CRC21 = (21, 0x102899)  # x^21+x^20+x^13+x^11+x^7+x^4+x^3+1, without x^21
REF_CRC17_MAX_LEN = 16
REF_FIXED_STUFF_EVERY = 4
REF_TAIL_NOMINAL = 1 + 1 + 7 + 3  # ACK slot, ACK delimiter, EOF, intermission
NOMINAL, DATA = "n", "d"
DYNAMIC, FIXED, PLAIN = "dyn", "fix", "-"


def _field(value: int, width: int) -> list[int]:
    return [(value >> i) & 1 for i in reversed(range(width))]


def _crc(bits: list[int], width: int, poly: int) -> int:
    """CRC-17/21 of CAN FD: register initialised with a 1 in its top bit."""
    crc = 1 << (width - 1)
    for b in bits:
        top = (crc >> (width - 1)) & 1
        crc = (crc << 1) & ((1 << width) - 1)
        if b ^ top:
            crc ^= poly
    return crc


def _reference_fd(
    can_id: int, data: bytes, ext: bool, brs: bool, esi: bool, pad: int
) -> tuple[FdBits, list[tuple[int, str, str]]]:
    """Emit every bit (value, rate, stuff kind) of an FD frame; return the split and stream."""
    dlc = next(i for i, n in enumerate(REF_FD_LENGTHS) if n >= len(data))
    data = data + bytes([pad]) * (REF_FD_LENGTHS[dlc] - len(data))
    if ext:  # SOF, base ID, SRR, IDE, ID extension, RRS, FDF, res, BRS
        arb = [0, *_field(can_id >> 18, 11), 1, 1, *_field(can_id & 0x3FFFF, 18), 0, 1, 0]
    else:  # SOF, ID, RRS, IDE, FDF, res, BRS
        arb = [0, *_field(can_id, 11), 0, 0, 1, 0]
    arb.append(1 if brs else 0)
    ctrl = [1 if esi else 0, *_field(dlc, 4)]
    for byte in data:
        ctrl += _field(byte, 8)
    fast = DATA if brs else NOMINAL
    out: list[tuple[int, str, str]] = []
    unstuffed = arb + ctrl
    n_dynamic = 0
    for i, b in enumerate(unstuffed):
        out.append((b, NOMINAL if i < len(arb) else fast, PLAIN))
        last = [v for v, _, _ in out[-STUFF_RUN:]]
        if len(last) == STUFF_RUN and len(set(last)) == 1 and i < len(unstuffed) - 1:
            # stuff bit after BRS is sent after the switch: data rate
            out.append((1 - b, NOMINAL if i < len(arb) - 1 else fast, DYNAMIC))
            n_dynamic += 1
    # CRC field: fixed stuff bit, stuff count (Gray + parity), CRC; a fixed stuff bit after
    # every 4th bit. The CRC covers SOF..data with dynamic stuff bits, and the stuff count.
    gray = REF_GRAY3[n_dynamic % 8]
    count = [*_field(gray, 3), bin(gray).count("1") % 2]
    width, poly = REF_CRC17 if len(data) <= REF_CRC17_MAX_LEN else REF_CRC21
    crc = _crc([v for v, _, _ in out] + count, width, poly)
    out.append((1 - out[-1][0], fast, FIXED))
    for j, b in enumerate(count + _field(crc, width)):
        out.append((b, fast, PLAIN))
        if (j + 1) % REF_FIXED_STUFF_EVERY == 0:
            out.append((1 - b, fast, FIXED))
    out.append((1, fast, PLAIN))  # CRC delimiter: rate switches back at its sample point
    out += [(1, NOMINAL, PLAIN)] * REF_TAIL_NOMINAL  # ACK slot (recessive as sent), rest
    nominal = sum(1 for _, rate, _ in out if rate == NOMINAL)
    return FdBits(nominal, len(out) - nominal), out


def _max_run(values: list[int]) -> int:
    best = run = 1
    for a, b in itertools.pairwise(values):
        run = run + 1 if a == b else 1
        best = max(best, run)
    return best


def _random_payload(rng: random.Random) -> bytes:
    """Random length 0..64; bytes biased to long runs so stuffing edge cases occur often."""
    choices = (0x00, 0xFF, 0x0F, 0xF0, 0x1F, 0xE0)
    n = rng.randrange(CANFD_MAX_LEN + 1)
    return bytes(
        rng.choice(choices) if rng.random() < 0.5 else rng.randrange(256) for _ in range(n)
    )


def test_fd_length_matches_reference_builder() -> None:
    """frame_bits_fd == bit-by-bit ISO FD frame, both ID lengths, all lengths, BRS on/off."""
    rng = random.Random(SEED)
    for _ in range(N_RANDOM_FD):
        ext = rng.random() < 0.5
        can_id = rng.randrange(1 << (29 if ext else 11))
        data = _random_payload(rng)
        brs, esi, pad = rng.random() < 0.7, rng.random() < 0.2, rng.choice((0x00, 0xCC, 0x55))
        ref, stream = _reference_fd(can_id, data, ext, brs, esi, pad)
        got = frame_bits_fd(can_id, data, ext, brs, esi=esi, padding_byte=pad)
        assert got == ref, (hex(can_id), data.hex(), ext, brs, esi)
        # the reference itself obeys the stuffing rule and the fixed-stuff count
        crc_end = len(stream) - REF_TAIL_NOMINAL - 1
        assert _max_run([v for v, _, _ in stream[:crc_end]]) <= STUFF_RUN
        n_fixed = sum(1 for _, _, kind in stream if kind == FIXED)
        assert n_fixed == (6 if fd_dlc2len(fd_len2dlc(len(data))) <= REF_CRC17_MAX_LEN else 7)
        worst = frame_bits_fd_worst_case(len(data), ext, brs)
        assert got.total_bits <= worst.total_bits
        assert got.nominal_bits <= worst.nominal_bits
        for nominal_bps, data_bps in ((BITRATE_500K, BITRATE_2M), (BITRATE_500K, BITRATE_8M)):
            assert wire_time_fd_ns(got, nominal_bps, data_bps) <= wire_time_fd_ns(
                worst, nominal_bps, data_bps
            )


def test_no_dynamic_stuff_bit_before_stuff_count() -> None:
    """Five equal bits ending the data field get no stuff bit: the fixed one replaces it."""
    ends_with_five_ones, no_run = b"\x1f", b"\x1e"  # ...0001 1111 vs ...0001 1110
    assert frame_bits_fd(ID_2AA, ends_with_five_ones) == frame_bits_fd(ID_2AA, no_run)
    # the same five bits inside the data field do cost a stuff bit
    assert (
        frame_bits_fd(ID_2AA, ends_with_five_ones + no_run).total_bits
        == frame_bits_fd(ID_2AA, no_run + no_run).total_bits + 1
    )


def test_brs_moves_bits_to_data_phase_only() -> None:
    """BRS keeps the total length; without it every bit is at the nominal rate."""
    data = bytes(range(CANFD_MAX_LEN))
    with_brs, without = frame_bits_fd(0x123, data), frame_bits_fd(0x123, data, brs=False)
    assert without.data_bits == 0
    assert with_brs.total_bits == without.total_bits
    # SOF..BRS (17, no stuffing for 0x2AA) + ACK, ACK delimiter, EOF, intermission (12)
    assert frame_bits_fd(ID_2AA, data).nominal_bits == 17 + REF_TAIL_NOMINAL


def test_fd_dlc_padding() -> None:
    """Lengths round up to 12, 16, 20, 24, 32, 48, 64 and padding bytes are on the wire."""
    assert [fd_dlc2len(fd_len2dlc(n)) for n in (9, 12, 13, 17, 21, 25, 33, 49)] == [
        12, 12, 16, 20, 24, 32, 48, 64,
    ]  # fmt: skip
    assert frame_bits_fd(0x10, bytes(9)) == frame_bits_fd(0x10, bytes(12))
    with pytest.raises(ValueError):
        fd_len2dlc(CANFD_MAX_LEN + 1)


def test_fd_wire_time_known_answer() -> None:
    """29 bits at 500 kbit/s + 550 bits at 2 Mbit/s = 58 + 275 us; without BRS 579 * 2 us."""
    fd = frame_bits_fd(ID_2AA, bytes([ALTERNATING_BYTE] * CANFD_MAX_LEN))
    assert fd == FdBits(29, 550)
    assert wire_time_fd_ns(fd, BITRATE_500K, BITRATE_2M) == 333_000
    slow = frame_bits_fd(ID_2AA, bytes([ALTERNATING_BYTE] * CANFD_MAX_LEN), brs=False)
    assert wire_time_fd_ns(slow, BITRATE_500K, BITRATE_2M) == 1_158_000
    assert wire_time_fd_ns(FdBits(111, 0), BITRATE_500K, BITRATE_2M) == wire_time_ns(
        111, BITRATE_500K
    )


# --- Linux include/linux/can/length.h (kernel >= 6.5, Vincent Mailhol 2023) ---------------
K_CAN_FRAME_HEADER_SFF_BITS = 19
K_CAN_FRAME_HEADER_EFF_BITS = 39
K_CANFD_FRAME_HEADER_SFF_BITS = 22
K_CANFD_FRAME_HEADER_EFF_BITS = 41
K_CAN_FRAME_CRC_FIELD_BITS = 16  # CRC-15 + delimiter
K_CANFD_FRAME_CRC17_FIELD_BITS = 28  # stuff count 4 + CRC 17 + delimiter 1 + fixed stuff 6
K_CANFD_FRAME_CRC21_FIELD_BITS = 33  # stuff count 4 + CRC 21 + delimiter 1 + fixed stuff 7
K_CAN_FRAME_FOOTER_BITS = 9  # ACK slot, ACK delimiter, EOF
K_CAN_INTERMISSION_BITS = 3
K_CAN_FRAME_LEN_MAX = 17  # bytes: can_frame_bytes(false, true, false, 8)
K_CANFD_FRAME_LEN_MAX = 75  # bytes: can_frame_bytes(true, true, false, 64)
BITS_PER_BYTE = 8
# maximum data length, including intermission (table of the commit introducing
# can_frame_bits): (is_fd, is_eff, bitstuffing) -> bits
K_MAX_FRAME_BITS = {
    (False, False, False): 111,
    (False, True, False): 131,
    (False, False, True): 135,
    (False, True, True): 160,
    (True, False, False): 579,
    (True, True, False): 598,
    (True, False, True): 712,
    (True, True, True): 736,
}


def _kernel_can_frame_bits(
    is_fd: bool, is_eff: bool, bitstuffing: bool, intermission: bool, data_len: int
) -> int:
    """Transcription of the kernel's can_frame_bits() macro."""

    def stuffed(n: int) -> int:  # can_bitstuffing_len
        return n + (n - 1) // 4 if bitstuffing else n

    if is_fd:
        header = K_CANFD_FRAME_HEADER_EFF_BITS if is_eff else K_CANFD_FRAME_HEADER_SFF_BITS
        crc = K_CANFD_FRAME_CRC17_FIELD_BITS if data_len <= 16 else K_CANFD_FRAME_CRC21_FIELD_BITS
        bits = stuffed(header + data_len * BITS_PER_BYTE) + crc
    else:
        header = K_CAN_FRAME_HEADER_EFF_BITS if is_eff else K_CAN_FRAME_HEADER_SFF_BITS
        bits = stuffed(header + data_len * BITS_PER_BYTE + K_CAN_FRAME_CRC_FIELD_BITS)
    return bits + K_CAN_FRAME_FOOTER_BITS + (K_CAN_INTERMISSION_BITS if intermission else 0)


def _div_round_up(a: int, b: int) -> int:
    return -(-a // b)


def test_kernel_transcription_matches_its_table() -> None:
    """The transcribed can_frame_bits() gives the kernel's own table and LEN_MAX constants."""
    for (fd, eff, stuffing), bits in K_MAX_FRAME_BITS.items():
        n = CANFD_MAX_LEN if fd else CAN_MAX_LEN
        assert _kernel_can_frame_bits(fd, eff, stuffing, True, n) == bits
    assert _div_round_up(K_MAX_FRAME_BITS[False, True, False], BITS_PER_BYTE) == (
        K_CAN_FRAME_LEN_MAX
    )
    assert _div_round_up(K_MAX_FRAME_BITS[True, True, False], BITS_PER_BYTE) == (
        K_CANFD_FRAME_LEN_MAX
    )


@pytest.mark.parametrize("intermission", [True, False])
def test_worst_case_equals_kernel(intermission: bool) -> None:
    """Davis classic worst case and the FD worst case == kernel bitstuffing figures, all n."""
    drop = 0 if intermission else K_CAN_INTERMISSION_BITS
    for eff in (False, True):
        for n in range(CAN_MAX_LEN + 1):
            kernel = _kernel_can_frame_bits(False, eff, True, intermission, n)
            assert frame_bits_worst_case(n, eff) - drop == kernel
        for n in REF_FD_LENGTHS:
            kernel = _kernel_can_frame_bits(True, eff, True, intermission, n)
            assert frame_bits_fd_worst_case(n, eff).total_bits - drop == kernel


def _zero_stuff_classic(extended: bool) -> int:
    """Length of an 8-byte classic frame that needs no stuff bit (searched over one byte)."""
    can_id = EXT_ID_ALTERNATING if extended else ID_2AA
    for last in range(256):
        data = bytes([ALTERNATING_BYTE] * (CAN_MAX_LEN - 1) + [last])
        if stuff_count(frame_bitstream(can_id, data, extended)) == 0:
            return frame_bits(can_id, data, extended)
    raise AssertionError("no stuff-free frame found")


@pytest.mark.parametrize("intermission", [True, False])
def test_unstuffed_lengths_equal_kernel(intermission: bool) -> None:
    """Frames without dynamic stuff bits are exactly the kernel's no-bitstuffing lengths."""
    drop = 0 if intermission else K_CAN_INTERMISSION_BITS
    for eff in (False, True):
        kernel = _kernel_can_frame_bits(False, eff, False, intermission, CAN_MAX_LEN)
        assert _zero_stuff_classic(eff) - drop == kernel
        can_id = EXT_ID_ALTERNATING if eff else ID_2AA
        for n in REF_FD_LENGTHS:
            fd = frame_bits_fd(can_id, bytes([ALTERNATING_BYTE] * n), eff)
            ref, stream = _reference_fd(can_id, bytes([ALTERNATING_BYTE] * n), eff, True, False, 0)
            assert fd == ref
            assert not any(kind == DYNAMIC for _, _, kind in stream)
            assert fd.total_bits - drop == _kernel_can_frame_bits(True, eff, False, intermission, n)
    # CAN_FRAME_LEN_MAX / CANFD_FRAME_LEN_MAX (bytes, rounded up, with intermission)
    assert _div_round_up(_zero_stuff_classic(True), BITS_PER_BYTE) == K_CAN_FRAME_LEN_MAX
    longest_unstuffed = frame_bits_fd(
        EXT_ID_ALTERNATING, bytes([ALTERNATING_BYTE] * CANFD_MAX_LEN), True
    ).total_bits
    assert _div_round_up(longest_unstuffed, BITS_PER_BYTE) == K_CANFD_FRAME_LEN_MAX
