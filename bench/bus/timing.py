"""Bus timing model: bit-exact frame length on the wire and non-pre-emptive arbitration by ID.

vcan and the portable bus deliver frames instantly; a real CAN bus does not. This module
gives lockstep runs a physical layer: a frame handed to the bus at ``ready_ns`` starts when
the bus is idle and it wins arbitration (lowest ID among the frames waiting), occupies the
wire for its exact length in bits / bitrate, and is received at the end of its EOF.

Frame length (classic CAN 2.0): SOF, arbitration field, control field, data, CRC-15 are
bit-stuffed (a complemented bit after five equal bits, stuff bits counting towards the
run; ISO 11898-1 §10.5); CRC delimiter, ACK slot and delimiter, EOF (7) and the
intermission (3) are not. Worst case (Davis, Burns, Bril, Lukkien 2007, eq. 1 context):
55 + 10 n bits for 11-bit IDs and 80 + 10 n for 29-bit IDs, including 3 bits intermission.

Pure functions plus one small stateful :class:`BusArbiter` with time as an argument.
"""

from __future__ import annotations

import functools
import heapq
import re
from dataclasses import dataclass

CRC15_POLY = 0x4599
STUFF_RUN = 5
UNSTUFFED_TAIL_BITS = 1 + 2 + 7 + 3  # CRC delimiter, ACK slot + delimiter, EOF, intermission
NS_PER_S = 1_000_000_000


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


@functools.lru_cache(maxsize=4096)
def _header(can_id: int, dlc: int, extended: bool, remote: bool) -> tuple[str, int]:
    """Bits SOF..DLC of a frame and the CRC-15 register after them."""
    rtr = 1 if remote else 0
    if extended:
        head = f"0{can_id >> 18:011b}11{can_id & 0x3FFFF:018b}{rtr}00{dlc:04b}"
    else:
        head = f"0{can_id:011b}{rtr}00{dlc:04b}"
    return head, crc15([int(c) for c in head])


def frame_bits(can_id: int, data: bytes, extended: bool = False, remote: bool = False) -> int:
    """Exact length on the wire in bits, including intermission.

    Same result as ``len(frame_bitstream) + stuff_count(...) + tail`` (tested against an
    independent stuffer), computed fast because the bench calls it per frame: the header
    and its CRC state are cached, data bytes go through a byte-wise CRC-15 table, and
    stuffing is counted per run of equal bits: a run of effective length E (its length,
    plus one if the previous run ended on a stuff bit, which has this run's value) gets
    E // 5 stuff bits and passes one on when E is a multiple of 5.
    """
    dlc = len(data)
    head, crc = _header(can_id, dlc, extended, remote)
    if remote or not dlc:
        bits = head + f"{crc:015b}"
    else:
        for byte in data:
            crc = ((crc << 8) & 0x7FFF) ^ _CRC15_TABLE[((crc >> 7) ^ byte) & 0xFF]
        bits = head + f"{int.from_bytes(data, 'big'):0{8 * dlc}b}" + f"{crc:015b}"
    stuff = carry = 0
    for run in _RUNS.findall(bits):
        e = len(run) + carry
        stuff += e // STUFF_RUN
        carry = 1 if e % STUFF_RUN == 0 else 0
    return len(bits) + stuff + UNSTUFFED_TAIL_BITS


def frame_bits_worst_case(dlc: int, extended: bool = False) -> int:
    """Upper bound on frame length (Davis et al. 2007): 55+10n (11-bit) or 80+10n (29-bit)."""
    return (80 if extended else 55) + 10 * dlc


def wire_time_ns(bits: int, bitrate_bps: int) -> int:
    """Time on the wire of ``bits`` at ``bitrate_bps``, in integer nanoseconds (rounded up)."""
    return -(-bits * NS_PER_S // bitrate_bps)


@dataclass(frozen=True)
class Delivery:
    """When one frame was on the wire."""

    ready_ns: int
    start_ns: int
    end_ns: int
    can_id: int
    seq: int


class BusArbiter:
    """Non-pre-emptive priority arbitration of frames handed to one bus.

    ``submit`` frames in any order, then ``resolve(until_ns)`` returns every frame that
    starts transmission before ``until_ns``, in wire order. Frames submitted later must not
    be ready earlier than the last resolved horizon (causality), else they are clamped.
    """

    def __init__(self, bitrate_bps: int) -> None:
        if bitrate_bps <= 0:
            raise ValueError(f"bitrate_bps={bitrate_bps}: must be positive")
        self.bitrate_bps = bitrate_bps
        self._busy_until_ns = 0
        self._pending: list[tuple[int, int, int, int]] = []  # (ready, id, seq, bits)
        self._seq = 0
        self.busy_ns_total = 0

    def submit(self, ready_ns: int, can_id: int, bits: int) -> int:
        """Queue a frame; returns its sequence number (to match the :class:`Delivery`)."""
        seq = self._seq
        self._seq += 1
        heapq.heappush(self._pending, (ready_ns, can_id, seq, bits))
        return seq

    def resolve(self, until_ns: int | None = None) -> list[Delivery]:
        """Deliveries of the frames that start before ``until_ns`` (all if None)."""
        out: list[Delivery] = []
        pending = self._pending
        while pending:
            t = max(self._busy_until_ns, pending[0][0])
            if until_ns is not None and t >= until_ns:
                break
            # every frame ready by t contends; lowest ID wins, then FIFO
            ready = []
            while pending and pending[0][0] <= t:
                ready.append(heapq.heappop(pending))
            ready.sort(key=lambda f: (f[1], f[2]))
            win = ready[0]
            for f in ready[1:]:
                heapq.heappush(pending, f)
            dur = wire_time_ns(win[3], self.bitrate_bps)
            end = t + dur
            self._busy_until_ns = end
            self.busy_ns_total += dur
            out.append(Delivery(win[0], t, end, win[1], win[2]))
        return out
