"""The flight-software process: CAN port and cycle scheduler around :class:`FlightComputer`.

Frames in: the bench's SYNC, IMU_RATE, IMU_ACCEL, STR_QUAT, NAV_POS, NAV_VEL, THR_STATUS,
BENCH_STATUS, checked on receipt by :class:`dbc.codec.FrameChecker` (ID, extended flag,
DLC, CRC, alive counter, range; our own messages heard from another node are counted
``unexpected``). Frames out (flight_sw.frames): FSW_STATUS (also the boot heartbeat),
FSW_ATT_EST, FSW_FDIR, THR_CMD_0..m. IDs, periods and counter widths come from the DBC
(dbc.icd).

Freshness and bench restarts (flight_sw.bench_link; docs/icd.md "Restarts"): a stale SYNC
or BENCH_STATUS is rejected without moving any alive counter; a bench restart (SYNC back
to 0, BENCH_STATUS time going back) is taken only after the bench has been quiet, then
the flight computer is re-initialised on the bench's new time and the new SYNC answered;
otherwise the frame is a replay, counted in ``restarts_refused``.
In realtime the flight computer's manoeuvre time is aligned on the first BENCH_STATUS.
Heartbeat: FSW_STATUS alone at start-up and after every second without any received frame
(before the first SYNC), and after ``LOCKSTEP_SILENCE_HEARTBEAT_S`` once cycling.

Modes: ``lockstep`` — one control cycle per SYNC(k), at the simulation time it carries;
``realtime`` — cycles on this process's own monotonic timer (period from the DBC), with
overruns counted; with a receive log (:mod:`flight_sw.rx_log`) every frame read is logged
with its receive timestamp, flushed per cycle. Status and attitude telemetry go out every
FSW_STATUS period. Runs until SIGTERM, SIGINT or SIGHUP, then commands every valve
closed, writes its statistics file and exits 0.
"""

from __future__ import annotations

import contextlib
import dataclasses
import signal
from pathlib import Path
from types import FrameType

import can
from cantools.database.can import Database

from dbc.codec import Decoded, Encoder, FrameChecker
from dbc.icd import BENCH, FSW, Icd
from dbc.quaternion import pack_quaternion
from dbc.records import write_record
from flight_sw.bench_link import BenchLink, Verdict, sim_time_ns
from flight_sw.clock import MonotonicClock
from flight_sw.computer import CycleResult, FlightComputer
from flight_sw.frames import command_signals, fdir_signals, feed, status_signals
from flight_sw.rx_log import ReceiveLog
from flight_sw.stats import NodeStats, stats_record
from transport.lockstep import recv_spinning, send_frames

HEARTBEAT_RETRY_S = 1.0  # silence before the next FSW_STATUS heartbeat, until the first SYNC
# Lockstep, once cycling: the bench is the time master and may be silent for a while without
# being gone (paused in a debugger; its send held up to hilbus.MEMBER_STALL_S = 1 s by a
# stopped bus monitor). A heartbeat then would put a wall-clock-timed frame into the
# deterministic trace and shift FSW_STATUS's alive counter. A restarted bench waits for the
# heartbeat up to its startup timeout (60 s by default), so a longer silence is harmless.
LOCKSTEP_SILENCE_HEARTBEAT_S = 5.0
NS_PER_S = 1e9
STATS_EVERY_STATUS_PERIODS = 10  # realtime: the statistics file is rewritten this often


def _next_phase_ns(now_ns: int, base_ns: int, period_ns: int, phase_ns: int) -> int:
    """The first ``base + k·period + phase`` (k integer) after ``now_ns``."""
    k = (now_ns - base_ns - phase_ns) // period_ns + 1
    return base_ns + k * period_ns + phase_ns


class StopRequested(Exception):  # noqa: N818 - a request, not an error
    """Raised by the signal handler to leave a blocking receive at once."""


