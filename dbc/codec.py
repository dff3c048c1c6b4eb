"""Encode and check frames of the ICD: the only place that turns signals into bytes and back.

Out (:class:`Encoder`): a message name and physical signal values in the DBC's units ->
an 8-byte payload with alive counter and CRC (see :mod:`dbc.e2e`).
In (:class:`FrameChecker`): a received ``can.Message`` -> decoded physical signals, or a
rejection counted under one cause of :class:`Reject`. Checks, in order: frame kind (error /
remote), known ID, DLC, CRC, alive counter (a repeat is rejected; a jump is accepted and
its missing frames counted as ``gaps``), signal ranges from the DBC. Freshness depends on
the receiver's notion of time, so the receiver calls :meth:`FrameChecker.reject` with
``Reject.STALE`` itself. Nothing here raises on bad input: bad frames are counted.

Scaling, IDs and ranges come only from the database passed in; the bits are packed and
unpacked by :class:`dbc.layout.FrameLayout`, compiled once per message from it.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import can
from cantools.database.can import Database, Message

from dbc import e2e
from dbc.errors import IcdError
from dbc.layout import FrameLayout

E2E_DATA_ID_ATTRIBUTE = "E2EDataID"
BITRATE_ATTRIBUTE = "Baudrate"  # BA_DEF_: default, minimum and maximum bitrate [bit/s]
RANGE_TOLERANCE = 1e-9  # relative slack on DBC min/max for float round-off


class Reject(str, Enum):
    """Why a received frame was not used."""

    ERROR_FRAME = "error_frame"
    REMOTE_FRAME = "remote_frame"
    UNKNOWN_ID = "unknown_id"
    DLC = "dlc"
    CRC = "crc"
    COUNTER = "counter"  # repeated or invalid (15) alive counter
    RANGE = "range"
    STALE = "stale"
    UNEXPECTED = "unexpected"  # one of this node's own messages, sent by another node


def data_id(message: Message) -> int:
    """The E2E data ID of ``message`` from the DBC attribute ``E2EDataID``."""
    try:
        return int(message.dbc.attributes[E2E_DATA_ID_ATTRIBUTE].value)  # type: ignore[union-attr]
    except (AttributeError, KeyError) as exc:
        raise IcdError(f"message {message.name} has no {E2E_DATA_ID_ATTRIBUTE} attribute") from exc


def cycle_time_ns(db: Database, name: str) -> int:
    """The DBC cycle time (``GenMsgCycleTime``) of message ``name`` in nanoseconds."""
    ms = db.get_message_by_name(name).cycle_time
    if not ms:
        raise IcdError(f"message {name} has no GenMsgCycleTime")
    return int(ms) * 1_000_000


def bitrate_bps(db: Database) -> int:
    """The bus's bitrate [bit/s]: the DBC's ``Baudrate`` attribute value."""
    try:
        return int(str(db.dbc.attributes[BITRATE_ATTRIBUTE].value))  # type: ignore[union-attr]
    except (AttributeError, KeyError, TypeError, ValueError) as exc:
        raise IcdError(f"the DBC has no usable {BITRATE_ATTRIBUTE} attribute ({exc})") from exc


def bitrate_range_bps(db: Database) -> tuple[int, int]:
    """(minimum, maximum) bitrate [bit/s] of the DBC's ``Baudrate`` definition."""
    try:
        a = db.dbc.attribute_definitions[BITRATE_ATTRIBUTE]  # type: ignore[union-attr]
        return int(str(a.minimum)), int(str(a.maximum))
    except (AttributeError, KeyError, TypeError, ValueError) as exc:
        raise IcdError(f"the DBC has no usable {BITRATE_ATTRIBUTE} definition ({exc})") from exc


def _range_checks(m: Message) -> list[tuple[str, float, float]]:
    """(signal, min - slack, max + slack) for the signals whose raw range can leave the DBC range.

    A signal whose every raw value maps inside [minimum, maximum] (e.g. a 1-bit flag with
    range 0..1) needs no check on receipt, which keeps wide status frames cheap.
    """
    out = []
    for s in m.signals:
        if s.minimum is None or s.maximum is None:
            continue
        lo, hi = float(s.minimum), float(s.maximum)
        raw_lo = -(1 << (s.length - 1)) if s.is_signed else 0
        raw_hi = (1 << (s.length - 1)) - 1 if s.is_signed else (1 << s.length) - 1
        phys = sorted((raw_lo * s.scale + s.offset, raw_hi * s.scale + s.offset))
        slack = RANGE_TOLERANCE * max(1.0, abs(lo), abs(hi))
        if phys[0] < lo - slack or phys[1] > hi + slack:
            out.append((s.name, lo - slack, hi + slack))
    return out


