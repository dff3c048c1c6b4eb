"""Encode and check frames of the ICD: the only place that turns signals into bytes and back.

Out (:class:`Encoder`): a message name and physical signal values in the DBC's units ->
an 8-byte payload with alive counter and CRC (see :mod:`dbc.e2e`).
In (:class:`FrameChecker`): a received ``can.Message`` -> decoded physical signals, or a
rejection counted under one cause of :class:`Reject`. Checks, in order: error frame,
extended (29-bit) ID (the ICD has 11-bit IDs only: an extended frame with the number of a
known ID is not that message), known ID, remote frame, DLC, CRC, one of this receiver's
own messages (a well-formed frame of it that another node sends: ``unexpected``; a
malformed one is counted by its fault), alive counter (a repeat or the
"invalid" value 15 is rejected; a counter 1..3 behind the last accepted one, while that
message's stream is live, is a ``sequence`` regression; a jump forward is accepted and
its missing frames counted as ``gaps``), signal ranges from the DBC.

Two phases: :meth:`FrameChecker.inspect` checks a frame without taking it; the receiver
then decides what only it can (freshness: a command for another cycle, a SYNC from the
past) and calls :meth:`FrameChecker.accept` (the alive counter moves on, the frame counts
as accepted) or :meth:`FrameChecker.reject` with its cause. A rejected frame never moves
the counter, so it cannot make the next genuine frame look like a repeat.
:meth:`FrameChecker.check` is both phases at once, for receivers with no freshness rule.
Nothing here raises on bad input: bad frames are counted.

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
# A counter this many steps behind the last accepted one is a regression, not a jump: a
# live sender would have to lose 12 or more frames in a row to look like that.
REGRESSION_MAX_STEPS = 3
# ... while the stream is live: its last frame is at most this many of its periods old
# (after a longer silence, e.g. a restarted sender, any counter starts a new sequence).
LIVE_PERIODS = 3
NS_PER_MS = 1_000_000


class Reject(str, Enum):
    """Why a received frame was not used."""

    ERROR_FRAME = "error_frame"
    REMOTE_FRAME = "remote_frame"
    UNKNOWN_ID = "unknown_id"
    DLC = "dlc"
    CRC = "crc"
    COUNTER = "counter"  # repeated or invalid (15) alive counter
    RANGE = "range"
    SEQUENCE = "sequence"  # alive counter 1..3 behind the live stream's: a replay or a 2nd sender
    STALE = "stale"  # for another cycle, or older than what was already taken
    UNEXPECTED = "unexpected"  # one of this node's own messages, sent by another node
    EXTENDED_ID = "extended_id"  # a 29-bit ID: no message of the ICD
    SECOND_SENDER = "second_sender"  # a second, different frame of an ID for the same cycle


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
        payload = layout.pack_merged({"CRC": 0, "AliveCounter": counter}, signals)
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
    """A frame that passed every check of :meth:`FrameChecker.inspect`."""

    name: str
    signals: dict[str, float]
    counter: int
    gap: int  # frames missed before this one according to the alive counter
    frame_id: int = 0
    t_ns: int = 0  # the receiver's time of receipt, as given to inspect


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
        self._live_ns: dict[int, int] = {}
        for m in db.messages:
            self._by_id[m.frame_id] = (m, data_id(m), _range_checks(m), FrameLayout(m))
            if m.cycle_time:
                self._live_ns[m.frame_id] = LIVE_PERIODS * int(m.cycle_time) * NS_PER_MS
        self._accept = accept
        self._own = own
        self._last_counter: dict[int, int] = {}
        self._last_t_ns: dict[int, int] = {}
        self.stats: dict[str, FrameStats] = defaultdict(FrameStats)
        self.last_cause: Reject | None = None  # why the last frame inspected was rejected

    def reject(self, name: str, cause: Reject) -> None:
        """Count a frame of ``name`` rejected for ``cause`` (e.g. STALE, by the receiver)."""
        st = self.stats[name]
        st.received += 1
        st.rejected[cause.value] += 1
        self.last_cause = cause

    def check(self, msg: can.Message, t_ns: int = 0) -> Decoded | None:
        """:meth:`inspect` then :meth:`accept`: the decoded frame, or None (cause counted)."""
        d = self.inspect(msg, t_ns)
        if d is not None:
            self.accept(d)
        return d

    def accept(self, d: Decoded) -> None:
        """Take a frame :meth:`inspect` passed: its counter becomes the last one."""
        self._last_counter[d.frame_id] = d.counter
        self._last_t_ns[d.frame_id] = d.t_ns
        st = self.stats[d.name]
        st.received += 1
        st.accepted += 1
        st.gaps += d.gap

    def inspect(self, msg: can.Message, t_ns: int = 0) -> Decoded | None:
        """Decoded signals if ``msg`` passes every check (not yet taken), else None.

        ``t_ns``: the receiver's time of receipt (any consistent clock), which decides
        whether the message's stream is live for the regression check. Rejections are
        counted here, by cause (and the last one kept in :attr:`last_cause`).
        """
        self.last_cause = None
        if msg.is_error_frame:
            self.reject("error_frame", Reject.ERROR_FRAME)
            return None
        if msg.is_extended_id:
            self.reject(f"0x{msg.arbitration_id:08X}x", Reject.EXTENDED_ID)
            return None
        entry = self._by_id.get(msg.arbitration_id)
        if entry is None:
            self.reject(f"0x{msg.arbitration_id:03X}", Reject.UNKNOWN_ID)
            return None
        message, did, limits, layout = entry
        name = message.name
        own = name in self._own
        if self._accept is not None and name not in self._accept and not own:
            return None
        if msg.is_remote_frame:
            self.reject(name, Reject.REMOTE_FRAME)
            return None
        data = msg.data
        if msg.dlc != message.length or len(data) != message.length:
            self.reject(name, Reject.DLC)
            return None
        if not e2e.crc_ok(did, data):
            self.reject(name, Reject.CRC)
            return None
        if own:  # a well-formed frame of ours that we did not send: a second sender
            self.reject(name, Reject.UNEXPECTED)
            return None
        counter = e2e.counter_of(data)
        if counter >= e2e.COUNTER_MODULUS:
            self.reject(name, Reject.COUNTER)
            return None
        gap = 0
        fid = msg.arbitration_id
        last = self._last_counter.get(fid)
        if last is not None:
            delta = e2e.counter_delta(last, counter)
            if delta == 0:
                self.reject(name, Reject.COUNTER)
                return None
            live_ns = self._live_ns.get(fid)
            if (delta >= e2e.COUNTER_MODULUS - REGRESSION_MAX_STEPS and live_ns is not None
                    and t_ns - self._last_t_ns[fid] <= live_ns):
                self.reject(name, Reject.SEQUENCE)
                return None
            gap = delta - 1
        signals = layout.unpack(data)
        for sig_name, lo, hi in limits:
            v = signals[sig_name]
            if v < lo or v > hi:
                self.reject(name, Reject.RANGE)
                return None
        return Decoded(name, signals, counter, gap, fid, t_ns)

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
