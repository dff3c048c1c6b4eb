"""The station: the bench's pure core, advanced by an explicit time argument.

What it owns: the plant (rigid body, valves, sensors, environment; bench.station.plant),
the faults (bench.station.fault_book), the valve watchdog and the bench's health flags.
What goes in: valve commands (command frame index, decoded THR_CMD signals, delivery time
[ns]), live fault commands (decoded FAULT_CMD signals), the flight software's liveness as
seen by the node. What comes out: the periodic sensor frames due at a time as
``(name, signals)`` records (bench.station.sampling), events ``(t_ns, name, fields)``
(captures, faults, watchdog trips), commanded valve pulses ``(t_on_s, t_off_s, thruster)``,
and the state the results room reads (true state, thrust, propellant).

Stepping: :meth:`Station.next_event_ns` says when something besides integration happens
(a telemetry or sensor tick, a fault starting or ending, the watchdog deadline);
:meth:`Station.step_to` integrates to that time (fixed 1 ms RK4 steps, DESIGN §6) and
applies what is due there. The caller (bench.node) interleaves the wire's work between
steps. Valve watchdog: no valid command for ``WATCHDOG_PERIODS`` control periods closes
every valve (event ``valve_watchdog``); the next command clears it.

No clock, socket or file is read or written here: the same inputs give the same outputs.
"""

from __future__ import annotations

import math
from typing import Any

from bench.scenario.spec import Scenario
from bench.station.fault_book import Event, FaultBook
from bench.station.plant import STEP_NS, Plant
from bench.station.sampling import SensorFrames, Signals
from dbc.icd import Icd

WATCHDOG_PERIODS = 3
NS_PER_S = 1_000_000_000
Pulse = tuple[float, float, int]  # (t_on_s, t_off_s, thruster)


class Station:
    """One vehicle on one bench (see the module docstring)."""

    def __init__(self, sc: Scenario, icd: Icd, seed: int, *, modelled_bus: bool,
                 bus_off_recovery_ns: int, telemetry_period_ns: int) -> None:
        self.sc = sc
        self.icd = icd
        self.period_ns = icd.control_period_ns
        self.n_thr = len(sc.thrusters)
        self.plant = Plant(sc, seed, icd.period_ns["IMU_RATE"], self.period_ns)
        self.frames = SensorFrames(self.plant, icd, self.n_thr, sc.rel_nav is not None)
        self.tick_ns = math.gcd(telemetry_period_ns, *self.frames.periods_ns.values())
        self.faults = FaultBook(sc.faults, self.plant, icd, modelled_bus, bus_off_recovery_ns)
        self._per_frame = icd.thrusters_per_command
        self._on_time = icd.on_time_signals
        self._health = icd.health_flags
        self.last_cmd_ns = 0
        self.watchdog_tripped = False
        self.watchdog_trips = 0
        self.fsw_silent = False  # set by the node: the flight software stopped answering
        self.second_sender = False  # set by the node: another sender of the ICD's frames
        #: mass-property events applied so far (summary.json ``events``)
        self.captures: list[dict[str, Any]] = []

    @property
    def t_ns(self) -> int:
        """The plant's time [ns]."""
        return self.plant.t_ns

    # -- stepping -----------------------------------------------------------------
    def next_event_ns(self) -> int:
        """The next time after now at which something besides integration happens."""
        t_ns = self.plant.t_ns
        nxt = (t_ns // self.tick_ns + 1) * self.tick_ns
        change = self.faults.next_change_ns(t_ns)
        if change is not None:
            nxt = min(nxt, change)
        if not self.watchdog_tripped:
            deadline = self.last_cmd_ns + WATCHDOG_PERIODS * self.period_ns
            nxt = min(nxt, deadline // STEP_NS * STEP_NS + STEP_NS)
        return max(nxt, t_ns + STEP_NS)

    def step_to(self, t_ns: int, events: list[Event]) -> None:
        """Integrate to ``t_ns`` and apply the captures, faults and watchdog due there."""
        plant = self.plant
        plant.advance_to(t_ns)
        if len(plant.applied_events) > len(self.captures):
            for t_ev, e in plant.applied_events[len(self.captures):]:
                rec = {**e.record(), "applied_t_s": t_ev / NS_PER_S}
                self.captures.append(rec)
                events.append((t_ev, "capture", rec))
        self.faults.due(t_ns, events)
        if (not self.watchdog_tripped
                and t_ns - self.last_cmd_ns > WATCHDOG_PERIODS * self.period_ns):
            plant.thrusters.close_all(t_ns)
            self.watchdog_tripped = True
            self.watchdog_trips += 1
            events.append((t_ns, "valve_watchdog", {
                "action": "all valves closed", "last_command_s": self.last_cmd_ns / NS_PER_S}))

    def frames_due(self, t_ns: int) -> list[tuple[str, Signals]]:
        """The periodic sensor and status frames due at ``t_ns`` (call after step_to)."""
        f = self.faults
        return self.frames.due(t_ns, self.health, len(f.active), f.cmd_counter, f.cmd_rejected)

    @property
    def health(self) -> int:
        """BENCH_STATUS.Health flags."""
        h = self._health
        return ((h["valve_watchdog"] if self.watchdog_tripped else 0)
                | (h["fsw_silent"] if self.fsw_silent else 0)
                | (h["second_sender"] if self.second_sender else 0))

    # -- inputs -------------------------------------------------------------------
    def command(self, frame_index: int, signals: dict[str, float], t_rx_ns: int,
                pulses: list[Pulse]) -> bool:
        """Deliver one THR_CMD frame to its valves at ``t_rx_ns``; True if any valve fires.

        Each valve that opens adds its commanded pulse to ``pulses``.
        """
        fires = False
        thrusters = self.plant.thrusters
        first = frame_index * self._per_frame
        for k in range(first, min(first + self._per_frame, self.n_thr)):
            on_ns = round(float(signals[self._on_time[k]]) * NS_PER_S)
            thrusters.command(t_rx_ns, k, on_ns)
            if on_ns > 0:
                fires = True
                pulses.append((t_rx_ns / NS_PER_S, (t_rx_ns + on_ns) / NS_PER_S, k))
        return fires

    def commanded(self, t_last_ns: int, events: list[Event]) -> None:
        """The cycle's commands were delivered, the last at ``t_last_ns``: feed the watchdog."""
        self.last_cmd_ns = t_last_ns
        if self.watchdog_tripped:
            events.append((t_last_ns, "valve_watchdog_cleared", {}))
            self.watchdog_tripped = False

    def fault_command(self, signals: dict[str, float], counter: int,
                      events: list[Event]) -> bool:
        """A live FAULT_CMD, applied now (never before a delivered command: events stay in
        time order); False if refused (recorded, and acknowledged as rejected)."""
        t_ns = max(self.plant.t_ns, self.last_cmd_ns)
        return self.faults.command(signals, counter, t_ns, self.n_thr, events)
