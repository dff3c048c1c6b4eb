"""The bench node: the station, the wire and the results of one run, and the one clock.

Rooms (docs/architecture.md): the station (bench.station: plant, valves, sensors, faults,
advanced by time arguments), the wire (bench.wire: bus faults, arbitration, bit-exact
timing, the receive path, the trace), the results (bench.results: telemetry, chains,
counts, summary.json). This module builds them, steps the station (sampling sensors and
telemetry on the way), hands received frames to the right room and owns the one clock;
the run loops are bench.lockstep (the bench is the time master, DESIGN §5) and
bench.realtime (paced to the wall clock).

Frames out: SYNC (lockstep), IMU_RATE, IMU_ACCEL, STR_QUAT, NAV_POS, NAV_VEL, THR_STATUS,
BENCH_STATUS (cycle times from the DBC). Frames in: the flight software's THR_CMD_n,
FSW_STATUS, FSW_ATT_EST, FSW_FDIR and the operator's FAULT_CMD, all through one receive
path (bench.wire.receipt) in both modes. Second senders: evidence from the receive path
(own messages heard, alive-counter regressions, a second command for one cycle) sets
BENCH_STATUS.Health's second-sender flag and is reported in summary.json.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import numpy as np
from cantools.database.can import Database
from mypy_extensions import mypyc_attr

from bench.lockstep import Lockstep
from bench.realtime import Realtime
from bench.results.record import RECORD_STANDARD
from bench.results.run import Results
from bench.results.telemetry import TELEMETRY_PERIOD_NS
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from bench.station.fault_book import Event
from bench.station.plant import STEP_NS
from bench.station.station import WATCHDOG_PERIODS, Station
from bench.wire.receipt import Arrival, Receipt
from bench.wire.timing.arbiter import bus_off_recovery_ns
from bench.wire.trace import TraceRecorder
from bench.wire.wire import Wire
from dbc.codec import Decoded, Encoder, FrameChecker
from dbc.errors import RunError
from dbc.icd import BENCH, FSW, Icd

NON_ICD = "non-ICD frames"  # unknown and extended IDs, error frames, in reject events
FAULT_RNG_STREAM = 0xFA  # spawn key of the wire's fault-injection random stream
STARTUP_POLL_S = 0.2
NS_PER_S = 1_000_000_000


@mypyc_attr(allow_interpreted_subclasses=True)  # tests and users pace with their own clocks
@dataclass
class Clock:
    """The bench's wall clock (the only reader of wall time in the bench)."""

    t0_ns: int = field(default_factory=time.monotonic_ns)
    wall0_s: float = field(default_factory=time.time)

    def now_ns(self) -> int:
        """Nanoseconds since the clock was made."""
        return time.monotonic_ns() - self.t0_ns

    def restart(self) -> None:
        """Make this instant the clock's zero (a realtime run starts when the flight
        software is heard, not when the bench was built)."""
        self.t0_ns = time.monotonic_ns()
        self.wall0_s = time.time()

    def from_wall_ns(self, wall_s: float) -> int:
        """A wall-clock timestamp (``time.time()`` seconds, e.g. a frame's) on this clock."""
        return round((wall_s - self.wall0_s) * NS_PER_S)


