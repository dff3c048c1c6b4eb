"""Worst-case response-time analysis (RTA) of periodic CAN messages.

What: the revised schedulability analysis for Controller Area Network of Davis, Burns,
Bril and Lukkien, "Controller Area Network (CAN) schedulability analysis: Refuted,
revisited and revised", Real-Time Systems 35:239-272 (2007). For each message m it gives
the worst-case response time R_m: the longest time from the event that queues an instance
of m (before its queuing jitter) to the end of that instance's frame on the wire,
assuming fixed-priority non-pre-emptive arbitration by identifier, no transmission
errors, and no internal priority inversion in the controllers (a node always offers its
highest-priority pending frame, as the arbitration model in :mod:`bench.wire.timing` does).

Inputs: :class:`CanMessageSpec` records (name, identifier, DLC, period T_m, queuing jitter
J_m, optional deadline D_m; seconds) and the bitrate (bit/s). :func:`messages_from_dbc`
builds the records from a cantools database (periodic messages only).
Outputs: :func:`response_times` returns one :class:`RtaResult` per message name, times in
seconds: C_m, B_m, the level-m busy period t_m, the number of instances Q_m, R_m, the
response time of every instance q, schedulability (R_m <= D_m, D_m = T_m by default) and
utilisations.

The recurrences, in the paper's notation (tau_bit = one bit time, hp(m) / lp(m) /
hep(m) = messages of higher / lower / higher-or-equal priority than m):

* C_m = frame_bits_worst_case(dlc) * tau_bit: 55 + 10 n bits for 11-bit identifiers,
  80 + 10 n for 29-bit, including the 3-bit intermission (worst-case bit stuffing).
* B_m = max_{k in lp(m)} C_k (0 for the lowest priority): m can be blocked by one lower-
  priority frame that won arbitration just before m was queued. This is the paper's form;
  it includes the frame's first bit, which strictly must already have been sent, so it
  is pessimistic by up to one tau_bit (kept, as the paper keeps it).
* t_m = B_m + sum_{k in hep(m)} ceil((t_m + J_k) / T_k) C_k, iterated from t_m = C_m:
  the longest level-m busy period.
* Q_m = ceil((t_m + J_m) / T_m) instances of m fall in it; each must be checked, because
  the first is not necessarily the worst (the flaw of the original 1994 analysis, which
  checked only q = 0).
* w_m(q) = B_m + q C_m + sum_{k in hp(m)} ceil((w_m(q) + J_k + tau_bit) / T_k) C_k,
  q = 0 .. Q_m - 1, iterated from w_m(q - 1) + C_m (a lower bound): the queuing delay of
  instance q; a higher-priority frame queued up to one bit time after instance q started
  its arbitration still wins it, hence the + tau_bit.
* R_m(q) = J_m + w_m(q) - q T_m + C_m and R_m = max_q R_m(q).

Source and citation note: the formulas above are those of the paper's revised analysis
(its Section 4, "revised schedulability analysis", as recalled; the transmission time,
the original analysis and the three-message counter-example are in its Section 3).
Equation numbers are deliberately not cited: they could not be checked against the
paper's text when this module was written, so sections are given from memory too.

Units and arithmetic: all internal times are integer nanoseconds, like
:class:`bench.wire.timing.arbiter.BusArbiter`: C and tau_bit are rounded up to the next ns with
:func:`bench.wire.timing.classic.wire_time_ns` (as the arbiter does), periods, jitters and
deadlines are rounded to the nearest ns. Integer arithmetic makes every fixed point exact
and every iteration terminate. Non-convergence: if the level-m utilisation
U_m = sum_{k in hep(m)} C_k / T_k is >= 1 (exact rational comparison), the busy period
is unbounded; m is then reported unschedulable with infinite busy period and R, and
``converged=False``, instead of iterating forever. Higher-priority messages whose own
level utilisation is below 1 are still analysed normally.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from bench.wire.timing.classic import NS_PER_S, frame_bits_worst_case, wire_time_ns
from dbc.errors import ConfigError

MAX_DLC = 8  # classic CAN 2.0 data length
STANDARD_ID_BITS = 11
EXTENDED_ID_BITS = 29
EXTENDED_LOW_BITS = EXTENDED_ID_BITS - STANDARD_ID_BITS  # identifier extension (18 bits)
MS_PER_S = 1000  # GenMsgCycleTime is in milliseconds
MIN_TIME_S = 1 / NS_PER_S  # periods and deadlines must be at least one ns (the time grid)
SPEC_SOURCE = "CanMessageSpec"
RTA_SOURCE = "response_times"
DBC_SOURCE = "messages_from_dbc"


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class CanMessageSpec:
    """One periodic CAN message as the analysis sees it.

    ``can_id``: 11-bit (``extended=False``) or 29-bit identifier; lower value = higher
    priority. ``dlc``: data bytes, 0..8. ``period_s``: minimum inter-arrival time T_m.
    ``jitter_s``: queuing jitter J_m (latest minus earliest queuing after the initiating
    event). ``deadline_s``: D_m, ``None`` = the period. ``node``: the sender (informative).
    """

    name: str
    can_id: int
    dlc: int
    period_s: float
    jitter_s: float = 0.0
    extended: bool = False
    node: str = ""
    deadline_s: float | None = None

    def __post_init__(self) -> None:
        src = f"{SPEC_SOURCE} {self.name!r}" if isinstance(self.name, str) else SPEC_SOURCE
        if not isinstance(self.name, str) or not self.name:
            raise ConfigError(src, "name", self.name, "a non-empty string")
        if not isinstance(self.extended, bool):
            raise ConfigError(src, "extended", self.extended, "a bool")
        id_bits = EXTENDED_ID_BITS if self.extended else STANDARD_ID_BITS
        if not _is_int(self.can_id) or not 0 <= self.can_id < (1 << id_bits):
            raise ConfigError(
                src, "can_id", self.can_id, f"an integer in [0, {(1 << id_bits) - 1}]"
            )
        if not _is_int(self.dlc) or not 0 <= self.dlc <= MAX_DLC:
            raise ConfigError(src, "dlc", self.dlc, f"an integer in [0, {MAX_DLC}]")
        if (
            not _is_real(self.period_s)
            or not math.isfinite(self.period_s)
            or self.period_s < MIN_TIME_S
        ):
            raise ConfigError(src, "period_s", self.period_s, f"a finite number >= {MIN_TIME_S}")
        if not _is_real(self.jitter_s) or not math.isfinite(self.jitter_s) or self.jitter_s < 0:
            raise ConfigError(src, "jitter_s", self.jitter_s, "a finite number >= 0")
        if self.deadline_s is not None and (
            not _is_real(self.deadline_s)
            or not math.isfinite(self.deadline_s)
            or self.deadline_s < MIN_TIME_S
        ):
            raise ConfigError(
                src, "deadline_s", self.deadline_s, f"None or a finite number >= {MIN_TIME_S}"
            )
        if not isinstance(self.node, str):
            raise ConfigError(src, "node", self.node, "a string")

    @property
    def effective_deadline_s(self) -> float:
        """D_m: ``deadline_s``, or the period when it is None."""
        return self.period_s if self.deadline_s is None else self.deadline_s

    @property
    def priority_key(self) -> tuple[int, int, int]:
        """Arbitration order (smaller wins): base identifier, then standard before extended
        (SRR recessive against a dominant RTR), then the 18-bit identifier extension."""
        if self.extended:
            return (
                self.can_id >> EXTENDED_LOW_BITS,
                1,
                self.can_id & ((1 << EXTENDED_LOW_BITS) - 1),
            )
        return (self.can_id, 0, 0)


@dataclass(frozen=True)
class RtaResult:
    """Analysis of one message; times in seconds (``math.inf`` when not converged)."""

    name: str
    can_id: int
    frame_bits: int  # worst-case frame length on the wire, bits, incl. intermission
    transmission_time_s: float  # C_m
    blocking_s: float  # B_m
    busy_period_s: float  # t_m
    instances: int  # Q_m (0 when not converged)
    response_time_s: float  # R_m = max_q R_m(q)
    worst_instance: int  # the q attaining R_m (-1 when not converged)
    instance_response_times_s: tuple[float, ...]  # R_m(q), q = 0 .. Q_m - 1
    deadline_s: float  # D_m
    schedulable: bool  # converged and R_m <= D_m
    converged: bool  # False when the level-m utilisation is >= 1
    utilisation: float  # C_m / T_m
    level_utilisation: float  # sum over hep(m) of C_k / T_k
    bus_utilisation: float  # sum over all messages of C_k / T_k


@dataclass(frozen=True)
class _Timed:
    """A spec with its times on the integer-ns grid."""

    spec: CanMessageSpec
    bits: int
    c_ns: int
    t_ns: int
    j_ns: int
    d_ns: int


def _to_ns(seconds: float) -> int:
    return round(seconds * NS_PER_S)


def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)


def _check_bitrate(bitrate_bps: object, source: str) -> int:
    if isinstance(bitrate_bps, bool) or not isinstance(bitrate_bps, int) or bitrate_bps <= 0:
        raise ConfigError(source, "bitrate_bps", bitrate_bps, "a positive integer (bit/s)")
    return bitrate_bps


def _timed(messages: Iterable[CanMessageSpec], bitrate_bps: int) -> list[_Timed]:
    """Specs on the ns grid, highest priority first; checks names and identifiers."""
    out: list[_Timed] = []
    names: set[str] = set()
    keys: dict[tuple[int, int, int], str] = {}
    for spec in messages:
        if not isinstance(spec, CanMessageSpec):
            raise ConfigError(RTA_SOURCE, "messages", spec, "CanMessageSpec records")
        if spec.name in names:
            raise ConfigError(RTA_SOURCE, "name", spec.name, "unique message names")
        if spec.priority_key in keys:
            raise ConfigError(
                RTA_SOURCE,
                f"{spec.name}.can_id",
                spec.can_id,
                f"an identifier unique on the bus (also used by {keys[spec.priority_key]!r})",
            )
        names.add(spec.name)
        keys[spec.priority_key] = spec.name
        bits = frame_bits_worst_case(spec.dlc, spec.extended)
        out.append(
            _Timed(
                spec=spec,
                bits=bits,
                c_ns=wire_time_ns(bits, bitrate_bps),
                t_ns=_to_ns(spec.period_s),
                j_ns=_to_ns(spec.jitter_s),
                d_ns=_to_ns(spec.effective_deadline_s),
            )
        )
    out.sort(key=lambda m: m.spec.priority_key)
    return out


def _utilisation(msgs: Sequence[_Timed]) -> Fraction:
    return sum((Fraction(m.c_ns, m.t_ns) for m in msgs), Fraction(0))


def _busy_period_ns(b_ns: int, hep: Sequence[_Timed], c_m_ns: int) -> int:
    """t_m = B_m + sum_{hep(m)} ceil((t_m + J_k) / T_k) C_k, from t_m = C_m.

    Terminates because the caller has checked the level-m utilisation is < 1."""
    t = c_m_ns
    while True:
        nxt = b_ns + sum(_ceil_div(t + k.j_ns, k.t_ns) * k.c_ns for k in hep)
        if nxt == t:
            return t
        t = nxt


def _queuing_delay_ns(start_ns: int, base_ns: int, hp: Sequence[_Timed], tau_bit_ns: int) -> int:
    """w = base + sum_{hp(m)} ceil((w + J_k + tau_bit) / T_k) C_k, from w = start."""
    w = start_ns
    while True:
        nxt = base_ns + sum(_ceil_div(w + k.j_ns + tau_bit_ns, k.t_ns) * k.c_ns for k in hp)
        if nxt == w:
            return w
        w = nxt


def bus_utilisation(messages: Iterable[CanMessageSpec], bitrate_bps: int) -> float:
    """Total bus utilisation sum C_k / T_k with worst-case frame lengths (dimensionless)."""
    bitrate = _check_bitrate(bitrate_bps, RTA_SOURCE)
    return float(_utilisation(_timed(messages, bitrate)))


def response_times(messages: Iterable[CanMessageSpec], bitrate_bps: int) -> dict[str, RtaResult]:
    """Worst-case response time of every message (Davis et al. 2007, revised analysis).

    ``messages``: specs with unique names and unique identifiers, in any order.
    ``bitrate_bps``: the bus bitrate (bit/s). Returns ``{name: RtaResult}`` in priority
    order (highest first). Raises :class:`ConfigError` on invalid input; an overloaded
    bus is not an error but a result with ``converged=False``.
    """
    bitrate = _check_bitrate(bitrate_bps, RTA_SOURCE)
    msgs = _timed(messages, bitrate)
    tau_bit_ns = wire_time_ns(1, bitrate)
    u_bus = float(_utilisation(msgs))
    results: dict[str, RtaResult] = {}
    for i, m in enumerate(msgs):
        hp, hep, lp = msgs[:i], msgs[: i + 1], msgs[i + 1 :]
        b_ns = max((k.c_ns for k in lp), default=0)
        u_level = _utilisation(hep)
        common: dict[str, Any] = {
            "name": m.spec.name,
            "can_id": m.spec.can_id,
            "frame_bits": m.bits,
            "transmission_time_s": m.c_ns / NS_PER_S,
            "blocking_s": b_ns / NS_PER_S,
            "deadline_s": m.d_ns / NS_PER_S,
            "utilisation": m.c_ns / m.t_ns,
            "level_utilisation": float(u_level),
            "bus_utilisation": u_bus,
        }
        if u_level >= 1:
            results[m.spec.name] = RtaResult(
                **common,
                busy_period_s=math.inf,
                instances=0,
                response_time_s=math.inf,
                worst_instance=-1,
                instance_response_times_s=(),
                schedulable=False,
                converged=False,
            )
            continue
        t_ns = _busy_period_ns(b_ns, hep, m.c_ns)
        q_count = _ceil_div(t_ns + m.j_ns, m.t_ns)
        per_instance_ns: list[int] = []
        w_ns = b_ns - m.c_ns  # so that the first start value w(-1) + C_m is B_m
        for q in range(q_count):
            w_ns = _queuing_delay_ns(w_ns + m.c_ns, b_ns + q * m.c_ns, hp, tau_bit_ns)
            per_instance_ns.append(m.j_ns + w_ns - q * m.t_ns + m.c_ns)
        r_ns = max(per_instance_ns)
        results[m.spec.name] = RtaResult(
            **common,
            busy_period_s=t_ns / NS_PER_S,
            instances=q_count,
            response_time_s=r_ns / NS_PER_S,
            worst_instance=per_instance_ns.index(r_ns),
            instance_response_times_s=tuple(r / NS_PER_S for r in per_instance_ns),
            schedulable=r_ns <= m.d_ns,
            converged=True,
        )
    return results


def messages_from_dbc(
    db: Any, bitrate_bps: int, jitter_s: Mapping[str, float] | None = None
) -> list[CanMessageSpec]:
    """Specs for the periodic messages of a cantools CAN database.

    ``db``: a ``cantools.database.can.Database``. A message is periodic when its cycle time
    (``GenMsgCycleTime``, ms) is set and > 0; event-driven messages are left out (the
    analysis needs a minimum inter-arrival time). ``dlc`` = the message length in bytes,
    ``node`` = its first sender ("" if none), deadline = period. ``jitter_s``: queuing
    jitter per message name (s), 0 for names not given; a name that is not a periodic
    message of ``db`` is an error (it would silently not be analysed). ``bitrate_bps`` is
    only validated: the specs do not depend on it (``response_times`` takes it again).
    """
    _check_bitrate(bitrate_bps, DBC_SOURCE)
    jitters = dict(jitter_s or {})
    specs: list[CanMessageSpec] = []
    for msg in db.messages:
        cycle_ms = msg.cycle_time
        if cycle_ms is None or cycle_ms <= 0:
            continue
        specs.append(
            CanMessageSpec(
                name=msg.name,
                can_id=msg.frame_id,
                dlc=msg.length,
                period_s=cycle_ms / MS_PER_S,
                jitter_s=jitters.pop(msg.name, 0.0),
                extended=bool(msg.is_extended_frame),
                node=msg.senders[0] if msg.senders else "",
            )
        )
    if jitters:
        raise ConfigError(
            DBC_SOURCE, "jitter_s", sorted(jitters), "names of periodic messages in the DBC"
        )
    return specs
