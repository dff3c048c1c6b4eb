"""The station's fault bookkeeping: scheduled and live faults, started and ended on time.

In: the scenario's ``[[faults]]`` (:class:`~bench.station.faults.FaultSpec`, sorted by start
time), live fault commands (FAULT_CMD signals, decoded), the time ``t_ns`` of each call.
Out: the physical effect of thruster and sensor faults on the plant (valve and sensor
fault state), the list of active faults (bus faults among them are read by the wire, which
applies them to frames), one record per fault for ``summary.json`` and the events that
say what happened (``fault_injected``, ``fault_cleared``, ``fault_cmd_rejected``), appended
to the caller's list as ``(t_ns, name, fields)``.

A fault with ``duration_s`` > 0 ends at start + duration; ``bus_off`` without a duration
ends after the bus's recovery time (``bus_off_recovery_ns``, 128 x 11 recessive bits;
the wire holds the node's frames until then). Bus faults that need the modelled bus
(``delay``, ``link_error``, ``bus_off``, ``babbling``) are recorded as not applied in a
run without one (realtime). A live command that cannot be applied (unknown kind, target
out of range, nothing to clear, the same fault already active) is refused: recorded with
``applied: false`` and its reason, and acknowledged as rejected in BENCH_STATUS.

Pure: no clock, socket or file; time is an argument.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bench.station.faults import BUS_KINDS, REALTIME_BUS_KINDS, FaultSpec, fault_from_command
from bench.station.plant import Plant
from dbc.faults import BUS_OFF
from dbc.icd import Icd

NS_PER_S = 1_000_000_000
STEP_NS = 1_000_000  # the plant's integration step (bench.station.plant.STEP_NS)
FAULT_CMD_SOURCE = "FAULT_CMD"
Event = tuple[int, str, dict[str, Any]]


def _step_ceil(t_ns: int) -> int:
    """``t_ns`` rounded up to the integration grid."""
    return -(-t_ns // STEP_NS) * STEP_NS


def _same_target(a: FaultSpec, b: FaultSpec) -> bool:
    return (a.kind, a.thruster, a.message, a.node) == (b.kind, b.thruster, b.message, b.node)


class FaultBook:
    """Pending, active and ended faults of one run (see the module docstring)."""

    def __init__(self, scheduled: tuple[FaultSpec, ...], plant: Plant, icd: Icd,
                 modelled_bus: bool, bus_off_recovery_ns: int) -> None:
        self._plant = plant
        self._icd = icd
        self._modelled_bus = modelled_bus
        self._recovery_ns = bus_off_recovery_ns
        self.pending: list[FaultSpec] = list(scheduled)
        #: (fault, end time or None), in the order they started
        self.active: list[tuple[FaultSpec, int | None]] = []
        #: one record per fault injected or refused (summary.json ``faults``)
        self.log: list[dict[str, Any]] = []
        self._records: dict[int, dict[str, Any]] = {}  # id(active fault) -> its record
        #: bus_off windows started and not yet handed to the wire: (node, from, to)
        self.bus_off_windows: list[tuple[str, int, int]] = []
        self.cmd_counter = icd.fault_cmd_counter_none  # BENCH_STATUS.FaultCmdCounter
        self.cmd_rejected = False  # BENCH_STATUS.FaultCmdRejected: the last one was refused
        self.specs: list[FaultSpec] = []  # the active faults' specs, in start order

    # -- time ---------------------------------------------------------------------
    def next_change_ns(self, after_ns: int) -> int | None:
        """The next step time (after ``after_ns``) at which a fault starts or ends."""
        nxt: int | None = None
        if self.pending:
            nxt = _step_ceil(round(self.pending[0].t_s * NS_PER_S))
        for _, t_end in self.active:
            if t_end is not None:
                c = _step_ceil(t_end)
                nxt = c if nxt is None else min(nxt, c)
        return nxt

    def due(self, t_ns: int, events: list[Event]) -> None:
        """Start the scheduled faults due at ``t_ns`` and end the expired ones."""
        while self.pending and self.pending[0].t_s * NS_PER_S <= t_ns:
            f = self.pending.pop(0)
            end = t_ns + round(f.duration_s * NS_PER_S) if f.duration_s > 0 else None
            self.start(f, t_ns, end, events)
        for item in [x for x in self.active if x[1] is not None and x[1] <= t_ns]:
            self._remove(item)
            self._end(item[0], t_ns, "duration")
            events.append((t_ns, "fault_cleared", item[0].record()))

    # -- start and end ------------------------------------------------------------
    def start(self, f: FaultSpec, t_ns: int, end_ns: int | None, events: list[Event],
              source: str = "scenario") -> None:
        """Apply ``f`` at ``t_ns`` until ``end_ns`` (None: the end of the run)."""
        rec = {**f.record(), "t_s": t_ns / NS_PER_S, "source": source}
        if f.kind in BUS_KINDS and not self._modelled_bus and f.kind not in REALTIME_BUS_KINDS:
            rec["applied"] = False
            rec["why"] = (f"{f.kind} acts on the modelled bus (lockstep runs only); in "
                          f"realtime only {', '.join(sorted(REALTIME_BUS_KINDS))} apply")
            self.log.append(rec)
            events.append((t_ns, "fault_injected", rec))
            return
        if f.thruster is not None:
            self._plant.thrusters.set_fault(f.thruster, f.kind, t_ns, **f.params)
        elif f.sensor is not None:
            self._sensor(f.sensor).set_fault(f.kind, t_ns, **f.params)
        elif f.kind == BUS_OFF and f.node is not None:
            until = end_ns if end_ns is not None else t_ns + self._recovery_ns
            self.bus_off_windows.append((f.node, t_ns, until))
            rec["until_s"] = until / NS_PER_S
            end_ns = until
        self.active.append((f, end_ns))
        self.specs.append(f)
        self._records[id(f)] = rec
        self.log.append(rec)
        events.append((t_ns, "fault_injected", rec))

    def _remove(self, item: tuple[FaultSpec, int | None]) -> None:
        self.active.remove(item)
        self.specs = [f for f, _ in self.active]

    def _end(self, f: FaultSpec, t_ns: int, by: str) -> None:
        """Undo the physical effect of ``f`` (bus faults just stop matching frames).

        Its record gets ``cleared_t_s`` and ``cleared_by`` (``duration`` or ``FAULT_CMD``).
        """
        rec = self._records.pop(id(f), None)
        if rec is not None:
            rec["cleared_t_s"], rec["cleared_by"] = t_ns / NS_PER_S, by
        if f.thruster is not None:
            self._plant.thrusters.clear_fault(f.thruster, f.kind, t_ns)
        elif f.sensor is not None:
            self._sensor(f.sensor).clear_fault(f.kind, t_ns)

    def _sensor(self, name: str) -> Any:
        p = self._plant
        return {"gyro": p.gyro, "accelerometer": p.accel, "star_tracker": p.star}[name]

    # -- live commands ------------------------------------------------------------
    def command(self, signals: Mapping[str, float], counter: int, t_ns: int,
                n_thrusters: int, events: list[Event]) -> bool:
        """A live FAULT_CMD at ``t_ns``: inject or clear; False (and recorded why) if refused."""
        self.cmd_counter = counter
        icd = self._icd
        why: str | None = None
        spec: FaultSpec | None = None
        try:
            spec = fault_from_command(dict(signals), icd, n_thrusters, t_ns / NS_PER_S)
        except ValueError as exc:  # ConfigError: a value this bench cannot apply
            why = str(exc)
        clear = int(signals["Action"]) == icd.fault_actions["clear"]
        if spec is not None:
            matching = [x for x in self.active if _same_target(x[0], spec)]
            if clear and not matching:
                why = f"{FAULT_CMD_SOURCE}: nothing to clear: no active {spec.kind} on that target"
            elif not clear and matching:
                why = f"{FAULT_CMD_SOURCE}: {spec.kind} is already active on that target"
        if why is not None or spec is None:
            self.refuse(signals, t_ns, why or "unknown", events)
            return False
        self.cmd_rejected = False
        if clear:
            for item in matching:
                self._remove(item)
                self._end(item[0], t_ns, FAULT_CMD_SOURCE)
                events.append((t_ns, "fault_cleared", {**item[0].record(),
                                                       "source": FAULT_CMD_SOURCE}))
            return True
        end = t_ns + round(spec.duration_s * NS_PER_S) if spec.duration_s > 0 else None
        self.start(spec, t_ns, end, events, source=FAULT_CMD_SOURCE)
        return True

    def refuse(self, signals: Mapping[str, float], t_ns: int, why: str,
               events: list[Event]) -> None:
        """Record a FAULT_CMD that is not applied, and acknowledge it as rejected."""
        self.cmd_rejected = True
        fields = {k: float(v) for k, v in signals.items() if k not in ("CRC", "AliveCounter")}
        code = int(signals.get("FaultType", 0))
        # the kind by name (the summary's fault lines name it), or its unknown number
        kind = self._icd.fault_kinds.get(code, f"FaultType {code}")
        self.log.append({**fields, "kind": kind, "t_s": t_ns / NS_PER_S,
                         "source": FAULT_CMD_SOURCE, "applied": False, "why": why})
        events.append((t_ns, "fault_cmd_rejected", {**fields, "why": why}))