@mypyc_attr(allow_interpreted_subclasses=True)  # tests instrument it by subclassing
class BenchNode:
    """One bench run on one bus."""


    def __init__(self, sc: Scenario, db: Database, bus: can.BusABC, run_dir: Path, mode: str,
                 seed: int, bus_spec: str,
                 progress: Callable[[float, float], None] | None = None,
                 clock: Clock | None = None,
                 realtime_loop: type[Realtime] = Realtime,
                 record: str = RECORD_STANDARD) -> None:
        """``realtime_loop``: the realtime loop's class (tests instrument it by subclassing);
        ``record``: how the run folder's trace and tables are written (bench.results.record)."""
        self.sc, self.db, self.bus, self.run_dir = sc, db, bus, run_dir
        self.mode, self.seed, self.bus_spec, self.progress = mode, seed, bus_spec, progress
        self.realtime_loop = realtime_loop
        self.clock = clock or Clock()
        self.icd = icd = Icd.from_database(db)
        lockstep = mode == "lockstep"
        self.period_ns = icd.control_period_ns
        self.station = Station(sc, icd, seed, modelled_bus=lockstep,
                               bus_off_recovery_ns=bus_off_recovery_ns(sc.bus.bitrate_bps),
                               telemetry_period_ns=TELEMETRY_PERIOD_NS)
        self.plant = self.station.plant
        self.n_thr = len(sc.thrusters)
        self.cmd_frames = icd.command_frames_for(self.n_thr)
        self.trace = TraceRecorder(run_dir, self.clock.wall0_s, lockstep, record)
        rng = np.random.default_rng(np.random.SeedSequence([seed, FAULT_RNG_STREAM]))
        faults = self.station.faults

        def active() -> list[Any]:
            return faults.specs

        self.wire = Wire(bus, icd, Encoder(db), self.trace, sc.bus.bitrate_bps, rng,
                         modelled=lockstep, active_faults=active)
        checker = FrameChecker(db, accept=icd.sent_by(FSW) | icd.sent_by("OPERATOR"),
                               own=icd.sent_by(BENCH))
        self.receipt = Receipt(icd, checker, rng, self.wire.fault_counts, active)
        self.results = Results(sc, icd, run_dir, mode, seed, bus_spec, self.n_thr,
                               round(sc.valve.open_delay_s * NS_PER_S), record)
        self.lockstep_spin_s = 0.0  # poll this long before blocking (transport.lockstep)
        self.fsw_alive: Callable[[], bool] | None = None
        self.fsw_exit_ns: int | None = None  # when the flight-software process was found gone
        self._rejects_seen: set[tuple[str, str]] = set()
        self.started = False  # the run has begun (live fault commands are taken)
        self.last_sync_ns = 0  # lockstep: time of the run's last SYNC
        self._samples: list[tuple[str, dict[str, float | int]]] = []
        self._realtime_clock: Clock | None = None  # realtime: samples go out as taken
        self._fsw_heard_wall_ns: int | None = None

    @property
    def sent(self) -> dict[str, int]:
        """Frames sent per message."""
        return self.wire.sent

    @property
    def n_cmd_frames(self) -> int:
        """How many command frames answer one cycle."""
        return len(self.cmd_frames)

    # -- events and the station's steps ----------------------------------------------
    def _events(self, events: list[Event]) -> None:
        """Write the rooms' events (events.jsonl, trace.asc) and hand bus-off to the wire."""
        for t_ns, name, fields in events:
            self.trace.event(t_ns, name, **fields)
        windows = self.station.faults.bus_off_windows
        if windows:
            for node, t0, t1 in windows:
                self.wire.bus_off(node, t0, t1)
            windows.clear()

    def integrate_to(self, t_end_ns: int) -> None:
        """Advance the station to ``t_end_ns``, sampling sensors and telemetry on the way."""
        st, wire = self.station, self.wire
        while st.t_ns < t_end_ns:
            t = st.next_event_ns()
            release = wire.next_release_ns()
            if release is not None:
                t = min(t, max(-(-release // STEP_NS) * STEP_NS, st.t_ns + STEP_NS))
            t = min(t_end_ns, t)
            events: list[Event] = []
            st.step_to(t, events)
            self._events(events)
            wire.release_delayed(t)
            if t % TELEMETRY_PERIOD_NS == 0:
                self.results.telemetry.row(t, st, self.results.fsw)
            self._samples += st.frames_due(t)
            if self._samples:
                self._emit_samples(t)

    def _emit_samples(self, t_ns: int) -> None:
        """Send the samples taken at ``t_ns`` (lockstep: held for SYNC at a control instant)."""
        samples, self._samples = self._samples, []
        clock = self._realtime_clock
        if clock is not None:
            now = clock.now_ns()
            for name, signals in samples:
                self._send(name, signals, t_ns, now)
            return
        if t_ns > self.last_sync_ns:
            return  # sampled after the last SYNC of the run: that cycle never comes
        for name, signals in samples:
            self._send(name, signals, t_ns)
        if t_ns % self.period_ns:  # between control instants: out at once; at one, with SYNC
            self.wire.release()

    def _send(self, name: str, signals: dict[str, float | int], ready_ns: int,
              now_ns: int | None = None) -> None:
        msg = self.wire.send(name, signals, ready_ns, now_ns)
        if name == "IMU_RATE":
            self.results.imu_tx_ns[msg.data[1] & 0x0F] = ready_ns if now_ns is None else now_ns

    # -- frames of the flight software and the operator -------------------------------
    def _take(self, d: Decoded, events: list[Event]) -> None:
        """A frame the receive path took (not a valve command): its effect."""
        name, s = d.name, d.signals
        st, fsw = self.station, self.results.fsw
        if name == "FAULT_CMD":
            if not self.started:
                st.faults.refuse(s, 0, "FAULT_CMD: the run has not started", events)
            else:
                st.fault_command(s, d.counter, events)
            return
        now_wall = self.clock.now_ns()
        if name == "FSW_STATUS":
            heard = self._fsw_heard_wall_ns
            restart = fsw.restart_allowed(s, None if heard is None else now_wall - heard)
            if restart is False:
                fsw.refuse_restart(st.t_ns, events)
                return
            if restart:
                self.receipt.forget_commands()
            fsw.on_status(s, st.t_ns, events)
        elif name == "FSW_ATT_EST":
            q = st.plant.state
            fsw.on_estimate(s, (q[0], q[1], q[2], q[3]))
        elif name == "FSW_FDIR":
            fsw.on_fdir(s, st.t_ns, events)
        self._fsw_heard_wall_ns = now_wall

    def check_fsw_alive(self) -> None:
        """The flight-software process gone: record when; once the valve watchdog has closed
        every valve (or ``WATCHDOG_PERIODS`` + 1 periods later), end the run as a run error."""
        st = self.station
        if self.fsw_exit_ns is None:
            if self.fsw_alive is None or self.fsw_alive():
                return
            self.fsw_exit_ns = st.t_ns
            self._events([(st.t_ns, "fsw_exited", {})])
        grace_ns = (WATCHDOG_PERIODS + 1) * self.period_ns
        if st.watchdog_tripped or st.t_ns - self.fsw_exit_ns > grace_ns:
            closed = ("the valve watchdog closed every valve" if st.watchdog_tripped
                      else "its last commands had ended")
            raise RunError(f"the flight software exited during the run (found gone at "
                           f"{self.fsw_exit_ns / NS_PER_S:g} s of simulated time); {closed}")

    def note_rejects(self, arrivals: list[Arrival], events: list[Event]) -> None:
        """The first reject of each message and cause from another node is an event (the
        console names it as it starts); later ones are only counted."""
        for a in arrivals:
            if a.cause is None:
                continue
            name = a.name if a.name is not None else NON_ICD
            key = (name, a.cause.value)
            if key not in self._rejects_seen and self.icd.sender.get(name) != BENCH:
                self._rejects_seen.add(key)
                events.append((self.station.t_ns, "frames_rejected",
                               {"message": name, "cause": a.cause.value}))

    def _second_sender(self) -> None:
        """Evidence of a second sender raises BENCH_STATUS.Health's flag (once)."""
        if self.receipt.second_sender and not self.station.second_sender:
            self.station.second_sender = True
            self.trace.event(self.station.t_ns, "second_sender",
                             messages=dict(self.receipt.second_sender))

    # -- start-up ---------------------------------------------------------------------
    def wait_for_fsw(self) -> None:
        """Wait for the flight software's first valid frame (its boot heartbeat).

        Every frame heard meanwhile goes into the trace at t = 0 (as a CAN logger records
        what precedes a run), bad ones too; only a valid frame of the flight software ends
        the wait (an operator's FAULT_CMD before the run is refused, not taken for it).
        """
        clock = self.clock
        timeout_ns = round(self.sc.bus.startup_timeout_s * NS_PER_S)
        deadline = clock.now_ns() + timeout_ns
        while clock.now_ns() < deadline:
            if self.fsw_alive is not None and not self.fsw_alive():
                raise RunError("the flight-software process exited before its first frame "
                               "(see fsw.log in the run folder)")
            left_s = max(0.0, (deadline - clock.now_ns()) / NS_PER_S)
            msg = self.bus.recv(timeout=min(STARTUP_POLL_S, left_s))
            if msg is None:
                continue
            arrivals = self.receipt.receive(msg, clock.now_ns(), None)
            rejects: list[Event] = []
            self.note_rejects(arrivals, rejects)
            self._events(rejects)
            for a in arrivals:
                # bits 0: before the run, off the modelled wire (the timing analysis skips it)
                self.trace.frame(a.msg, 0, tx=False,
                                 t_rx_ns=0 if a.decoded is not None else float("nan"))
                if a.decoded is None:
                    continue
                events: list[Event] = []
                self._take(a.decoded, events)
                self._events(events)
                if self.icd.sender[a.decoded.name] == FSW:
                    return
        raise RunError(self._no_fsw_message())

    def _no_fsw_message(self) -> str:
        """Why the wait for the flight software ended without it (names what was heard)."""
        rejected = {n: r["rejected"] for n, r in self.receipt.checker.summary().items()
                    if r["rejected"] and self.icd.sender.get(n) == FSW}
        heard = "".join(f"; heard {n} but rejected it: " + ", ".join(
            f"{c} ({k})" for c, k in causes.items()) for n, causes in rejected.items())
        return (f"no flight software on bus {self.bus_spec} within "
                f"{self.sc.bus.startup_timeout_s} s (expected its FSW_STATUS heartbeat){heard}")

    # -- lockstep ---------------------------------------------------------------------
    def run_lockstep(self, duration_s: float) -> None:
        """Lockstep run of ``duration_s`` simulated seconds (bench.lockstep)."""
        Lockstep(self).run(duration_s)

    def _start(self) -> None:
        """t = 0: the faults due at once act on the first samples too; first telemetry."""
        events: list[Event] = []
        self.station.faults.due(0, events)
        self._events(events)
        self._samples += self.station.frames_due(0)
        self.results.telemetry.row(0, self.station, self.results.fsw)

    # -- realtime ---------------------------------------------------------------------
    def run_realtime(self, duration_s: float, clock: Clock | None = None) -> None:
        """Wall-clock-paced run of ``duration_s`` seconds (bench.realtime)."""
        if clock is not None:
            self.clock = clock
        self.realtime_loop(self, self.clock).run(duration_s)

    # -- results ----------------------------------------------------------------------
    def summary(self, sim_time_s: float) -> dict[str, Any]:
        """summary.json content from the bench's side (with the trace's digest)."""
        summary = self.results.summary(sim_time_s, self.station, self.wire, self.receipt)
        summary["trace_sha256"] = self.trace.digest()
        return summary

    def close(self, sim_time_s: float) -> dict[str, Any]:
        """Finish files and write summary.json; returns the summary."""
        self.trace.close()
        self.results.close()
        summary = self.summary(sim_time_s)
        write_summary(self.run_dir / "summary.json", summary)
        return summary
