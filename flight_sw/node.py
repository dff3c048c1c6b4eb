"""The flight-software process: CAN port and cycle scheduler around :class:`FlightComputer`.

Frames in (checked on receipt by :class:`dbc.codec.FrameChecker`: ID, DLC, CRC, alive
counter, range; freshness of SYNC by its cycle number): SYNC, IMU_RATE, IMU_ACCEL,
STR_QUAT, NAV_POS, NAV_VEL, THR_STATUS, BENCH_STATUS. Frames out: FSW_STATUS (also the boot
heartbeat), FSW_ATT_EST, FSW_FDIR, THR_CMD_0..3 (on-times of 4 thrusters each, the cycle
number and the newest IMU_RATE counter used).

Bench restart: a SYNC whose cycle goes back to 0 (or more than ``STALE_SYNC_WINDOW`` cycles
back), or a BENCH_STATUS whose SimTime goes backwards, means the bench started a new run:
the flight computer is re-initialised on the bench's new time
(:meth:`FlightComputer.restart`), the cycle bookkeeping starts again and the new SYNC is
answered (never a hang). A SYNC one or two cycles back is a stale frame, rejected.
In realtime the flight computer's manoeuvre time is aligned on the first BENCH_STATUS.
Heartbeat: FSW_STATUS alone at start-up and after every second without any received frame
(before the first SYNC, or when the bench has gone), so a restarted bench finds us.

Modes: ``lockstep`` — one control cycle per SYNC(k), at the simulation time it carries;
``realtime`` — cycles on this process's own monotonic timer (period from the DBC), with
overruns counted; with a receive log (:mod:`flight_sw.rx_log`) every frame read is logged
with its receive timestamp, flushed per cycle. Status and attitude telemetry go out every
FSW_STATUS period. Runs until SIGTERM/SIGINT, then writes its statistics file and exits 0.
"""

from __future__ import annotations

import json
import math
import signal
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

import can
import numpy as np
from cantools.database.can import Database

from dbc.codec import Decoded, Encoder, FrameChecker, Reject, cycle_time_ns
from dbc.quaternion import pack_quaternion, unpack_quaternion
from flight_sw.clock import MonotonicClock
from flight_sw.computer import CycleResult, FlightComputer
from flight_sw.fdir.base import NO_THRUSTER
from flight_sw.rx_log import ReceiveLog
from transport.lockstep import recv_spinning, send_frames

THRUSTERS_PER_CMD_FRAME = 4
HEARTBEAT_RETRY_S = 1.0  # silence before the next FSW_STATUS heartbeat, until the first SYNC
# Lockstep, once cycling: the bench is the time master and may be silent for a while without
# being gone (paused in a debugger; its send held up to hilbus.MEMBER_STALL_S = 1 s by a
# stopped bus monitor). A heartbeat then would put a wall-clock-timed frame into the
# deterministic trace and shift FSW_STATUS's alive counter. A restarted bench waits for the
# heartbeat up to its startup timeout (60 s by default), so a longer silence is harmless.
LOCKSTEP_SILENCE_HEARTBEAT_S = 5.0
CYCLE_MODULUS = 256
STATUS_CYCLE_MODULUS = 65536
OVERRUN_MAX = 255
ON_TIME_LSB_S = 1e-4
MAX_CMD_FRAMES = 4  # THR_CMD_0..3 in the DBC
CMD_FRAMES = tuple(f"THR_CMD_{f}" for f in range(MAX_CMD_FRAMES))
ON_TIME_SIGNALS = tuple(f"OnTime_T{k:02d}" for k in range(MAX_CMD_FRAMES * THRUSTERS_PER_CMD_FRAME))
# A full-period pulse is sent this much longer, to bridge command-arrival jitter (see
# ``send_commands``); far below the DBC's 102.3 ms and the bench's valve watchdog.
FULL_ON_OVERLAP_S = 0.005
MS_PER_S = 1000
NS_PER_MS = 1_000_000
BENCH_FRAMES = frozenset(
    {
        "SYNC",
        "IMU_RATE",
        "IMU_ACCEL",
        "STR_QUAT",
        "NAV_POS",
        "NAV_VEL",
        "THR_STATUS",
        "BENCH_STATUS",
    }
)
# A SYNC at most this many cycles behind the last one is stale; further back, a restart.
STALE_SYNC_WINDOW = 2
DETECTION_TIME_MAX_S = 655.35  # FSW_FDIR.DetectionTime range
ISOLATION_DELAY_MAX_S = 2.55  # FSW_FDIR.IsolationDelay range
ALLOC_RESIDUAL_MAX_NM = 12.75  # FSW_STATUS.AllocResidual range
ALLOC_RESIDUAL_MAX_N = 12.75  # FSW_STATUS.AllocForceResidual range


