"""The ICD's facts as plain values, read once from the DBC: what both sides must agree on.

In: a cantools :class:`~cantools.database.can.Database` (the project's ``thruster_hil.dbc``
or another that follows its conventions). Out: an :class:`Icd`, a frozen record of frame
IDs, senders, cycle times [ns], the layout of the valve commands (which frames, how many
thrusters per frame, the on-time signal of each thruster), the widths of the cycle
counters, the value tables (flight-software modes, fault kinds, failure kinds, bench
health flags) and signal ranges.

Why: nothing outside ``dbc/`` writes an ID, a period, a counter modulus or a value-table
entry as a literal. The bench, the flight software and the operator tools build one
:class:`Icd` at start-up and read these facts from it, so a changed DBC (another period,
a fifth command frame) changes both sides at once, or fails here with an
:class:`~dbc.errors.IcdError` naming what is missing.

Conventions read from the DBC (each checked): the valve commands are the messages named
``THR_CMD_<n>``, each carrying ``Cycle``, ``ImuCounter`` and ``OnTime_T<kk>`` signals
numbered across frames in ID order; value tables (``VAL_``) name the flight-software
modes (``FSW_STATUS.Mode``), the fault kinds of ``FAULT_CMD.FaultType`` (0 = none), the
failure kinds and the "no thruster" value of ``FSW_FDIR``, the bench's health flags
(``BENCH_STATUS.Health``, one bit each) and ``FaultCmdCounter``'s "none yet" value.
Pure: no I/O beyond the database object passed in.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from dbc.errors import IcdError

if TYPE_CHECKING:  # the type only: this module reads an already loaded database
    from cantools.database.can import Database, Message

NS_PER_MS = 1_000_000
BENCH = "BENCH"  # the DBC's node names (BU_)
FSW = "FSW"
OPERATOR = "OPERATOR"
COMMAND_PREFIX = "THR_CMD_"
ON_TIME_PREFIX = "OnTime_T"
E2E_SIGNALS = ("CRC", "AliveCounter")  # in every frame (dbc.e2e), not payload
NO_FAULT_KIND = "none"  # FAULT_CMD.FaultType 0


def _value_table(m: Message, signal: str) -> dict[int, str]:
    """``VAL_`` of ``m.signal`` as {raw value: name}; IcdError when the table is missing."""
    try:
        choices = m.get_signal_by_name(signal).choices
    except KeyError as exc:
        raise IcdError(f"message {m.name} has no signal {signal}") from exc
    if not choices:
        raise IcdError(f"{m.name}.{signal} has no value table (VAL_) in the DBC")
    return {int(k): str(v) for k, v in choices.items()}


def _flags(table: Mapping[int, str], where: str) -> dict[str, int]:
    """A value table of single-bit flags as {name: bit mask} (0 = none is skipped)."""
    out = {}
    for value, name in table.items():
        if value == 0:
            continue
        if value & (value - 1):
            raise IcdError(f"{where}: value {value} ({name}) is not a single bit")
        out[name] = value
    return out


def _modulus(m: Message, signal: str) -> int:
    """Number of distinct values of an unsigned counter signal (2 ** its length)."""
    return 1 << m.get_signal_by_name(signal).length


@dataclass(frozen=True)
class Icd:
    """Facts of one DBC (see the module docstring); build with :meth:`from_database`."""

    frame_id: Mapping[str, int]
    name_by_id: Mapping[int, str]  # standard (11-bit) IDs only
    sender: Mapping[str, str]
    period_ns: Mapping[str, int]  # 0: sent on event
    signal_range: Mapping[tuple[str, str], tuple[float, float]]
    payload: Mapping[str, tuple[str, ...]]  # signal names per message, E2E ones left out
    nodes: tuple[str, ...]
    command_frames: tuple[str, ...]
    on_time_signals: tuple[str, ...]  # per thruster index
    thrusters_per_command: int
    on_time_lsb_s: float
    command_cycle_modulus: int
    sync_cycle_modulus: int
    status_cycle_modulus: int
    modes: Mapping[str, int]  # FSW_STATUS.Mode name -> value
    fault_kinds: Mapping[int, str]  # FAULT_CMD.FaultType value -> kind (0 "none" left out)
    fault_actions: Mapping[str, int]  # FAULT_CMD.Action name -> value
    failure_kinds: Mapping[int, str]  # FSW_FDIR.FailureKind value -> name
    no_failed_thruster: int  # FSW_FDIR.FailedThruster when none is isolated
    health_flags: Mapping[str, int]  # BENCH_STATUS.Health name -> bit
    fdir_flags: Mapping[str, int]  # FSW_STATUS.FdirFlags name -> bit
    sensor_flags: Mapping[str, int]  # FSW_FDIR.SensorFlags name -> bit
    fault_cmd_counter_none: int  # BENCH_STATUS.FaultCmdCounter before any FAULT_CMD

    @classmethod
    def from_database(cls, db: Database) -> Icd:
        """Read the facts of ``db``; raises IcdError naming the first missing one."""
        try:
            return cls._read(db)
        except KeyError as exc:
            raise IcdError(f"the DBC lacks {exc} (see dbc/icd.py for what both sides read)"
                           ) from exc

    @classmethod
    def _read(cls, db: Database) -> Icd:
        msgs = {m.name: m for m in db.messages}
        commands = sorted((m for m in db.messages if m.name.startswith(COMMAND_PREFIX)),
                          key=lambda m: m.frame_id)
        if not commands:
            raise IcdError(f"the DBC has no {COMMAND_PREFIX}n messages")
        on_times: list[str] = []
        per_frame = 0
        for m in commands:
            names = [s.name for s in m.signals if s.name.startswith(ON_TIME_PREFIX)]
            per_frame = per_frame or len(names)
            if len(names) != per_frame:
                raise IcdError(f"{m.name}: {len(names)} on-time signals, {per_frame} in the first")
            on_times += names
        expected = [f"{ON_TIME_PREFIX}{k:02d}" for k in range(len(on_times))]
        if on_times != expected:
            raise IcdError(f"on-time signals {on_times}: expected {expected} (thruster order)")
        first = commands[0]
        period_ms = first.cycle_time
        if not period_ms:
            raise IcdError(f"{first.name} has no GenMsgCycleTime: no control period")
        fdir = msgs["FSW_FDIR"]
        none = [v for v, n in _value_table(fdir, "FailedThruster").items() if n == NO_FAULT_KIND]
        if len(none) != 1:
            raise IcdError("FSW_FDIR.FailedThruster's value table must name one 'none' value")
        counter_none = [v for v, n in _value_table(msgs["BENCH_STATUS"],
                                                  "FaultCmdCounter").items() if n == "none"]
        if len(counter_none) != 1:
            raise IcdError("BENCH_STATUS.FaultCmdCounter's value table must name one 'none'")
        kinds = _value_table(msgs["FAULT_CMD"], "FaultType")
        if kinds.get(0) != NO_FAULT_KIND:
            raise IcdError(f"FAULT_CMD.FaultType 0 must be {NO_FAULT_KIND!r}")
        ranges = {
            (m.name, s.name): (float(s.minimum), float(s.maximum))
            for m in db.messages for s in m.signals
            if s.minimum is not None and s.maximum is not None
        }
        nodes = tuple(n.name for n in db.nodes)
        for node in (BENCH, FSW, OPERATOR):
            if node not in nodes:
                raise IcdError(f"the DBC has no node {node} (BU_)")
        return cls(
            frame_id={m.name: m.frame_id for m in db.messages},
            name_by_id={m.frame_id: m.name for m in db.messages if not m.is_extended_frame},
            sender={m.name: (m.senders[0] if m.senders else "") for m in db.messages},
            period_ns={m.name: int(m.cycle_time or 0) * NS_PER_MS for m in db.messages},
            signal_range=ranges,
            payload={m.name: tuple(s.name for s in m.signals if s.name not in E2E_SIGNALS)
                     for m in db.messages},
            nodes=nodes,
            command_frames=tuple(m.name for m in commands),
            on_time_signals=tuple(on_times),
            thrusters_per_command=per_frame,
            on_time_lsb_s=float(first.get_signal_by_name(on_times[0]).scale),
            command_cycle_modulus=_modulus(first, "Cycle"),
            sync_cycle_modulus=_modulus(msgs["SYNC"], "Cycle"),
            status_cycle_modulus=_modulus(msgs["FSW_STATUS"], "Cycle"),
            modes={n: v for v, n in _value_table(msgs["FSW_STATUS"], "Mode").items()},
            fault_kinds={v: n for v, n in kinds.items() if v != 0},
            fault_actions={n: v for v, n in _value_table(msgs["FAULT_CMD"], "Action").items()},
            failure_kinds=_value_table(fdir, "FailureKind"),
            no_failed_thruster=none[0],
            health_flags=_flags(_value_table(msgs["BENCH_STATUS"], "Health"),
                                "BENCH_STATUS.Health"),
            fault_cmd_counter_none=counter_none[0],
            fdir_flags=_flags(_value_table(msgs["FSW_STATUS"], "FdirFlags"),
                              "FSW_STATUS.FdirFlags"),
            sensor_flags=_flags(_value_table(fdir, "SensorFlags"), "FSW_FDIR.SensorFlags"),
        )

    @property
    def control_period_ns(self) -> int:
        """The control period [ns]: the valve commands' cycle time."""
        return self.period_ns[self.command_frames[0]]

    @property
    def max_thrusters(self) -> int:
        """How many thrusters the command frames can address."""
        return len(self.on_time_signals)

    def command_frames_for(self, n_thrusters: int) -> tuple[str, ...]:
        """The command frames a vehicle of ``n_thrusters`` uses (one per started group)."""
        n = -(-n_thrusters // self.thrusters_per_command)
        return self.command_frames[:n]

    def sent_by(self, node: str) -> frozenset[str]:
        """Names of the messages ``node`` sends."""
        return frozenset(n for n, s in self.sender.items() if s == node)

    def limit(self, message: str, signal: str) -> float:
        """The largest magnitude ``message.signal`` may carry (its DBC range's bound)."""
        lo, hi = self.signal_range[(message, signal)]
        return max(abs(lo), abs(hi))
