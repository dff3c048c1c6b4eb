"""Priority arbitration of frames on one bus, with link errors and bus-off.

In: frames submitted with the instant they are ready (ns), their identifier and their
length (classic bits from :func:`bench.wire.timing.classic.frame_bits` or
:class:`~bench.wire.timing.fd.FdBits`), optionally failed attempts and a transmitting
node; bus-off windows per node. Out: a :class:`Delivery` per frame, in wire order, saying
when it (and each failed attempt) was on the wire, and the bus time used and lost.

Units. Bitrates in bit/s, times in integer nanoseconds (``*_ns``), a wire time rounded up
to the next ns once per frame (or per failed attempt).

Arbitration. A frame handed to the bus at ``ready_ns`` starts when the bus is idle and it
wins arbitration (lowest ID among the frames waiting, then the first submitted), and
occupies the wire for its exact length in bits / bitrate; arbitration is not pre-empted.

Errors and bus-off. :data:`ERROR_FRAME_BITS` (20) is the worst-case error frame: error
flag 6, superposition of the other nodes' flags up to 6 more, delimiter 8; it is followed
by the 3-bit intermission. A failed attempt is assumed to be detected at the end of the
frame, the error flag starting at the ACK delimiter (an ACK error seen by the
transmitter): it costs the frame's bits up to the ACK slot, the error frame and the
intermission. Error counters are not modelled: failures and bus-off periods are given.
Bus-off recovery takes 128 occurrences of 11 consecutive recessive bits (1408 bit times,
ISO 11898-1:2015 §12.1.4.2 fault confinement rules), assuming a quiet bus.

Sources: ISO 11898-1:2015 (error frames §10.4.4, fault confinement §12.1.4).
"""

from __future__ import annotations

import heapq
from operator import itemgetter
from typing import Final, final

from bench.wire.timing.classic import (
    ACK_DELIMITER_BITS,
    EOF_BITS,
    INTERMISSION_BITS,
    NS_PER_S,
    wire_time_ns,
)
from bench.wire.timing.fd import FdBits, wire_time_fd_ns

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


@final
class Delivery:
    """When one frame was on the wire.

    ``start_ns``/``end_ns`` bound the successful attempt (``end_ns`` includes the
    intermission). ``failed_ns`` lists the [start, end) of each failed attempt, error frame
    and intermission included; ``attempts`` = len(failed_ns) + 1.

    A plain class with ``Final`` fields, not a frozen dataclass: one is made per frame on
    the wire, and a frozen dataclass's generated ``__init__`` (``object.__setattr__`` per
    field, interpreted even in the compiled module) cost ~2.7 us each, ~40x this one.
    Equal by value, like the dataclass it replaces.
    """

    def __init__(self, ready_ns: int, start_ns: int, end_ns: int, can_id: int, seq: int,
                 attempts: int = 1, node: str = "",
                 failed_ns: tuple[tuple[int, int], ...] = ()) -> None:
        self.ready_ns: Final = ready_ns
        self.start_ns: Final = start_ns
        self.end_ns: Final = end_ns
        self.can_id: Final = can_id
        self.seq: Final = seq
        self.attempts: Final = attempts
        self.node: Final = node
        self.failed_ns: Final = failed_ns

    def _key(self) -> tuple[int, int, int, int, int, int, str, tuple[tuple[int, int], ...]]:
        return (self.ready_ns, self.start_ns, self.end_ns, self.can_id, self.seq,
                self.attempts, self.node, self.failed_ns)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Delivery) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return (f"Delivery(ready_ns={self.ready_ns}, start_ns={self.start_ns}, "
                f"end_ns={self.end_ns}, can_id={self.can_id}, seq={self.seq}, "
                f"attempts={self.attempts}, node={self.node!r}, failed_ns={self.failed_ns})")

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