def _next_phase_ns(now_ns: int, base_ns: int, period_ns: int, phase_ns: int) -> int:
    """The first ``base + k·period + phase`` (k integer) after ``now_ns``."""
    k = (now_ns - base_ns - phase_ns) // period_ns + 1
    return base_ns + k * period_ns + phase_ns


def _spread(values: list[float]) -> dict[str, float | None]:
    """p50, p99 and max of ``values`` (full precision; the bus carries 0.05 steps)."""
    if not values:
        return {"p50": None, "p99": None, "max": None}
    p50, p99 = np.percentile(np.asarray(values, dtype=float), (50.0, 99.0))
    return {"p50": float(p50), "p99": float(p99), "max": float(max(values))}


def _percentiles_us(samples_ns: list[int]) -> dict[str, float | int | None]:
    """p50, p99 and max of ``samples_ns`` in microseconds."""
    if not samples_ns:
        return {"p50": None, "p99": None, "max": None, "n": 0}
    a = np.asarray(samples_ns, dtype=float) / 1e3
    p50, p99 = np.percentile(a, (50.0, 99.0))
    return {
        "p50": round(float(p50), 1),
        "p99": round(float(p99), 1),
        "max": round(float(a.max()), 1),
        "n": len(samples_ns),
    }


class StopRequested(Exception):  # noqa: N818 - a request, not an error
    """Raised by the signal handler to leave a blocking receive at once."""


@dataclass
class NodeStats:
    """Counters the node reports at exit."""

    cycles: int = 0
    overruns: int = 0
    restarts: int = 0
    sent: dict[str, int] = field(default_factory=dict)
    cycle_ns: list[int] = field(default_factory=list)  # cycle start -> last frame sent
    residual_Nm: list[float] = field(default_factory=list)  # allocation torque residual
    residual_N: list[float] = field(default_factory=list)  # allocation force residual
    saturated_cycles: int = 0