class Encoder:
    """Encodes messages of one sender, keeping one alive counter per message."""

    def __init__(self, db: Database) -> None:
        self._db = db
        self._by_name: dict[str, tuple[Message, int, FrameLayout]] = {
            m.name: (m, data_id(m), FrameLayout(m)) for m in db.messages
        }
        self._counters: dict[str, int] = {}

    def frame_id(self, name: str) -> int:
        """The CAN ID of message ``name``."""
        return self._lookup(name)[0].frame_id

    def _lookup(self, name: str) -> tuple[Message, int, FrameLayout]:
        try:
            return self._by_name[name]
        except KeyError:
            raise IcdError(f"no message {name!r} in the DBC") from None

    def encode(self, name: str, signals: dict[str, float | int],
               counter: int | None = None) -> bytearray:
        """Payload of ``name`` with ``signals`` (physical units), counter and CRC.

        ``counter`` defaults to this encoder's next alive counter for ``name``; an explicit
        one (for a sender resuming someone else's sequence) also becomes the new last value.
        """
        _message, did, layout = self._lookup(name)
        if counter is None:
            counter = (self._counters.get(name, -1) + 1) % e2e.COUNTER_MODULUS
        elif not 0 <= counter < e2e.COUNTER_MODULUS:
            raise IcdError(
                f"alive counter {counter} of {name}: expected 0..{e2e.COUNTER_MODULUS - 1}"
            )
        values: dict[str, Any] = {"CRC": 0, "AliveCounter": counter}
        values.update(signals)
        payload = layout.pack(values, signals)
        self._counters[name] = counter  # only once it is encoded: a bad value sends nothing
        return e2e.protect(did, payload, counter)

    def message(
        self, name: str, signals: dict[str, float | int], timestamp: float = 0.0
    ) -> can.Message:
        """A ``can.Message`` of ``name`` carrying ``signals``."""
        message = self._lookup(name)[0]
        return can.Message(
            arbitration_id=message.frame_id,
            is_extended_id=message.is_extended_frame,
            data=self.encode(name, signals),
            timestamp=timestamp,
        )


@dataclass
class Decoded:
    """A frame that passed every check."""

    name: str
    signals: dict[str, float]
    counter: int
    gap: int  # frames missed before this one according to the alive counter


@dataclass
class FrameStats:
    """Per-message receive statistics."""

    received: int = 0
    accepted: int = 0
    gaps: int = 0
    rejected: dict[str, int] = field(default_factory=lambda: defaultdict(int))


class FrameChecker:
    """Checks and decodes received frames, counting rejects by cause per message."""

    def __init__(self, db: Database, accept: frozenset[str] | None = None,
                 own: frozenset[str] = frozenset()) -> None:
        """``accept``: names this receiver consumes; other known frames are ignored, not counted.

        ``own``: names this node sends itself. Receiving one means another node on the bus
        sends them too (a second bench, a second flight software): counted as UNEXPECTED.
        """
        self._by_id: dict[int, tuple[Message, int, list[tuple[str, float, float]], FrameLayout]]
        self._by_id = {}
        for m in db.messages:
            self._by_id[m.frame_id] = (m, data_id(m), _range_checks(m), FrameLayout(m))
        self._accept = accept
        self._own = own
        self._last_counter: dict[int, int] = {}
        self.stats: dict[str, FrameStats] = defaultdict(FrameStats)

    def reject(self, name: str, cause: Reject) -> None:
        """Count a rejection of ``name`` for ``cause`` (used by receivers for STALE)."""
        self.stats[name].rejected[cause.value] += 1

    def check(self, msg: can.Message) -> Decoded | None:
        """Decoded signals if ``msg`` passes every check, else None (and the cause is counted)."""
        if msg.is_error_frame:
            self._count_reject("error_frame", Reject.ERROR_FRAME)
            return None
        entry = self._by_id.get(msg.arbitration_id)
        if entry is None or msg.is_extended_id:
            self._count_reject(f"0x{msg.arbitration_id:03X}", Reject.UNKNOWN_ID)
            return None
        message, did, limits, layout = entry
        name = message.name
        if self._accept is not None and name not in self._accept:
            if name in self._own:
                self._count_reject(name, Reject.UNEXPECTED)
            return None
        if msg.is_remote_frame:
            self._count_reject(name, Reject.REMOTE_FRAME)
            return None
        data = msg.data
        if msg.dlc != message.length or len(data) != message.length:
            self._count_reject(name, Reject.DLC)
            return None
        if not e2e.crc_ok(did, data):
            self._count_reject(name, Reject.CRC)
            return None
        counter = e2e.counter_of(data)
        last = self._last_counter.get(msg.arbitration_id)
        if counter >= e2e.COUNTER_MODULUS:
            self._count_reject(name, Reject.COUNTER)
            return None
        gap = 0
        if last is not None:
            delta = e2e.counter_delta(last, counter)
            if delta == 0:
                self._count_reject(name, Reject.COUNTER)
                return None
            gap = delta - 1
        signals = layout.unpack(data)
        for sig_name, lo, hi in limits:
            v = signals[sig_name]
            if v < lo or v > hi:
                self._count_reject(name, Reject.RANGE)
                self._last_counter[msg.arbitration_id] = counter
                return None
        self._last_counter[msg.arbitration_id] = counter
        st = self.stats[name]
        st.received += 1
        st.accepted += 1
        st.gaps += gap
        return Decoded(name, signals, counter, gap)

    def _count_reject(self, name: str, cause: Reject) -> None:
        st = self.stats[name]
        st.received += 1
        st.rejected[cause.value] += 1

    def summary(self) -> dict[str, dict[str, Any]]:
        """Plain-dict statistics: per message received, accepted, gaps and rejected by cause."""
        return {
            name: {
                "received": s.received,
                "accepted": s.accepted,
                "gaps": s.gaps,
                "rejected": dict(sorted(s.rejected.items())),
            }
            for name, s in sorted(self.stats.items())
        }
