"""The bench node: the lockstep and realtime loops around the station, the wire and the results.

Rooms (docs/architecture.md): the station (bench.station: plant, valves, sensors, faults,
advanced by time arguments), the wire (bench.wire: bus faults, arbitration, bit-exact
timing, the receive path, the trace), the results (bench.results: telemetry, chains,
counts, summary.json). This module only runs the loops and owns the one clock.

Frames out: SYNC (lockstep), IMU_RATE, IMU_ACCEL, STR_QUAT, NAV_POS, NAV_VEL, THR_STATUS,
BENCH_STATUS (cycle times from the DBC). Frames in: the flight software's THR_CMD_n,
FSW_STATUS, FSW_ATT_EST, FSW_FDIR and the operator's FAULT_CMD, all through one receive
path (bench.wire.receipt) in both modes.

Lockstep (DESIGN §5): per control cycle k the bench sends every sensor sample due in
(t_{k-1}, t_k] with SYNC(k) (one burst), waits for the flight software's THR_CMD frames of
cycle k, delivers them to the valves at the time the bus model says they arrive
(response delay, arbitration, exact frame length) and integrates to t_{k+1}; the run
files' text is formatted while the flight software computes. A missing answer within
``stall_timeout_s`` of wall time is a counted stall (naming the missing frames); after
``SILENT_AFTER_STALLS`` stalls in a row the flight software is declared silent and the
bench stops waiting (never hangs). Realtime: the plant is paced to the clock, sensors go
out when due and commands are applied when they arrive; latencies are measured.

Second senders: evidence from the receive path (own messages heard, alive-counter
regressions, a second command for one cycle) sets BENCH_STATUS.Health's second-sender
flag and is reported in summary.json (bench.results).
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

from bench.results.run import Results
from bench.results.telemetry import TELEMETRY_PERIOD_NS
from bench.results.writers import write_summary
from bench.scenario.spec import Scenario
from bench.station.fault_book import Event
from bench.station.plant import STEP_NS
from bench.station.station import Pulse, Station
from bench.wire.receipt import Arrival, Receipt
from bench.wire.timing.arbiter import bus_off_recovery_ns
from bench.wire.timing.classic import frame_bits
from bench.wire.trace import TraceRecorder
from bench.wire.wire import Wire
from dbc.codec import Decoded, Encoder, FrameChecker
from dbc.errors import RunError
from dbc.icd import BENCH, FSW, Icd
from transport.lockstep import recv_spinning

FAULT_RNG_STREAM = 0xFA  # spawn key of the wire's fault-injection random stream
STARTUP_POLL_S = 0.2
FLUSH_EVERY_CYCLES = 5  # run files go to disk this often (and the progress line is updated)
SILENT_AFTER_STALLS = 3
RT_FRAMES_PER_PASS = 64  # realtime: frames read between two steps toward the wall clock
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

    def from_wall_ns(self, wall_s: float) -> int:
        """A wall-clock timestamp (``time.time()`` seconds, e.g. a frame's) on this clock."""
        return round((wall_s - self.wall0_s) * NS_PER_S)


@mypyc_attr(allow_interpreted_subclasses=True)  # tests instrument it by subclassing
class BenchNode:
    """One bench run on one bus."""

    def __init__(self, sc: Scenario, db: Database, bus: can.BusABC, run_dir: Path, mode: str,
                 seed: int, bus_spec: str,
                 progress: Callable[[float, float], None] | None = None,
                 clock: Clock | None = None) -> None:
        self.sc, self.db, self.bus, self.run_dir = sc, db, bus, run_dir
        self.mode, self.seed, self.bus_spec, self.progress = mode, seed, bus_spec, progress
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
        self.trace = TraceRecorder(run_dir, self.clock.wall0_s, lockstep)
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
                               round(sc.valve.open_delay_s * NS_PER_S))
        self.lockstep_spin_s = 0.0  # poll this long before blocking (transport.lockstep)
        self.fsw_alive: Callable[[], bool] | None = None
        self.started = False  # the run has begun (live fault commands are taken)
        self.consecutive_stalls = 0
        self.last_sync_ns = 0  # lockstep: time of the run's last SYNC
        self._samples: list[tuple[str, dict[str, float | int]]] = []
        self._realtime_clock: Clock | None = None
        self._rt_fire_ns: int | None = None
        self._rt_end_ns = 0
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
            for a in self.receipt.receive(msg, 0, None):
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
        """Lockstep run of ``duration_s`` simulated seconds."""
        period = self.period_ns
        n_cycles = round(duration_s * NS_PER_S / period)
        self.last_sync_ns = (n_cycles - 1) * period
        delay_ns = round(self.sc.bus.fsw_response_delay_s * NS_PER_S)
        self.wait_for_fsw()
        self.started = True
        self.trace.event(0, "run_started", mode=self.mode, seed=self.seed, cycles=n_cycles)
        clock, wire, results = self.clock, self.wire, self.results
        wall0 = clock.now_ns()
        self._start()
        for k in range(n_cycles):
            t_k = k * period
            cycle_wall0 = clock.now_ns()
            self._emit_samples(t_k)
            # SYNC closes the samples of (t_{k-1}, t_k]: it is queued once they are through,
            # and the flight software's cycle starts when SYNC has arrived.
            wire.flush()
            self._send("SYNC", {"Cycle": k, "SimTime": t_k / NS_PER_S}, max(t_k, wire.last_rx_ns))
            wire.release()
            wire.flush()
            self._collect(k, wire.last_rx_ns + delay_ns)
            self.integrate_to(t_k + period)
            if k % FLUSH_EVERY_CYCLES == 0 and self.progress is not None:
                self.progress(t_k / NS_PER_S, duration_s)
            results.cycle_wall_ns.append(clock.now_ns() - cycle_wall0)
        wire.release()
        wire.flush()
        self._samples.clear()
        results.wall_s = (clock.now_ns() - wall0) / NS_PER_S
        self.trace.event(self.station.t_ns, "run_finished", stalls=results.stalls)

    def _start(self) -> None:
        """t = 0: the faults due at once act on the first samples too; first telemetry."""
        events: list[Event] = []
        self.station.faults.due(0, events)
        self._events(events)
        self._samples += self.station.frames_due(0)
        self.results.telemetry.row(0, self.station, self.results.fsw)

    def _collect(self, k: int, ready_ns: int) -> None:
        """Receive cycle k's commands and deliver them at their modelled arrival."""
        st, wire, results = self.station, self.wire, self.results
        # While the flight software computes: integrate the steps that end before its
        # frames can arrive, and record the bench's own frames already on the wire.
        self.integrate_to(max(st.t_ns, ready_ns // STEP_NS * STEP_NS))
        wire.flush(ready_ns)
        wire.babble(k * self.period_ns, (k + 1) * self.period_ns)
        wire.release()  # delayed frames released meanwhile
        self.trace.write_pending()
        results.write_pending()
        if k % FLUSH_EVERY_CYCLES == 0:
            self.trace.flush()
            results.flush()
        got: list[tuple[int, int, dict[str, float], int]] = []  # (frame, seq, signals, delay)
        lost = 0  # command frames that injected faults kept from the bench this cycle
        fsw_dead = self.fsw_alive is not None and not self.fsw_alive()
        timeout_ns = (0 if (st.fsw_silent or fsw_dead)
                      else round(self.sc.bus.stall_timeout_s * NS_PER_S))
        wait0 = self.clock.now_ns()
        deadline = wait0 + timeout_ns
        imu_counter: int | None = None
        want = len(self.cmd_frames)
        events: list[Event] = []
        while len(got) + lost < want:
            left_s = max(0.0, (deadline - self.clock.now_ns()) / NS_PER_S)
            msg = recv_spinning(self.bus, left_s, self.lockstep_spin_s)
            if msg is None:
                break
            for a in self.receipt.receive(msg, ready_ns, k):
                is_cmd = a.name is not None and self.receipt.command_index(a.name) is not None
                if a.fate.drop:
                    lost += is_cmd
                    continue
                seq = self._onto_wire(a, ready_ns)
                lost += is_cmd and a.injected_loss
                d = a.decoded
                if d is None:
                    continue
                index = self.receipt.command_index(d.name)
                if index is not None:
                    got.append((index, seq, d.signals, a.fate.delay_ns))
                    imu_counter = int(d.signals["ImuCounter"])
                else:
                    self._take(d, events)
            if events:
                self._events(events)
                events = []
        self._second_sender()
        results.fsw_wait_ns.append(self.clock.now_ns() - wait0)
        rx = wire.flush(ready_ns + self.period_ns)
        if any(g[1] not in rx for g in got):  # a congested wire: resolve what is left
            rx.update(wire.flush())
        self._stall_bookkeeping(k, len(got) + lost < want, got)
        if not got:
            return
        t_last = 0
        t_fire: int | None = None
        pulses: list[Pulse] = []
        for index, seq, s, delay_ns in sorted(got, key=lambda g: (g[0], g[1])):
            t_rx = rx[seq] + delay_ns
            t_last = max(t_last, t_rx)
            if st.command(index, s, t_rx, pulses) and (t_fire is None or t_rx < t_fire):
                t_fire = t_rx
        results.add_pulses(pulses)
        st.commanded(t_last, events)
        self._events(events)
        if imu_counter is not None:
            results.chain(k, imu_counter, t_last, t_fire)

    def _onto_wire(self, a: Arrival, ready_ns: int) -> int:
        """Lockstep: a received copy goes onto the modelled wire (a frame that passed the
        checks, or one an injected bus fault spoiled; -1 otherwise: trace only, so garbage
        on the bus cannot shift a lockstep run)."""
        faulted = a.fate.corrupt_bit is not None or a.fate.duplicate
        sender = self.icd.sender[a.name] if a.name is not None else ""
        if a.name is not None and sender != BENCH and (a.passed_checks or faulted):
            return self.wire.received(a.msg, ready_ns, sender, a.fate)
        self.wire.received_off_wire(a.msg, ready_ns)
        return -1

    def _stall_bookkeeping(self, k: int, stalled: bool,
                           got: list[tuple[int, int, dict[str, float], int]]) -> None:
        """Count a stall (naming the missing frames), declare the flight software silent
        after ``SILENT_AFTER_STALLS`` in a row, and back when it answers again."""
        st, results = self.station, self.results
        t_ns = k * self.period_ns
        if stalled:
            results.stalls += 1
            self.consecutive_stalls += 1
            if not st.fsw_silent:
                have = {g[0] for g in got}
                missing = [n for i, n in enumerate(self.cmd_frames) if i not in have]
                self.trace.event(t_ns, "stall", cycle=k, frames=len(got), missing=missing)
            if self.consecutive_stalls >= SILENT_AFTER_STALLS and not st.fsw_silent:
                st.fsw_silent = True
                self.trace.event(t_ns, "fsw_silent", cycle=k)
        else:
            if st.fsw_silent:
                self.trace.event(t_ns, "fsw_back", cycle=k)
            self.consecutive_stalls = 0
            st.fsw_silent = False

    # -- realtime ---------------------------------------------------------------------
    def run_realtime(self, duration_s: float, clock: Clock | None = None) -> None:
        """Wall-clock-paced run of ``duration_s`` seconds.

        A bench slower than the wall clock still ends at ``duration_s`` of plant time: each
        pass steps the plant to the clock, then reads at most ``RT_FRAMES_PER_PASS`` frames,
        so neither catching up nor a stream of frames can keep it from sending sensors or
        from ending. Every pass, and every command frame, that finds the plant more than a
        control period behind the clock is counted (``bench_late``) and the largest lag is
        reported (``bench_max_lag_ms``): such a run's timing figures are not real time.
        """
        if clock is not None:
            self.clock = clock
        self.wait_for_fsw()
        self.started = True
        self.trace.event(0, "run_started", mode=self.mode, seed=self.seed)
        clock = self.clock
        st, results = self.station, self.results
        results.wall_origin_s = clock.wall0_s
        end_ns = round(duration_s * NS_PER_S)
        self._rt_end_ns = end_ns
        self._realtime_clock = clock
        self._start()
        self._emit_samples(0)
        next_progress = 0
        while st.t_ns < end_ns:
            results.note_lag(clock.now_ns() - st.t_ns, self.period_ns)
            self.integrate_to(min(clock.now_ns(), end_ns) // STEP_NS * STEP_NS)
            wait_s = max(0.0, (st.t_ns + STEP_NS - clock.now_ns()) / NS_PER_S)
            msg = self.bus.recv(timeout=wait_s)
            n_read = 0
            while msg is not None:
                self._on_realtime_frame(msg, clock)
                n_read += 1
                if n_read >= RT_FRAMES_PER_PASS or st.t_ns >= end_ns:
                    break  # back to stepping; the rest stays queued for the next pass
                msg = self.bus.recv(timeout=0.0)
            if st.t_ns >= next_progress:
                self.trace.flush()
                results.flush()
                if self.progress is not None:
                    self.progress(st.t_ns / NS_PER_S, duration_s)
                next_progress += FLUSH_EVERY_CYCLES * self.period_ns
        self._realtime_clock = None
        results.wall_s = clock.now_ns() / NS_PER_S
        self.trace.event(st.t_ns, "run_finished", late_steps=results.late_steps,
                         max_lag_ms=results.max_lag_ns / 1e6)

    def _on_realtime_frame(self, msg: can.Message, clock: Clock) -> None:
        """A frame read in realtime: the receive path, then the trace and its effect."""
        st = self.station
        events: list[Event] = []
        for a in self.receipt.receive(msg, clock.now_ns(), None):
            if a.fate.drop:
                continue
            t_ns = clock.now_ns()
            tx_wall = getattr(a.msg, "tx_timestamp", None)  # the portable bus: sender's time
            self.trace.frame(
                a.msg, t_ns, tx=False,
                t_ready_ns=float("nan") if tx_wall is None else clock.from_wall_ns(tx_wall),
                t_rx_ns=clock.from_wall_ns(a.msg.timestamp) if a.msg.timestamp > 0 else t_ns,
                bits=frame_bits(a.msg.arbitration_id, bytes(a.msg.data)))
            d = a.decoded
            if d is None:
                continue
            index = self.receipt.command_index(d.name)
            if index is None:
                self._take(d, events)
                continue
            self.results.note_lag(t_ns - st.t_ns, self.period_ns)
            self.integrate_to(min(self._rt_end_ns, max(st.t_ns, t_ns // STEP_NS * STEP_NS)))
            t_apply = max(t_ns, st.t_ns)
            pulses: list[Pulse] = []
            if st.command(index, d.signals, t_apply, pulses):
                self._rt_fire_ns = t_apply if self._rt_fire_ns is None else self._rt_fire_ns
            self.results.add_pulses(pulses)
            st.commanded(t_apply, events)
            st.fsw_silent = False
            self._fsw_heard_wall_ns = clock.now_ns()
            if index == len(self.cmd_frames) - 1:
                self.results.chain(int(d.signals["Cycle"]), int(d.signals["ImuCounter"]), t_ns,
                                   self._rt_fire_ns)
                self._rt_fire_ns = None
        self._events(events)
        self._second_sender()

    # -- results ----------------------------------------------------------------------
    def summary(self, sim_time_s: float) -> dict[str, Any]:
        """summary.json content from the bench's side."""
        return self.results.summary(sim_time_s, self.station, self.wire, self.receipt)

    def close(self, sim_time_s: float) -> dict[str, Any]:
        """Finish files and write summary.json; returns the summary."""
        self.trace.close()
        self.results.close()
        summary = self.summary(sim_time_s)
        write_summary(self.run_dir / "summary.json", summary)
        return summary