class FlightNode:
    """Binds a FlightComputer to a bus."""

    def __init__(self, db: Database, bus: can.BusABC, computer: FlightComputer,
                 stats_path: Path | None = None, rx_log: ReceiveLog | None = None,
                 clock: MonotonicClock | None = None) -> None:
        self.db = db
        self.icd = icd = Icd.from_database(db)
        self.rx_log = rx_log  # realtime: when each frame arrived (flight_sw/rx_log.py)
        self.bus = bus
        self.fc = computer
        self.encoder = Encoder(db)
        self.checker = FrameChecker(db, accept=icd.sent_by(BENCH), own=icd.sent_by(FSW))
        self.stats = NodeStats()
        self.clock = clock or MonotonicClock()
        self.stats_path = stats_path
        self.n_thr = len(computer.modulators)
        self.period_ns = icd.control_period_ns
        self.status_every = max(1, icd.period_ns["FSW_STATUS"] // self.period_ns)
        self._sync_modulus = icd.sync_cycle_modulus
        self._stop = False
        self._waiting = False  # blocked in the bus receive: a stop signal may interrupt
        self.lockstep_silence_heartbeat_s = LOCKSTEP_SILENCE_HEARTBEAT_S
        self.lockstep_spin_s = 0.0  # lockstep: poll this long before blocking (transport.lockstep)
        self.link = BenchLink(self.checker)  # which SYNC / BENCH_STATUS count, restarts
        self._pending_seen: set[str] = set()
        self._last_result: CycleResult | None = None
        self._reported: tuple[int, int, int] | None = None  # (mode, FDIR, sensor flags) sent
        self._realtime = False
        self._time_aligned = False
        # lockstep: the frames of the cycle being computed, sent together at its end
        self._held: list[tuple[str, can.Message]] | None = None

    # -- signals -----------------------------------------------------------------
    def install_signal_handlers(self) -> None:
        """SIGTERM / SIGINT end the loop: at once while blocked in a receive, else after the
        current step (a frame being sent is sent and counted, so the statistics match what
        the bench received).

        A second signal while stopping is ignored, so the statistics file is still written.
        """

        def _handler(signum: int, frame: FrameType | None) -> None:
            if self._stop:  # already stopping (e.g. Ctrl-C, then the bench's SIGTERM):
                return  # let the statistics be written
            self._stop = True
            if self._waiting:
                raise StopRequested(signum)

        for s in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
            signal.signal(s, _handler)

    def run(self, mode: str) -> None:
        """Run ``mode`` ('lockstep' or 'realtime') until stopped; then command every valve
        closed and write the statistics."""
        try:
            if mode == "lockstep":
                self.run_lockstep()
            else:
                self.run_realtime()
        except StopRequested:
            pass
        finally:
            self._close_valves()
            self.write_stats()

    def _close_valves(self) -> None:
        """On the way out: one set of valve commands with every on-time 0, for the cycle
        after the last one (a bench still listening closes its valves; hardware too)."""
        self._held = None
        res = self._last_result
        if res is None:
            return
        closed = dataclasses.replace(res, on_time_s=(0.0,) * len(res.on_time_s))
        with contextlib.suppress(can.CanError, OSError):  # after the run: not in ``sent``
            for name, sig in command_signals(self.icd, self.stats.cycles, closed, self.n_thr,
                                             self.period_ns):
                self.bus.send(self.encoder.message(name, sig))

    def _recv(self, timeout_s: float) -> can.Message | None:
        """``bus.recv`` that a stop signal may interrupt (see install_signal_handlers)."""
        self._waiting = True
        try:
            if self._stop:
                raise StopRequested(0)
            spin_s = 0.0 if self._realtime else self.lockstep_spin_s
            return recv_spinning(self.bus, timeout_s, spin_s)
        finally:
            self._waiting = False

    # -- transmit ----------------------------------------------------------------
    def _send(self, name: str, signals: dict[str, float | int]) -> None:
        msg = self.encoder.message(name, signals)
        if self._held is not None:  # a lockstep cycle: sent with the others at its end
            self._held.append((name, msg))
            return
        self.bus.send(msg)
        self.stats.sent[name] = self.stats.sent.get(name, 0) + 1

    def _send_held(self) -> None:
        """The cycle's frames, in the order encoded, as one burst (lockstep.send_frames)."""
        held = self._held or []
        send_frames(self.bus, [msg for _name, msg in held])
        for name, _msg in held:
            self.stats.sent[name] = self.stats.sent.get(name, 0) + 1

    def _status(self, cycle: int) -> dict[str, float | int]:
        return status_signals(self.icd, int(self.fc.mode), cycle, self.stats.overruns,
                              self._last_result)

    def send_status(self, cycle: int) -> None:
        """FSW_STATUS, FSW_ATT_EST and FSW_FDIR."""
        self._send("FSW_STATUS", self._status(cycle))
        est = self.fc.estimator.estimate()
        q = [float(x) for x in est.q_BN]
        self._send("FSW_ATT_EST", {"Valid": int(est.initialised), **pack_quaternion(q)})
        self._send("FSW_FDIR", fdir_signals(self.icd, self.n_thr, self._last_result))

    def run_cycle(self, cycle: int, t_ns: int) -> None:
        """One control cycle at ``t_ns`` and its frames (status first, commands last).

        Lockstep: the frames go to the bus together once all are encoded (one burst on a
        bus that takes bursts); realtime: each as soon as it is encoded.
        """
        t0 = self.clock.now_ns()
        if self._realtime:
            self._cycle_frames(cycle, t_ns)
        else:
            self._held = []
            try:
                self._cycle_frames(cycle, t_ns)
                self._send_held()
            finally:
                self._held = None
        self.stats.cycle_ns.append(self.clock.now_ns() - t0)

    def _cycle_frames(self, cycle: int, t_ns: int) -> None:
        res = self.fc.cycle(t_ns)
        self._last_result = res
        st = self.stats
        st.cycles += 1
        st.residual_Nm.append(res.residual_Nm)
        st.residual_N.append(res.residual_force_N)
        st.saturated_cycles += bool(res.saturated)
        # Status at its DBC rate, and at once when the mode or a flag changes: the bench
        # and the operator learn of a safe-mode entry or an isolation in the same cycle.
        reported = (int(self.fc.mode), res.fdir_flags, res.sensor_flags)
        if cycle % self.status_every == 0 or reported != self._reported:
            self._reported = reported
            self.send_status(cycle)
        for name, sig in command_signals(self.icd, cycle, res, self.n_thr, self.period_ns):
            self._send(name, sig)

    # -- receive -----------------------------------------------------------------
    def handle(self, d: Decoded, t_ns: int) -> None:
        """Feed one checked sensor frame to the computer, stamped ``t_ns``."""
        if feed(self.fc, d, t_ns):
            self._pending_seen.add(d.name)

    def _on_bench_status(self, d: Decoded, now_ns: int) -> None:
        """BENCH_STATUS (flight_sw.bench_link): a restart, or the bench's time; realtime aligns
        the timeline on it (the first one, then any that shows the bench's time 0 earlier)."""
        verdict = self.link.bench_status(d, now_ns)
        bench_ns = self.link.bench_time_ns or 0
        if verdict is Verdict.RESTART:
            self.bench_restarted(self.clock.now_ns() if self._realtime else bench_ns, bench_ns)
        elif verdict is Verdict.TAKEN and self._realtime:
            # our time of the bench's time 0: the earliest estimate so far (each arrives
            # late by its transport and our own reading delay, never early; same clock)
            base = self.clock.now_ns() - bench_ns
            if not self._time_aligned or base < self.fc.timeline.time_base_ns:
                self.fc.timeline.time_base_ns = base
                if self.fc.thruster_fdir is not None:
                    self.fc.thruster_fdir.time_base_ns = base
            self._time_aligned = True

    def bench_restarted(self, t_ns: int, bench_ns: int | None) -> None:
        """Start again with a restarted bench: our time ``t_ns`` is its time ``bench_ns``
        (None: not known yet, a SYNC restart)."""
        self.fc.restart(t_ns, t_ns if bench_ns is None else bench_ns)
        self.stats.restarts += 1
        self.link.restarted(bench_ns)
        self._pending_seen.clear()
        self._time_aligned = self._realtime

    def _heartbeat(self) -> None:
        """FSW_STATUS alone: BOOT before the first cycle, else the current state."""
        self._send("FSW_STATUS", self._status(self.stats.cycles))

    # -- loops -------------------------------------------------------------------
    def run_lockstep(self) -> None:
        """Cycle on SYNC frames until stopped."""
        self._heartbeat()
        clock = self.clock
        link = self.link
        while not self._stop:
            silence_s = (HEARTBEAT_RETRY_S if link.last_sync_ns is None
                         else self.lockstep_silence_heartbeat_s)
            msg = self._recv(silence_s)
            if msg is None:
                self._heartbeat()
                continue
            now = clock.now_ns()
            d = self.checker.inspect(msg, now)
            if d is None:
                continue
            if d.name == "BENCH_STATUS":
                self._on_bench_status(d, now)
                continue
            if d.name != "SYNC":
                link.take(d, now)
                self.handle(d, link.last_sync_ns or 0)
                continue
            verdict = link.sync(d, now)
            if verdict is Verdict.STALE:
                continue
            if verdict is Verdict.RESTART:
                t_restart = sim_time_ns(d.signals["SimTime"])
                self.bench_restarted(t_restart, None)
            first = link.last_sync_ns is None
            cycle, t_ns = link.ran(d)
            if first:
                self.fc.watchdog.start(t_ns)
            for name in self._pending_seen:
                self.fc.watchdog.seen(name, t_ns)
            self._pending_seen.clear()
            self.run_cycle(cycle, t_ns)
        self.write_stats()

    def run_realtime(self) -> None:
        """Cycle on this process's own timer until stopped.

        The timer free-runs until the bench's time is known (its first BENCH_STATUS), then
        is put in phase with it: each cycle starts ``cycle_phase_ns`` after one of the
        bench's control instants (multiples of the period in its time), so the sensor
        samples of that instant have arrived. A free-running timer would sit at a random
        phase, often just before the samples: a run-to-run spread of up to a period in
        the sensor-to-command latency.
        """
        clock = self.clock
        self._realtime = True
        self._heartbeat()
        period = self.period_ns
        next_ns = clock.now_ns() + period
        cycle = 0
        phased_base: int | None = None
        self.fc.watchdog.start(clock.now_ns())
        while not self._stop:
            now = clock.now_ns()
            base = self.fc.timeline.time_base_ns
            if self._time_aligned and base != phased_base:
                phased_base = base
                next_ns = _next_phase_ns(now, base, period, self.fc.cycle_phase_ns)
            if now < next_ns:
                msg = self._recv((next_ns - now) / NS_PER_S)
                if msg is not None:
                    self._realtime_frame(msg)
                continue
            self.run_cycle(cycle, next_ns)
            if self.rx_log is not None:
                self.rx_log.flush()
            cycle += 1
            next_ns += period
            done = clock.now_ns()
            while done >= next_ns:  # computation overran: skip the missed period(s)
                self.stats.overruns += 1
                next_ns += period
            if cycle % (self.status_every * STATS_EVERY_STATUS_PERIODS) == 0:
                self.write_stats()
        self.write_stats()

    def _realtime_frame(self, msg: can.Message) -> None:
        """A frame read in realtime: logged, checked, fed to the computer at its arrival."""
        if self.rx_log is not None:
            self.rx_log.row(msg)
        t = self.clock.now_ns()
        d = self.checker.inspect(msg, t)
        if d is None:
            return
        if d.name == "BENCH_STATUS":
            self._on_bench_status(d, t)
            return
        self.link.take(d, t)
        self.handle(d, t)
        for name in self._pending_seen:
            self.fc.watchdog.seen(name, t)
        self._pending_seen.clear()

    # -- statistics --------------------------------------------------------------
    def write_stats(self) -> None:
        """Write the node's statistics record (flight_sw.stats) if a path was given."""
        if self.stats_path is not None:
            write_record(self.stats_path, stats_record(
                self.stats, self.checker.summary(), self.fc, self._last_result, self.bus,
                self.link.restarts_refused))