class FlightNode:
    """Binds a FlightComputer to a bus."""

    def __init__(
        self,
        db: Database,
        bus: can.BusABC,
        computer: FlightComputer,
        stats_path: Path | None = None,
        rx_log: ReceiveLog | None = None,
    ) -> None:
        self.db = db
        self.rx_log = rx_log  # realtime: when each frame arrived (flight_sw/rx_log.py)
        self.bus = bus
        self.fc = computer
        self.encoder = Encoder(db)
        self.checker = FrameChecker(db, accept=BENCH_FRAMES)
        self.stats = NodeStats()
        self.clock = MonotonicClock()
        self.stats_path = stats_path
        self.n_thr = len(computer.modulators)
        self.n_cmd_frames = math.ceil(self.n_thr / THRUSTERS_PER_CMD_FRAME)
        self.period_ns = cycle_time_ns(db, "THR_CMD_0")
        self.status_every = max(1, cycle_time_ns(db, "FSW_STATUS") // self.period_ns)
        self._stop = False
        self._waiting = False  # blocked in the bus receive: a stop signal may interrupt
        self.lockstep_silence_heartbeat_s = LOCKSTEP_SILENCE_HEARTBEAT_S
        self.lockstep_spin_s = 0.0  # lockstep: poll this long before blocking (transport.lockstep)
        self._last_sync: int | None = None
        self._pending_seen: set[str] = set()
        self._sync_cycle = -1
        self._last_flags = 0
        self._last_sat = False
        self._last_residual = 0.0
        self._last_result: CycleResult | None = None
        self._reported: tuple[int, int, int] | None = None  # (mode, FDIR, sensor flags) sent
        self._bench_time_ns: int | None = None  # newest BENCH_STATUS SimTime
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

        signal.signal(signal.SIGTERM, _handler)
        signal.signal(signal.SIGINT, _handler)

    def run(self, mode: str) -> None:
        """Run ``mode`` ('lockstep' or 'realtime') until stopped; always writes statistics."""
        try:
            if mode == "lockstep":
                self.run_lockstep()
            else:
                self.run_realtime()
        except StopRequested:
            pass
        finally:
            self.write_stats()

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
        """The cycle's frames, in the order encoded, as one burst (see
        transport.lockstep.send_frames)."""
        held = self._held or []
        send_frames(self.bus, [msg for _name, msg in held])
        for name, _msg in held:
            self.stats.sent[name] = self.stats.sent.get(name, 0) + 1

    def _status_signals(self, cycle: int) -> dict[str, float]:
        """FSW_STATUS content: mode, counters, FDIR flags, the allocation's saturation/residual."""
        res = self._last_result
        return {
            "Mode": int(self.fc.mode),
            "Cycle": cycle % STATUS_CYCLE_MODULUS,
            "Overruns": min(self.stats.overruns, OVERRUN_MAX),
            "FdirFlags": self._last_flags,
            "AllocSaturated": int(self._last_sat),
            "AllocResidual": min(self._last_residual, ALLOC_RESIDUAL_MAX_NM),
            "AllocForceResidual": min(
                res.residual_force_N if res is not None else 0.0, ALLOC_RESIDUAL_MAX_N
            ),
        }

    def send_status(self, cycle: int) -> None:
        """FSW_STATUS, FSW_ATT_EST and FSW_FDIR."""
        fc = self.fc
        self._send("FSW_STATUS", self._status_signals(cycle))
        est = fc.estimator.estimate()
        q = [float(x) for x in est.q_BN]
        self._send("FSW_ATT_EST", {"Valid": int(est.initialised), **pack_quaternion(q)})
        self._send("FSW_FDIR", self._fdir_signals())

    def _fdir_signals(self) -> dict[str, float | int]:
        """FSW_FDIR from the last cycle (all thrusters available before the first cycle)."""
        res = self._last_result
        rep = res.fdir if res is not None else None
        if rep is None:
            return {
                "AvailableMask": (1 << self.n_thr) - 1,
                "FailedThruster": NO_THRUSTER,
                "FailureKind": 0,
                "DetectionTime": 0.0,
                "IsolationDelay": 0.0,
                "SensorFlags": res.sensor_flags if res is not None else 0,
            }
        return {
            "AvailableMask": rep.available_mask,
            "FailedThruster": rep.failed_thruster,
            "FailureKind": int(rep.failure_kind),
            "DetectionTime": min(max(rep.detection_time_s, 0.0), DETECTION_TIME_MAX_S),
            "IsolationDelay": min(max(rep.isolation_delay_s, 0.0), ISOLATION_DELAY_MAX_S),
            "SensorFlags": res.sensor_flags if res is not None else 0,
        }

    def send_commands(self, cycle: int, res: CycleResult) -> None:
        """THR_CMD_0..m for one cycle (thrusters beyond the vehicle's count are 0).

        A full-period on-time is sent ``FULL_ON_OVERLAP_S`` longer, so that consecutive
        full-on pulses overlap the next command, which continues the energised coil: no
        closing and re-opening transient when a command arrives a little later than the
        previous one (e.g. behind the status frames). The next command always ends or
        continues it, so the thrust is that of a continuous pulse.
        """
        max_on = self.period_ns / 1e9
        for f in range(self.n_cmd_frames):
            sig: dict[str, float | int] = {
                "Cycle": cycle % CYCLE_MODULUS,
                "ImuCounter": res.imu_counter,
            }
            for j in range(THRUSTERS_PER_CMD_FRAME):
                k = f * THRUSTERS_PER_CMD_FRAME + j
                on = min(max(res.on_time_s[k] if k < self.n_thr else 0.0, 0.0), max_on)
                if on >= max_on:
                    on = max_on + FULL_ON_OVERLAP_S
                sig[ON_TIME_SIGNALS[k]] = round(on / ON_TIME_LSB_S) * ON_TIME_LSB_S
            self._send(CMD_FRAMES[f], sig)

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
        self._last_flags, self._last_sat, self._last_residual = (
            res.fdir_flags,
            res.saturated,
            res.residual_Nm,
        )
        self.stats.cycles += 1
        self.stats.residual_Nm.append(res.residual_Nm)
        self.stats.residual_N.append(res.residual_force_N)
        self.stats.saturated_cycles += bool(res.saturated)
        # Status at its DBC rate, and at once when the mode or a flag changes: the bench
        # and the operator learn of a safe-mode entry or an isolation in the same cycle.
        reported = (int(self.fc.mode), res.fdir_flags, res.sensor_flags)
        if cycle % self.status_every == 0 or reported != self._reported:
            self._reported = reported
            self.send_status(cycle)
        self.send_commands(cycle, res)

    # -- receive -----------------------------------------------------------------
    def handle(self, d: Decoded, t_ns: int) -> None:
        """Feed one checked sensor frame to the computer, stamped ``t_ns``."""
        s = d.signals
        fc = self.fc
        name = d.name
        if name == "IMU_RATE":
            if s["Valid"] and fc.on_imu_rate(
                t_ns, np.array((s["RateX"], s["RateY"], s["RateZ"])), d.counter, d.gap
            ):
                self._pending_seen.add(name)
        elif name == "IMU_ACCEL":
            if s["Valid"]:
                fc.on_imu_accel(
                    t_ns, np.array((s["AccelX"], s["AccelY"], s["AccelZ"])), d.counter, d.gap
                )
        elif name == "STR_QUAT":
            payload = (s["Largest"], s["C0"], s["C1"], s["C2"])
            if s["Valid"] and fc.on_star_tracker(t_ns, np.array(unpack_quaternion(s)), payload):
                self._pending_seen.add(name)
        elif name == "NAV_POS":
            if s["Valid"]:
                fc.on_nav_pos(t_ns, np.array((s["PosX"], s["PosY"], s["PosZ"])))
        elif name == "NAV_VEL":
            if s["Valid"]:
                fc.on_nav_vel(t_ns, np.array((s["VelX"], s["VelY"], s["VelZ"])))
        elif name == "THR_STATUS":
            fc.on_thr_status(t_ns, s)
        elif name == "BENCH_STATUS":
            self._on_bench_time(round(float(s["SimTime"]) * MS_PER_S) * NS_PER_MS, t_ns)

    def _on_bench_time(self, bench_ns: int, t_ns: int) -> None:
        """BENCH_STATUS SimTime: a step back is a bench restart; realtime aligns on it (the
        first one, then any that shows the bench's time 0 earlier)."""
        last = self._bench_time_ns
        self._bench_time_ns = bench_ns
        if last is not None and bench_ns < last:
            now = self.clock.now_ns() if self._realtime else bench_ns
            self.bench_restarted(now, bench_ns)
            self._bench_time_ns = bench_ns
        elif self._realtime:
            # our time of the bench's time 0: the earliest estimate so far (each arrives
            # late by its transport and our own reading delay, never early; same clock)
            base = self.clock.now_ns() - bench_ns
            if not self._time_aligned or base < self.fc.timeline.time_base_ns:
                self.fc.timeline.time_base_ns = base
                if self.fc.thruster_fdir is not None:
                    self.fc.thruster_fdir.time_base_ns = base
            self._time_aligned = True

    def bench_restarted(self, t_ns: int, bench_ns: int) -> None:
        """Start again with a restarted bench: our time ``t_ns`` is its time ``bench_ns``."""
        self.fc.restart(t_ns, bench_ns)
        self.stats.restarts += 1
        self._last_sync = None
        self._sync_cycle = -1
        self._bench_time_ns = None
        self._pending_seen.clear()
        self._time_aligned = self._realtime

    def _heartbeat(self) -> None:
        """FSW_STATUS alone: BOOT before the first cycle, else the current state.

        Sent at start-up and after every second without any frame (before the first SYNC,
        or when the bench has gone: a restarted bench waits for this frame to start); in
        lockstep once cycling, after ``LOCKSTEP_SILENCE_HEARTBEAT_S`` without any frame.
        """
        self._send("FSW_STATUS", self._status_signals(self.stats.cycles))

    # -- loops -------------------------------------------------------------------
    def run_lockstep(self) -> None:
        """Cycle on SYNC frames until stopped."""
        self._heartbeat()
        while not self._stop:
            silence_s = (HEARTBEAT_RETRY_S if self._last_sync is None
                         else self.lockstep_silence_heartbeat_s)
            msg = self._recv(silence_s)
            if msg is None:
                self._heartbeat()
                continue
            d = self.checker.check(msg)
            if d is None:
                continue
            if d.name != "SYNC":
                self.handle(d, self._last_sync or 0)
                continue
            cycle = int(d.signals["Cycle"])
            t_ns = round(float(d.signals["SimTime"]) * MS_PER_S) * NS_PER_MS
            if self._last_sync is not None and cycle <= self._sync_cycle:
                if cycle == 0 or self._sync_cycle - cycle > STALE_SYNC_WINDOW:
                    self.bench_restarted(t_ns, t_ns)
                else:
                    self.checker.reject("SYNC", Reject.STALE)
                    continue
            if self._last_sync is None:
                self.fc.watchdog.start(t_ns)
            for name in self._pending_seen:
                self.fc.watchdog.seen(name, t_ns)
            self._pending_seen.clear()
            self._last_sync, self._sync_cycle = t_ns, cycle
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
                msg = self._recv((next_ns - now) / 1e9)
                if msg is not None:
                    if self.rx_log is not None:
                        self.rx_log.row(msg)
                    d = self.checker.check(msg)
                    if d is not None:
                        t = clock.now_ns()
                        self.handle(d, t)
                        for name in self._pending_seen:
                            self.fc.watchdog.seen(name, t)
                        self._pending_seen.clear()
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
            if cycle % (self.status_every * 10) == 0:
                self.write_stats()
        self.write_stats()

    def _allocation_stats(self) -> dict[str, Any]:
        """Residual of the allocation (demand − B T) over the run and saturated cycles."""
        st = self.stats
        return {
            "residual_torque_Nm": _spread(st.residual_Nm),
            "residual_force_N": _spread(st.residual_N),
            "saturated_cycles": st.saturated_cycles,
            "cycles": st.cycles,
        }

    def _fdir_stats(self) -> dict[str, Any]:
        """Isolated thruster failures (times relative to the bench's time 0) and flags."""
        fc = self.fc
        res = self._last_result
        out: dict[str, Any] = {
            "sensor_flags": res.sensor_flags if res is not None else 0,
            "fdir_flags": res.fdir_flags if res is not None else 0,
            "failures": [],
        }
        fdir = fc.thruster_fdir
        if fdir is not None:
            base = fdir.time_base_ns
            out["available_mask"] = int(sum(1 << k for k in range(fdir.n) if fdir.mask[k]))
            out["failures"] = [
                {
                    "thruster": f.thruster,
                    "kind": f.kind.name.lower(),
                    "t_detect_s": (f.t_detect_ns - base) / 1e9,
                    "t_isolate_s": (f.t_isolate_ns - base) / 1e9,
                    "source": f.source,
                }
                for f in fdir.failures
            ]
        return out

    def write_stats(self) -> None:
        """Write the node's statistics JSON (atomically) if a path was given."""
        if self.stats_path is None:
            return
        data: dict[str, Any] = {
            "cycles": self.stats.cycles,
            "overruns": self.stats.overruns,
            "sent": dict(sorted(self.stats.sent.items())),
            "received": self.checker.summary(),
            "mode": self.fc.mode.name,
            "cycle_time_us": _percentiles_us(self.stats.cycle_ns),
            "allocation": self._allocation_stats(),
            "inertia_estimate_B_kgm2": (
                None if self.fc.inertia_B_kgm2 is None else self.fc.inertia_B_kgm2.tolist()
            ),
            "restarts": self.stats.restarts,
            "fdir": self._fdir_stats(),
            # portable bus: frames not delivered to a member that stopped reading
            "bus_overrun_drops": getattr(self.bus, "overrun_drops", 0),
            "bus_overrun_drops_by_pid": {
                str(k): v for k, v in getattr(self.bus, "overrun_drops_by_pid", {}).items()},
        }
        tmp = self.stats_path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=2), encoding="utf-8")
        tmp.replace(self.stats_path)
