"""The bench process: plant, valve drivers, sensors, time master, recorder, metrics.

Frames out: SYNC (lockstep), IMU_RATE, IMU_ACCEL, STR_QUAT, THR_STATUS, BENCH_STATUS.
Frames in (checked on receipt: ID, DLC, CRC, alive counter, range; freshness by cycle
number): THR_CMD_0..3, FSW_STATUS, FSW_ATT_EST. Rates come from the DBC cycle times.

Lockstep (DESIGN §5): per control cycle k the bench sends every sensor sample due in
(t_{k-1}, t_k], then SYNC(k); it waits for the flight software's THR_CMD frames of cycle k,
delivers them to the valves at the time the bus model says they arrive (flight-software
response delay from the scenario, then arbitration and exact frame length), and
integrates to t_{k+1}. A missing answer within ``stall_timeout_s`` of wall time is a counted
stall; after ``SILENT_AFTER_STALLS`` stalls in a row the flight software is declared silent
and the bench stops waiting (never hangs). In lockstep the samples of a control instant go
to the bus together with its SYNC (one burst on hilbus), samples between control instants
as soon as they are taken, and the run files' text is formatted while the flight software
computes (bench/recorder.py, deferred writing). Realtime: the bench paces the plant to its own
monotonic clock, sends sensors when due and applies commands when they arrive; all
latencies are measured. Valve watchdog: no valid command for ``WATCHDOG_PERIODS`` command
periods closes every valve and records the event.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import numpy as np
from cantools.database.can import Database
from mypy_extensions import mypyc_attr

from bench.bus.timing import INTERMISSION_BITS, BusArbiter, Delivery, frame_bits, wire_time_ns
from bench.faults import (
    BUS_KINDS,
    NO_FATE,
    REALTIME_BUS_KINDS,
    Fate,
    FaultSpec,
    fault_from_command,
    frame_fate,
)
from bench.metrics import (
    expectation,
    latency_summary,
    pointing_metrics,
    settling_expectation,
    settling_time_s,
)
from bench.plant import STEP_NS, Plant
from bench.recorder import CHAIN_COLUMNS, NAN, TelemetryWriter, TraceRecorder, write_summary
from bench.reference import KIND_STEP, attitude_error_deg, rate_error_B, reference
from bench.scenario import Scenario
from dbc.codec import Encoder, FrameChecker, Reject, cycle_time_ns
from dbc.errors import RunError
from dbc.quaternion import pack_quaternion, unpack_quaternion
from transport.lockstep import recv_spinning, send_frames

WATCHDOG_PERIODS = 3
MODE_BOOT = 0  # FSW_STATUS.Mode
FAULT_CMD_NONE = 15  # BENCH_STATUS.FaultCmdCounter before any FAULT_CMD
FAULT_RNG_STREAM = 0xFA  # spawn key of the fault-injection random stream
BENCH_NODE = "BENCH"
STARTUP_POLL_S = 0.2
FLUSH_EVERY_CYCLES = 5  # run files go to disk this often (and the progress line is updated)
SILENT_AFTER_STALLS = 3
THRUSTERS_PER_CMD_FRAME = 4
RT_FRAMES_PER_PASS = 64  # realtime: frames read between two steps toward the wall clock
CYCLE_MODULUS = 256
NS_PER_S = 1_000_000_000
RAD_DEG = 180.0 / math.pi
TELEMETRY_PERIOD_NS = 10_000_000
SENSOR_ORDER = ("IMU_RATE", "IMU_ACCEL", "STR_QUAT", "NAV_POS", "NAV_VEL", "THR_STATUS",
                "BENCH_STATUS")
FSW_FRAMES = frozenset({"THR_CMD_0", "THR_CMD_1", "THR_CMD_2", "THR_CMD_3", "FSW_STATUS",
                        "FSW_ATT_EST", "FSW_FDIR", "FAULT_CMD"})
NO_FAILED_THRUSTER = 31  # FSW_FDIR.FailedThruster: none isolated
FAILURE_KINDS = {0: "none", 1: "stuck_closed", 2: "stuck_open", 3: "other"}
NAV_POS_MAX_M = 32.767  # NAV_POS range in the DBC
NAV_VEL_MAX_M_S = 3.2767  # NAV_VEL range in the DBC
HEALTH_WATCHDOG = 0x1
HEALTH_FSW_SILENT = 0x2


def quat_error_deg(q: tuple[float, ...] | np.ndarray, r: tuple[float, ...]) -> float:
    """Rotation angle between attitudes q and r [deg]."""
    d = abs(q[0] * r[0] + q[1] * r[1] + q[2] * r[2] + q[3] * r[3])
    return 2.0 * math.acos(min(1.0, d)) * RAD_DEG


def _same_target(a: FaultSpec, b: FaultSpec) -> bool:
    return (a.kind, a.thruster, a.message, a.node) == (b.kind, b.thruster, b.message, b.node)


def _flip(msg: can.Message, bit: int) -> None:
    """Flip payload bit ``bit`` (0..55) of bytes 1..7 of ``msg`` in place."""
    data = bytearray(msg.data)
    data[1 + bit // 8] ^= 1 << (bit % 8)
    msg.data = data


def _clip(x: float, limit: float) -> float:
    """``x`` limited to the DBC range +-``limit`` (a sensor saturates, it does not wrap)."""
    return min(limit, max(-limit, x))


def _step_ceil(t_ns: int) -> int:
    """``t_ns`` rounded up to the integration grid."""
    return -(-t_ns // STEP_NS) * STEP_NS


def frame_table(db: Database) -> dict[str, dict[str, Any]]:
    """An empty per-message table of the ICD: sender, sent, received, gaps, rejected by cause.

    ``sent`` comes from the sender, the rest from the receiver: :func:`merge_counts` fills
    in one node's view at a time.
    """
    return {
        m.name: {"sender": m.senders[0] if m.senders else "?", "sent": None, "received": None,
                 "gaps": None, "rejected": {}}
        for m in db.messages
    }


def merge_counts(
    table: dict[str, dict[str, Any]], other: dict[str, dict[str, int]], node: str,
    sent: dict[str, int], received: dict[str, dict[str, Any]],
) -> None:
    """Merge what ``node`` sent and received into ``table``.

    Frames that are no message of the ICD (unknown IDs, error frames) are summed per cause
    into ``other[node]``, since every node receives them.
    """
    for name, n in sent.items():
        if name in table:
            table[name]["sent"] = n
    mine = other.setdefault(node, {})
    for name, r in received.items():
        if name in table:
            table[name].update(received=r["received"], gaps=r["gaps"], rejected=r["rejected"])
        else:
            for cause, n in r["rejected"].items():
                mine[cause] = mine.get(cause, 0) + n


def zero_unheard(table: dict[str, dict[str, Any]], reported: set[str]) -> None:
    """Messages their sender sent that no reporting receiver heard: ``received`` 0, not None.

    ``reported``: the nodes whose receive counts were merged (a node that wrote no report
    leaves its messages' reception unknown, None).
    """
    for row in table.values():
        if row["sent"] and row["received"] is None and reported - {row["sender"]}:
            row["received"], row["gaps"] = 0, 0


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

    def __init__(
        self,
        sc: Scenario,
        db: Database,
        bus: can.BusABC,
        run_dir: Path,
        mode: str,
        seed: int,
        bus_spec: str,
        progress: Callable[[float, float], None] | None = None,
    ) -> None:
        self.sc, self.db, self.bus, self.run_dir = sc, db, bus, run_dir
        self.mode, self.seed, self.bus_spec = mode, seed, bus_spec
        self.progress = progress
        self.encoder = Encoder(db)
        self.checker = FrameChecker(db, accept=FSW_FRAMES, own=frozenset(
            m.name for m in db.messages if m.senders and m.senders[0] == BENCH_NODE))
        self.period_ns = cycle_time_ns(db, "THR_CMD_0")
        self.sensor_period_ns = {n: cycle_time_ns(db, n) for n in SENSOR_ORDER}
        self.sensors_sent = tuple(
            n for n in SENSOR_ORDER if sc.rel_nav is not None or not n.startswith("NAV_")
        )
        self._nav_vel: tuple[tuple[float, float, float], bool] = ((0.0, 0.0, 0.0), False)
        self.tick_ns = math.gcd(TELEMETRY_PERIOD_NS, *self.sensor_period_ns.values())
        self.plant = Plant(sc, seed, self.sensor_period_ns["IMU_RATE"], self.period_ns)
        self.events_log: list[dict[str, Any]] = []
        self.n_thr = len(sc.thrusters)
        self.n_cmd_frames = math.ceil(self.n_thr / THRUSTERS_PER_CMD_FRAME)
        self.arbiter = BusArbiter(sc.bus.bitrate_bps)
        self._intermission_ns = wire_time_ns(INTERMISSION_BITS, sc.bus.bitrate_bps)
        # Lockstep: the files' text is formatted while the flight software computes
        # (write_pending before waiting for its commands), not between its frames.
        deferred = mode == "lockstep"
        self.trace = TraceRecorder(run_dir, Clock().wall0_s, deferred)
        self.telemetry = TelemetryWriter(run_dir / "telemetry.csv", self._columns(), deferred)
        self.chains = TelemetryWriter(run_dir / "chains.csv", CHAIN_COLUMNS, deferred)
        self.open_delay_ns = round(sc.valve.open_delay_s * NS_PER_S)
        self._rt_fire_ns: int | None = None
        self.pulses = TelemetryWriter(
            run_dir / "valve_pulses.csv", ["t_on_s", "t_off_s", "thruster"], deferred
        )
        # Lockstep: frames put on the bus wait here until released together (one burst on
        # a bus that takes bursts): a control instant's samples go out with its SYNC.
        self._tx_held: list[can.Message] = []
        self._hold_tx = deferred
        self.sent: dict[str, int] = {}
        self.queue: list[tuple[int, int, str, dict[str, float | int]]] = []
        self.imu_tx_ns: dict[int, int] = {}
        self.latency_ns: list[int] = []
        self.last_cmd_ns = 0
        self.watchdog_tripped = False
        self.watchdog_trips = 0
        self.stalls = 0
        self.consecutive_stalls = 0
        self.fsw_silent = False
        self.late_steps = 0
        self.max_lag_ns = 0  # realtime: how far the plant fell behind the wall clock
        self._rt_clock: Clock | None = None  # realtime: sensor frames go out as sampled
        self._rt_end_ns = 0
        self.wall_origin_s: float | None = None  # realtime: time.time() at the run's t = 0
        self.fsw_status: dict[str, float] = {}
        self.fsw_q_est: tuple[float, float, float, float] | None = None
        self.fsw_q_valid = False
        self.fsw_est_err_deg = float("nan")
        self.faults_log: list[dict[str, Any]] = []
        self.pending_faults = list(sc.faults)
        self.active_faults: list[tuple[FaultSpec, int | None]] = []
        self._active_records: dict[int, dict[str, Any]] = {}  # id(active fault) -> its record
        self.delayed: list[tuple[int, can.Message, str]] = []
        self.fault_cmd_counter = FAULT_CMD_NONE
        self.fault_cmd_rejected = False  # the last FAULT_CMD was refused
        self.fdir: dict[str, Any] = {}
        self.fsw_restarts = 0
        self.fault_counts: dict[str, int] = {
            k: 0 for k in ("dropped", "delayed", "corrupted", "duplicated", "babbled",
                           "failed_attempts")}  # failed_attempts: link_error retransmissions
        self.fault_rng = np.random.default_rng(np.random.SeedSequence([seed, FAULT_RNG_STREAM]))
        self.sender_of = {m.name: (m.senders[0] if m.senders else "") for m in db.messages}
        self.name_of = {m.frame_id: m.name for m in db.messages}
        # THR_STATUS signal names per thruster (Cmd, Open, Current), and all of them
        self._status_signals = [str(s.name) for s in db.get_message_by_name("THR_STATUS").signals
                                if s.name not in ("CRC", "AliveCounter")]
        self._status_names = [(f"Cmd_T{k:02d}", f"Open_T{k:02d}", f"Current_T{k:02d}")
                              for k in range(self.n_thr)]
        self.on_time_last = [0.0] * self.n_thr
        self.tel_t: list[float] = []
        self.tel_err: list[float] = []
        self.tel_rate_err: list[float] = []
        # distance from the reference position ([manoeuvre] r_target_N_m, else the initial one)
        self.tel_pos_err: list[float] = []
        self.wall_s = 0.0
        # lockstep, per cycle: wall time of the whole cycle, and of the wait for the flight
        # software's commands within it (the rest is the bench's own work)
        self.cycle_wall_ns: list[int] = []
        self.fsw_wait_ns: list[int] = []
        # poll this long before blocking for commands (transport.lockstep)
        self.lockstep_spin_s = 0.0
        self.fsw_alive: Callable[[], bool] | None = None
        self._wire_pending: dict[int, tuple[can.Message, bool, int]] = {}
        self.last_sync_ns = 0  # lockstep: time of the run's last SYNC
        self._last_rx_ns = 0  # latest reception on the modelled wire

    # -- telemetry ---------------------------------------------------------------
    def _columns(self) -> list[str]:
        cols = [
            "t_s",
            "q0",
            "q1",
            "q2",
            "q3",
            "wx_rad_s",
            "wy_rad_s",
            "wz_rad_s",
            "rx_m",
            "ry_m",
            "rz_m",
            "vx_m_s",
            "vy_m_s",
            "vz_m_s",
            "att_err_deg",
            "rate_err_deg_s",
            "fsw_q0",
            "fsw_q1",
            "fsw_q2",
            "fsw_q3",
            "fsw_est_err_deg",
            "fsw_mode",
        ]
        cols += [f"thrust_T{k:02d}_N" for k in range(len(self.sc.thrusters))]
        return [*cols, "propellant_kg", "active_faults"]

    def _telemetry_row(self, t_ns: int) -> None:
        s = self.plant.state
        q = s[0:4]
        if self.sc.reference.kind == KIND_STEP:
            err = quat_error_deg(q, self.sc.q_target_BN)
            rate_err = math.sqrt(s[4] ** 2 + s[5] ** 2 + s[6] ** 2) * RAD_DEG
        else:  # a moving reference: errors w.r.t. q_RN(t), omega_RN(t) (bench/reference.py)
            q_ref, w_ref = reference(self.sc.reference, t_ns / NS_PER_S)
            q_t = (s[0], s[1], s[2], s[3])
            err = attitude_error_deg(q_t, q_ref)
            dw = rate_error_B(q_t, (s[4], s[5], s[6]), q_ref, w_ref)
            rate_err = math.sqrt(dw[0] ** 2 + dw[1] ** 2 + dw[2] ** 2) * RAD_DEG
        fq = self.fsw_q_est if (self.fsw_q_est and self.fsw_q_valid) else None
        est_err = self.fsw_est_err_deg if fq else float("nan")
        thr = self.plant.thrusters
        row: list[float | int] = [t_ns / NS_PER_S, *q, *s[4:13], err, rate_err]
        row += list(fq) if fq else [float("nan")] * 4
        row += [est_err, int(self.fsw_status.get("Mode", -1))]
        row += [thr.valves[k].thrust_N(t_ns) for k in range(self.n_thr)]
        row.append(thr.total_propellant_kg)
        row.append(len(self.active_faults))
        self.telemetry.row(row)
        if t_ns >= self.sc.manoeuvre_start_s * NS_PER_S:
            self.tel_t.append(t_ns / NS_PER_S)
            self.tel_err.append(err)
            self.tel_rate_err.append(rate_err)
            self.tel_pos_err.append(math.dist(s[7:10], self.sc.r_reference_N_m))

    # -- sensors -----------------------------------------------------------------
    def _sample(self, name: str, t_ns: int) -> dict[str, float | int]:
        p = self.plant
        s = p.state
        if name == "IMU_RATE":
            w, ok = p.gyro.measure(t_ns, (s[4], s[5], s[6]))
            return {"Valid": int(ok), "RateX": w[0], "RateY": w[1], "RateZ": w[2]}
        if name == "IMU_ACCEL":
            a, ok = p.accel.measure(t_ns, p.specific_force_B())
            return {"Valid": int(ok), "AccelX": a[0], "AccelY": a[1], "AccelZ": a[2]}
        if name == "STR_QUAT":
            q, valid = p.star.sample(t_ns, (s[0], s[1], s[2], s[3]))
            return {"Valid": int(valid), **pack_quaternion(q)}
        if name == "NAV_POS":
            assert p.rel_nav is not None
            pos, vel, ok = p.rel_nav.sample(t_ns, (s[7], s[8], s[9]), (s[10], s[11], s[12]))
            self._nav_vel = (vel, ok)
            return {"Valid": int(ok), "PosX": _clip(pos[0], NAV_POS_MAX_M),
                    "PosY": _clip(pos[1], NAV_POS_MAX_M), "PosZ": _clip(pos[2], NAV_POS_MAX_M)}
        if name == "NAV_VEL":  # sampled with NAV_POS (same solution), sent right after it
            vel, ok = self._nav_vel
            return {"Valid": int(ok), "VelX": _clip(vel[0], NAV_VEL_MAX_M_S),
                    "VelY": _clip(vel[1], NAV_VEL_MAX_M_S), "VelZ": _clip(vel[2], NAV_VEL_MAX_M_S)}
        if name == "THR_STATUS":
            sig: dict[str, float | int] = dict.fromkeys(self._status_signals, 0)
            names = self._status_names
            for k, (cmd, opn, cur) in enumerate(p.thrusters.status(t_ns)):
                sig[names[k][0]], sig[names[k][1]], sig[names[k][2]] = int(cmd), int(opn), int(cur)
            return sig
        # BENCH_STATUS
        health = (HEALTH_WATCHDOG if self.watchdog_tripped else 0) | (
            HEALTH_FSW_SILENT if self.fsw_silent else 0
        )
        return {
            "SimTime": t_ns / NS_PER_S,
            "ActiveFaults": len(self.active_faults),
            "Health": health,
            "FaultCmdCounter": self.fault_cmd_counter,
            "FaultCmdRejected": int(self.fault_cmd_rejected),
        }

    def _queue_due(self, t_ns: int) -> None:
        for name in self.sensors_sent:
            if t_ns % self.sensor_period_ns[name] == 0:
                self.queue.append(
                    (t_ns, self.encoder.frame_id(name), name, self._sample(name, t_ns))
                )

    # -- faults and watchdog -----------------------------------------------------
    def _faults_due(self, t_ns: int) -> None:
        """Start the scheduled faults due at ``t_ns`` and end the expired ones."""
        while self.pending_faults and self.pending_faults[0].t_s * NS_PER_S <= t_ns:
            f = self.pending_faults.pop(0)
            end = t_ns + round(f.duration_s * NS_PER_S) if f.duration_s > 0 else None
            self._start_fault(f, t_ns, end)
        for item in [x for x in self.active_faults if x[1] is not None and x[1] <= t_ns]:
            self.active_faults.remove(item)
            self._end_fault(item[0], t_ns, "duration")
            self.trace.event(t_ns, "fault_cleared", **item[0].record())

    def _start_fault(self, f: FaultSpec, t_ns: int, end_ns: int | None,
                     source: str = "scenario") -> None:
        rec = {**f.record(), "t_s": t_ns / NS_PER_S, "source": source}
        if f.kind in BUS_KINDS and self.mode != "lockstep" and f.kind not in REALTIME_BUS_KINDS:
            rec["applied"] = False
            rec["why"] = (f"{f.kind} acts on the modelled bus (lockstep runs only); in "
                          f"realtime only {', '.join(sorted(REALTIME_BUS_KINDS))} apply")
            self.faults_log.append(rec)
            self.trace.event(t_ns, "fault_injected", **rec)
            return
        if f.thruster is not None:
            self.plant.thrusters.set_fault(f.thruster, f.kind, t_ns, **f.params)
        elif f.sensor is not None:
            self._sensor(f.sensor).set_fault(f.kind, t_ns, **f.params)
        elif f.kind == "bus_off" and f.node is not None:
            until = self.arbiter.bus_off(f.node, t_ns, end_ns)
            rec["until_s"] = until / NS_PER_S
            end_ns = until
        self.active_faults.append((f, end_ns))
        self._active_records[id(f)] = rec
        self.faults_log.append(rec)
        self.trace.event(t_ns, "fault_injected", **rec)

    def _record_events(self) -> None:
        """Log the plant's newly applied mass-property events (events.jsonl, summary)."""
        for t_ns, e in self.plant.applied_events[len(self.events_log):]:
            rec = {**e.record(), "applied_t_s": t_ns / NS_PER_S}
            self.events_log.append(rec)
            self.trace.event(t_ns, "capture", **rec)

    def _sensor(self, name: str) -> Any:
        return {"gyro": self.plant.gyro, "accelerometer": self.plant.accel,
                "star_tracker": self.plant.star}[name]

    def _end_fault(self, f: FaultSpec, t_ns: int, by: str) -> None:
        """Undo the physical effect of ``f`` (bus faults just stop matching frames).

        Its record in ``faults`` (summary.json) gets ``cleared_t_s`` and ``cleared_by``
        (``duration`` or ``FAULT_CMD``).
        """
        rec = self._active_records.pop(id(f), None)
        if rec is not None:
            rec["cleared_t_s"], rec["cleared_by"] = t_ns / NS_PER_S, by
        if f.thruster is not None:
            self.plant.thrusters.clear_fault(f.thruster, f.kind, t_ns)
        elif f.sensor is not None:
            self._sensor(f.sensor).clear_fault(f.kind, t_ns)

    @property
    def active_faults_specs(self) -> list[FaultSpec]:
        """The faults active now, in the order they started."""
        return [f for f, _ in self.active_faults]

    def _watchdog(self, t_ns: int) -> None:
        if (
            not self.watchdog_tripped
            and t_ns - self.last_cmd_ns > WATCHDOG_PERIODS * self.period_ns
        ):
            self.plant.thrusters.close_all(t_ns)
            self.watchdog_tripped = True
            self.watchdog_trips += 1
            self.trace.event(
                t_ns,
                "valve_watchdog",
                action="all valves closed",
                last_command_s=self.last_cmd_ns / NS_PER_S,
            )

    # -- integration -------------------------------------------------------------
    def _next_event_ns(self, t_ns: int) -> int:
        """The next time (after ``t_ns``) at which something besides integration happens."""
        nxt = (t_ns // self.tick_ns + 1) * self.tick_ns
        if self.pending_faults:
            nxt = min(nxt, _step_ceil(round(self.pending_faults[0].t_s * NS_PER_S)))
        for _, t_end in self.active_faults:
            if t_end is not None:
                nxt = min(nxt, _step_ceil(t_end))
        for t_release, _, _ in self.delayed:
            nxt = min(nxt, _step_ceil(t_release))
        if not self.watchdog_tripped:
            nxt = min(
                nxt,
                (self.last_cmd_ns + WATCHDOG_PERIODS * self.period_ns) // STEP_NS * STEP_NS
                + STEP_NS,
            )
        return max(nxt, t_ns + STEP_NS)

    def integrate_to(self, t_end_ns: int) -> None:
        """Advance the plant, sampling sensors and telemetry on the way.

        In lockstep, sensor frames go out as soon as they are sampled (still before the
        SYNC that follows them), so the flight software digests them while the bench
        integrates.
        """
        while self.plant.t_ns < t_end_ns:
            t = min(t_end_ns, self._next_event_ns(self.plant.t_ns))
            self.plant.advance_to(t)
            if len(self.plant.applied_events) > len(self.events_log):
                self._record_events()
            self._faults_due(t)
            if self.delayed:
                self._release_delayed(t)
            self._watchdog(t)
            if t % TELEMETRY_PERIOD_NS == 0:
                self._telemetry_row(t)
            self._queue_due(t)
            if self.queue and self._rt_clock is not None:
                self._send_queue(realtime_ns=self._rt_clock.now_ns())
            elif self.queue and self.mode == "lockstep":
                if t <= self.last_sync_ns:
                    self._send_queue()
                    if t % self.period_ns:  # between control instants: out at once; at
                        self._release_tx()  # one, with its SYNC (run_lockstep)
                else:  # sampled after the last SYNC of the run: that cycle never comes
                    self.queue.clear()

    # -- transmit / receive --------------------------------------------------------
    def _send(
        self,
        name: str,
        signals: dict[str, float | int],
        ready_ns: int,
        realtime_ns: int | None = None,
    ) -> can.Message:
        msg = self.encoder.message(name, signals)
        fate = (frame_fate(self.active_faults_specs, name, BENCH_NODE, self.fault_rng)
                if self.active_faults else NO_FATE)
        if name == "IMU_RATE":
            self.imu_tx_ns[msg.data[1] & 0x0F] = ready_ns if realtime_ns is None else realtime_ns
        if fate is not NO_FATE:
            if fate.drop:
                self.fault_counts["dropped"] += 1
                return msg
            if fate.delay_ns and realtime_ns is None:
                self.fault_counts["delayed"] += 1
                self.delayed.append((ready_ns + fate.delay_ns, msg, name))
                return msg
            if fate.corrupt_bit is not None:
                self.fault_counts["corrupted"] += 1
                _flip(msg, fate.corrupt_bit)
        copies = 2 if fate.duplicate else 1
        if copies == 2:
            self.fault_counts["duplicated"] += 1
        self.fault_counts["failed_attempts"] += fate.failed_attempts
        for _ in range(copies):
            self._put_on_bus(msg, name, ready_ns, realtime_ns, fate.failed_attempts)
        return msg

    def _put_on_bus(self, msg: can.Message, name: str, ready_ns: int, realtime_ns: int | None,
                    failed_attempts: int = 0) -> None:
        if self._hold_tx:
            self._tx_held.append(msg)
        else:
            self.bus.send(msg)
        self.sent[name] = self.sent.get(name, 0) + 1
        bits = frame_bits(msg.arbitration_id, bytes(msg.data))
        if realtime_ns is not None:
            self.trace.frame(msg, realtime_ns, tx=True, t_ready_ns=realtime_ns, t_rx_ns=NAN,
                             bits=bits)
        else:
            seq = self.arbiter.submit(ready_ns, msg.arbitration_id, bits, node=BENCH_NODE,
                                      failed_attempts=failed_attempts)
            self._wire_pending[seq] = (msg, True, bits)

    def _release_delayed(self, t_ns: int) -> None:
        """Put delayed bench frames whose time has come on the bus."""
        due = [d for d in self.delayed if d[0] <= t_ns]
        for item in sorted(due, key=lambda d: (d[0], d[1].arbitration_id)):
            self.delayed.remove(item)
            self._put_on_bus(item[1], item[2], item[0], None)

    def _babble(self, t0_ns: int, t1_ns: int) -> None:
        """Frames of the active babbling nodes for [t0, t1): on the bus and on the wire model."""
        for f in self.active_faults_specs:
            if f.kind != "babbling":
                continue
            step = round(NS_PER_S / f.params["rate_hz"])
            t = -(-t0_ns // step) * step
            while t < t1_ns:
                data = bytes(self.fault_rng.integers(0, 256, 8, dtype=np.uint8))
                msg = can.Message(arbitration_id=int(f.params["can_id"]), is_extended_id=False,
                                  data=data)
                if self._hold_tx:
                    self._tx_held.append(msg)
                else:
                    self.bus.send(msg)
                self.fault_counts["babbled"] += 1
                bits = frame_bits(msg.arbitration_id, data)
                seq = self.arbiter.submit(t, msg.arbitration_id, bits, node=str(f.node))
                self._wire_pending[seq] = (msg, True, bits)
                t += step

    def _flush_wire(self, until_ns: int | None = None) -> dict[int, int]:
        """Resolve bus arbitration; record frames in wire order. Returns seq -> rx time.

        A frame's failed attempts (link_error) go into the trace as error frames, stamped
        at their end, in time order with the frames delivered meanwhile.
        """
        rx: dict[int, int] = {}
        entries: list[tuple[int, int, Delivery | None]] = []  # (time, 0 error / 1 frame, ...)
        errors = False
        for d in self.arbiter.resolve(until_ns):
            if d.failed_ns:
                errors = True
                entries.extend((end - self._intermission_ns, 0, None) for _s, end in d.failed_ns)
            t_rx = d.end_ns - self._intermission_ns  # received at the end of EOF
            entries.append((t_rx, 1, d))
            rx[d.seq] = t_rx
            self._last_rx_ns = max(self._last_rx_ns, t_rx)
        if errors:
            entries.sort(key=lambda e: (e[0], e[1]))  # stable: frames keep their wire order
        for t, _kind, frame in entries:  # not `d`: that name is a Delivery above
            if frame is None:
                self.trace.error_frame(t)
                continue
            msg, tx, bits = self._wire_pending.pop(frame.seq)
            self.trace.frame(msg, t, tx=tx, t_ready_ns=frame.ready_ns,
                             t_start_ns=frame.start_ns, bits=bits)
        return rx

    def _send_queue(self, realtime_ns: int | None = None) -> None:
        self.queue.sort(key=lambda f: (f[0], f[1]))
        for t_ns, _id, name, sig in self.queue:
            self._send(name, sig, t_ns, realtime_ns)
        self.queue.clear()

    def _release_tx(self) -> None:
        """Hand the held frames to the bus, in order, together (see
        transport.lockstep.send_frames)."""
        if self._tx_held:
            send_frames(self.bus, self._tx_held)
            self._tx_held = []

    def _flush_files(self) -> None:
        """Flush the run files to disk (a crash loses at most the last few cycles)."""
        self.trace.flush()
        self.telemetry.flush()
        self.pulses.flush()
        self.chains.flush()

    def _write_pending(self) -> None:
        """Format the run files' deferred rows and trace lines (lockstep)."""
        self.trace.write_pending()
        self.telemetry.write_pending()
        self.pulses.write_pending()
        self.chains.write_pending()

    def _on_fsw_frame(self, d_name: str, s: dict[str, float], counter: int = 0) -> None:
        if d_name == "FAULT_CMD":
            self._on_fault_cmd(s, counter)
        elif d_name == "FSW_FDIR":
            self._on_fdir(s)
        elif d_name == "FSW_STATUS":
            if int(s["Mode"]) == MODE_BOOT and self.fsw_status.get("Mode", MODE_BOOT) != MODE_BOOT:
                # the flight software booted again: its counters restart, its state is new
                self.fsw_restarts += 1
                self.trace.event(self.plant.t_ns, "fsw_restart", count=self.fsw_restarts)
            self.fsw_status = s
        elif d_name == "FSW_ATT_EST":
            self.fsw_q_est = unpack_quaternion(s)
            # the estimate is of the cycle's time t_k, which is where the plant is now (lockstep)
            self.fsw_est_err_deg = quat_error_deg(self.plant.state[0:4], self.fsw_q_est)
            self.fsw_q_valid = bool(s["Valid"])

    def _on_fdir(self, s: dict[str, float]) -> None:
        """Keep the flight software's latest FDIR report and record its first isolation."""
        failed = int(s["FailedThruster"])
        report = {
            "available_mask": int(s["AvailableMask"]),
            "failed_thruster": None if failed == NO_FAILED_THRUSTER else failed,
            "failure_kind": FAILURE_KINDS.get(int(s["FailureKind"]), "other"),
            "detection_time_s": float(s["DetectionTime"]) or None,
            "isolation_delay_s": float(s["IsolationDelay"]),
            "sensor_flags": int(s["SensorFlags"]),
        }
        if report["failed_thruster"] is not None and self.fdir.get("failed_thruster") is None:
            self.trace.event(self.plant.t_ns, "fsw_isolated", **report)
        self.fdir = report

    def _on_fault_cmd(self, s: dict[str, float], counter: int) -> None:
        """A live FAULT_CMD: inject or clear, acknowledged in BENCH_STATUS.FaultCmdCounter.

        A command this bench cannot apply is acknowledged with FaultCmdRejected = 1 and
        recorded (events.jsonl, and summary.json's ``faults`` with ``applied: false``).
        """
        self.fault_cmd_counter = counter
        t = max(self.plant.t_ns, self.last_cmd_ns)  # valve events must stay in time order
        try:
            spec = fault_from_command(s, self.name_of, self.n_thr, t / NS_PER_S)
        except ValueError as exc:  # ConfigError: a value this bench cannot apply
            self.fault_cmd_rejected = True
            fields = {k: float(v) for k, v in s.items() if k not in ("CRC", "AliveCounter")}
            self.faults_log.append({**fields, "t_s": t / NS_PER_S, "source": "FAULT_CMD",
                                    "applied": False, "why": str(exc)})
            self.trace.event(t, "fault_cmd_rejected", **fields, why=str(exc))
            return
        self.fault_cmd_rejected = False
        if int(s["Action"]) == 0:
            for item in [x for x in self.active_faults if _same_target(x[0], spec)]:
                self.active_faults.remove(item)
                self._end_fault(item[0], t, "FAULT_CMD")
                self.trace.event(t, "fault_cleared", **item[0].record(), source="FAULT_CMD")
            return
        end = t + round(spec.duration_s * NS_PER_S) if spec.duration_s > 0 else None
        self._start_fault(spec, t, end, source="FAULT_CMD")

    def _apply_command(self, s: dict[str, float], frame_index: int, t_rx_ns: int) -> bool:
        """Deliver one THR_CMD frame to its valves at ``t_rx_ns``; True if any valve fires."""
        fires = False
        for j in range(THRUSTERS_PER_CMD_FRAME):
            k = frame_index * THRUSTERS_PER_CMD_FRAME + j
            if k >= self.n_thr:
                break
            on_s = float(s[f"OnTime_T{k:02d}"])
            on_ns = round(on_s * NS_PER_S)
            self.plant.thrusters.command(t_rx_ns, k, on_ns)
            self.on_time_last[k] = on_s
            if on_ns > 0:
                fires = True
                self.pulses.row([t_rx_ns / NS_PER_S, (t_rx_ns + on_ns) / NS_PER_S, k])
        return fires

    def _chain(self, cycle: int, imu_counter: int, t_cmd_ns: int, t_fire_ns: int | None) -> None:
        """One row of chains.csv: IMU sample -> last command frame -> first valve opening.

        ``t_fire_ns``: receipt of the first command frame that fires a valve (the opening
        follows it by the valve's opening delay), None when no valve fires this cycle.
        """
        t_imu = self.imu_tx_ns.get(imu_counter)
        if t_imu is not None:
            self.latency_ns.append(t_cmd_ns - t_imu)
        t_fire = NAN if t_fire_ns is None else t_fire_ns / NS_PER_S
        t_open = NAN if t_fire_ns is None else (t_fire_ns + self.open_delay_ns) / NS_PER_S
        self.chains.row([cycle, imu_counter, NAN if t_imu is None else t_imu / NS_PER_S,
                         t_cmd_ns / NS_PER_S, t_fire, t_open])

    # -- lockstep ----------------------------------------------------------------
    def wait_for_fsw(self) -> None:
        """Wait for the flight software's first valid frame (its boot heartbeat).

        Every frame heard meanwhile goes into the trace at t = 0 (as a CAN logger records
        what precedes a run), bad ones too; only the valid one ends the wait.
        """
        deadline = time.monotonic() + self.sc.bus.startup_timeout_s
        while time.monotonic() < deadline:
            if self.fsw_alive is not None and not self.fsw_alive():
                raise RunError(
                    "the flight-software process exited before its first frame "
                    "(see fsw.log in the run folder)"
                )
            msg = self.bus.recv(timeout=min(STARTUP_POLL_S, max(0.0, deadline - time.monotonic())))
            if msg is None:
                continue
            d = self.checker.check(msg)
            # bits 0: before the run, off the modelled wire (the timing analysis skips it)
            self.trace.frame(msg, 0, tx=False, t_rx_ns=0 if d is not None else NAN)
            if d is not None:
                self._on_fsw_frame(d.name, d.signals, d.counter)
                return
        raise RunError(
            f"no flight software on bus {self.bus_spec} within "
            f"{self.sc.bus.startup_timeout_s} s (expected its FSW_STATUS heartbeat)"
        )

    def run_lockstep(self, duration_s: float) -> None:
        """Lockstep run of ``duration_s`` simulated seconds."""
        n_cycles = round(duration_s * NS_PER_S / self.period_ns)
        self.last_sync_ns = (n_cycles - 1) * self.period_ns
        delay_ns = round(self.sc.bus.fsw_response_delay_s * NS_PER_S)
        self.wait_for_fsw()
        self.trace.event(0, "run_started", mode=self.mode, seed=self.seed, cycles=n_cycles)
        wall0 = time.monotonic()
        self._faults_due(0)  # a fault at t = 0 acts on the first samples too
        self._queue_due(0)
        self._telemetry_row(0)
        for k in range(n_cycles):
            t_k = k * self.period_ns
            cycle_wall0_ns = time.monotonic_ns()
            self._send_queue()
            # SYNC closes the samples of (t_{k-1}, t_k]: it is queued once they are through,
            # and the flight software's cycle starts when SYNC has arrived.
            self._flush_wire()
            self._send("SYNC", {"Cycle": k, "SimTime": t_k / NS_PER_S},
                       max(t_k, self._last_rx_ns))
            self._release_tx()
            self._flush_wire()
            self._collect_lockstep(k, self._last_rx_ns + delay_ns)
            self.integrate_to(t_k + self.period_ns)
            if k % FLUSH_EVERY_CYCLES == 0 and self.progress is not None:
                self.progress(t_k / NS_PER_S, duration_s)
            self.cycle_wall_ns.append(time.monotonic_ns() - cycle_wall0_ns)
        self._release_tx()
        self._flush_wire()
        self.queue.clear()
        self.wall_s = time.monotonic() - wall0
        self.trace.event(self.plant.t_ns, "run_finished", stalls=self.stalls)

    def _collect_lockstep(self, k: int, ready_ns: int) -> None:
        """Receive this cycle's commands, deliver them at their modelled arrival."""
        # While the flight software computes: integrate the steps that end before its
        # frames can arrive, and record the bench's own frames already on the wire.
        self.integrate_to(max(self.plant.t_ns, ready_ns // STEP_NS * STEP_NS))
        self._flush_wire(ready_ns)
        self._babble(k * self.period_ns, (k + 1) * self.period_ns)
        self._release_tx()  # delayed frames released meanwhile
        self._write_pending()
        if k % FLUSH_EVERY_CYCLES == 0:
            self._flush_files()
        want = self.n_cmd_frames
        got: list[tuple[int, int, dict[str, float], int]] = []  # (frame, seq, signals, delay)
        lost = 0  # command frames that faults kept from the bench this cycle
        fsw_dead = self.fsw_alive is not None and not self.fsw_alive()
        timeout = 0.0 if (self.fsw_silent or fsw_dead) else self.sc.bus.stall_timeout_s
        wait0_ns = time.monotonic_ns()
        deadline = time.monotonic() + timeout
        imu_counter = None
        while len(got) + lost < want:
            remaining = deadline - time.monotonic()
            msg = recv_spinning(self.bus, max(0.0, remaining), self.lockstep_spin_s)
            if msg is None:
                break
            name = self.name_of.get(msg.arbitration_id)
            fate = (frame_fate(self.active_faults_specs, name, self.sender_of[name], self.fault_rng)
                    if self.active_faults and name is not None else NO_FATE)
            if not self._take_rx_fate(msg, fate):
                lost += bool(name and name.startswith("THR_CMD_"))
                continue
            self.fault_counts["delayed"] += bool(fate.delay_ns)
            self.fault_counts["failed_attempts"] += fate.failed_attempts
            for _copy in range(2 if fate.duplicate else 1):
                bits = frame_bits(msg.arbitration_id, bytes(msg.data))
                d = self.checker.check(msg)
                # A frame of the flight software's cycle goes on the modelled wire: one that
                # passes the checks, or one an injected bus fault spoiled. Anything else
                # (unknown IDs, error frames, malformed impostors of known IDs) arrives at
                # a wall-clock moment that has no place in simulated time: trace only, so
                # garbage on the bus cannot shift a lockstep run (tests/e2e/test_flood.py).
                faulted = fate.corrupt_bit is not None or fate.duplicate
                if (name is not None and self.sender_of[name] != BENCH_NODE
                        and (d is not None or faulted)):
                    seq = self.arbiter.submit(ready_ns, msg.arbitration_id, bits,
                                              node=self.sender_of[name],
                                              failed_attempts=fate.failed_attempts)
                    self._wire_pending[seq] = (msg, False, bits)
                else:
                    seq = -1
                    self.trace.frame(msg, ready_ns, tx=False, t_rx_ns=NAN, bits=bits)
                if d is None:
                    if name is not None and name.startswith("THR_CMD_") and _copy == 0:
                        lost += 1  # rejected (e.g. corrupted): this cycle will not get it
                    continue
                s: dict[str, float] = d.signals
                if d.name.startswith("THR_CMD_"):
                    if int(s["Cycle"]) != k % CYCLE_MODULUS:
                        self.checker.reject(d.name, Reject.STALE)
                        continue
                    got.append((int(d.name[-1]), seq, s, fate.delay_ns))
                    imu_counter = int(s["ImuCounter"])
                else:
                    self._on_fsw_frame(d.name, s, d.counter)
        self.fsw_wait_ns.append(time.monotonic_ns() - wait0_ns)
        rx = self._flush_wire(ready_ns + self.period_ns)
        if len(got) + lost < want:
            self.stalls += 1
            self.consecutive_stalls += 1
            if not self.fsw_silent:
                self.trace.event(k * self.period_ns, "stall", cycle=k, frames=len(got))
            if self.consecutive_stalls >= SILENT_AFTER_STALLS and not self.fsw_silent:
                self.fsw_silent = True
                self.trace.event(k * self.period_ns, "fsw_silent", cycle=k)
        else:
            if self.fsw_silent:
                self.trace.event(k * self.period_ns, "fsw_back", cycle=k)
            self.consecutive_stalls = 0
            self.fsw_silent = False
        if not got:
            return
        t_last = 0
        t_fire: int | None = None
        for index, seq, s, delay_ns in sorted(got, key=lambda g: (g[0], g[1])):
            t_rx = rx[seq] + delay_ns
            t_last = max(t_last, t_rx)
            if self._apply_command(s, index, t_rx) and (t_fire is None or t_rx < t_fire):
                t_fire = t_rx
        self.last_cmd_ns = t_last
        if self.watchdog_tripped:
            self.trace.event(t_last, "valve_watchdog_cleared")
            self.watchdog_tripped = False
        if imu_counter is not None:
            self._chain(k, imu_counter, t_last, t_fire)

    # -- realtime ----------------------------------------------------------------
    def run_realtime(self, duration_s: float, clock: Clock | None = None) -> None:
        """Wall-clock-paced run of ``duration_s`` seconds.

        A bench slower than the wall clock (an overloaded or emulated machine) still ends
        at ``duration_s`` of plant time: each pass steps the plant to the clock, then reads
        at most ``RT_FRAMES_PER_PASS`` frames, so neither catching up nor a stream of
        frames can keep it from sending sensors or from ending. Every pass, and every
        command frame, that finds the plant more than a control period behind the clock is
        counted (``bench_late``) and the largest lag is reported (``bench_max_lag_ms``):
        such a run's timing figures are not real time.
        """
        self.wait_for_fsw()
        self.trace.event(0, "run_started", mode=self.mode, seed=self.seed)
        clock = clock or Clock()
        self.wall_origin_s = clock.wall0_s
        end_ns = round(duration_s * NS_PER_S)
        self._rt_end_ns = end_ns
        self._faults_due(0)  # a fault at t = 0 acts on the first samples too
        self._queue_due(0)
        self._telemetry_row(0)
        self._send_queue(realtime_ns=clock.now_ns())
        self._rt_clock = clock
        next_progress = 0
        while self.plant.t_ns < end_ns:
            self._note_lag(clock.now_ns())
            self.integrate_to(min(clock.now_ns(), end_ns) // STEP_NS * STEP_NS)
            wait_s = max(0.0, (self.plant.t_ns + STEP_NS - clock.now_ns()) / NS_PER_S)
            msg = self.bus.recv(timeout=wait_s)
            n_read = 0
            while msg is not None:
                self._on_realtime_frame(msg, clock)
                n_read += 1
                if n_read >= RT_FRAMES_PER_PASS or self.plant.t_ns >= end_ns:
                    break  # back to stepping; the rest stays queued for the next pass
                msg = self.bus.recv(timeout=0.0)
            if self.plant.t_ns >= next_progress:
                self.trace.flush()
                self.telemetry.flush()
                self.pulses.flush()
                self.chains.flush()
                if self.progress is not None:
                    self.progress(self.plant.t_ns / NS_PER_S, duration_s)
                next_progress += 5 * self.period_ns
        self._rt_clock = None
        self.wall_s = clock.now_ns() / NS_PER_S
        self.trace.event(self.plant.t_ns, "run_finished", late_steps=self.late_steps,
                         max_lag_ms=self.max_lag_ns / 1e6)

    def _note_lag(self, now_ns: int) -> None:
        """Realtime: how far the plant is behind the clock before it catches up."""
        lag_ns = now_ns - self.plant.t_ns
        self.max_lag_ns = max(self.max_lag_ns, lag_ns)
        if lag_ns > self.period_ns:
            self.late_steps += 1

    def _on_realtime_frame(self, msg: can.Message, clock: Clock) -> None:
        """A frame read in realtime: the active drop/corrupt/duplicate faults, then its effect."""
        name = self.name_of.get(msg.arbitration_id)
        if self.active_faults and name is not None and self.sender_of[name] != BENCH_NODE:
            fate = frame_fate(self.active_faults_specs, name, self.sender_of[name],
                              self.fault_rng)
            if not self._take_rx_fate(msg, fate):
                return
            if fate.duplicate:
                self._realtime_frame(msg, clock)
        self._realtime_frame(msg, clock)

    def _take_rx_fate(self, msg: can.Message, fate: Fate) -> bool:
        """Count the bus faults' ``fate`` of a received frame and corrupt ``msg`` as it says.

        Shared by both run modes; False when the frame is dropped (never seen). Duplicates
        are counted here and delivered twice by the caller.
        """
        if fate.drop:
            self.fault_counts["dropped"] += 1
            return False
        if fate.corrupt_bit is not None:
            self.fault_counts["corrupted"] += 1
            _flip(msg, fate.corrupt_bit)
        self.fault_counts["duplicated"] += fate.duplicate
        return True

    def _realtime_frame(self, msg: can.Message, clock: Clock) -> None:
        """Trace every frame heard (as a CAN logger would, bad ones too), act on good ones."""
        t_ns = clock.now_ns()
        d = self.checker.check(msg)
        tx_wall = getattr(msg, "tx_timestamp", None)  # the portable bus carries the sender's time
        self.trace.frame(
            msg, t_ns, tx=False,
            t_ready_ns=NAN if tx_wall is None else clock.from_wall_ns(tx_wall),
            t_rx_ns=clock.from_wall_ns(msg.timestamp) if msg.timestamp > 0 else t_ns,
            bits=frame_bits(msg.arbitration_id, bytes(msg.data)),
        )
        if d is None:
            return
        s: dict[str, float] = d.signals
        if d.name.startswith("THR_CMD_"):
            self._note_lag(t_ns)
            self.integrate_to(min(self._rt_end_ns, max(self.plant.t_ns, t_ns // STEP_NS * STEP_NS)))
            t_apply = max(t_ns, self.plant.t_ns)
            index = int(d.name[-1])
            if self._apply_command(s, index, t_apply):
                self._rt_fire_ns = t_apply if self._rt_fire_ns is None else self._rt_fire_ns
            self.last_cmd_ns = t_apply
            self.watchdog_tripped = False
            self.fsw_silent = False
            if index == self.n_cmd_frames - 1:
                self._chain(int(s["Cycle"]), int(s["ImuCounter"]), t_ns, self._rt_fire_ns)
                self._rt_fire_ns = None
        else:
            self._on_fsw_frame(d.name, s, d.counter)

    # -- results -----------------------------------------------------------------
    def summary(self, sim_time_s: float) -> dict[str, Any]:
        """summary.json content from the bench's side."""
        sc = self.sc
        pm = pointing_metrics(
            np.asarray(self.tel_t),
            np.asarray(self.tel_err),
            np.asarray(self.tel_rate_err),
            sc.expectations.settling_band_deg,
            sc.expectations.steady_state_window_s,
            sc.manoeuvre_start_s,
        )
        frames = frame_table(self.db)
        other: dict[str, dict[str, int]] = {}
        merge_counts(frames, other, BENCH_NODE, self.sent, self.checker.summary())
        e = sc.expectations
        pos, t_arr = np.asarray(self.tel_pos_err), np.asarray(self.tel_t)
        pos_final = float(pos[-1]) if len(pos) else 0.0
        pos_ss = float(pos[t_arr >= t_arr[-1] - e.steady_state_window_s].max()) if len(pos) else 0.0
        pos_settling = (
            settling_time_s(t_arr, pos, e.position_band_m, sc.manoeuvre_start_s)
            if e.position_band_m is not None else None
        )
        rate_settling = (
            settling_time_s(t_arr, np.asarray(self.tel_rate_err), e.rate_settling_band_deg_s,
                            sc.manoeuvre_start_s)
            if e.rate_settling_band_deg_s is not None else None
        )
        exps = [
            x
            for x in (
                settling_expectation("settling_time_s", pm.settling_time_s,
                                     e.settling_time_s_max, e.settling_band_deg, "deg"),
                settling_expectation("rate_settling_time_s", rate_settling,
                                     e.rate_settling_time_s_max, e.rate_settling_band_deg_s,
                                     "deg/s"),
                expectation(
                    "steady_state_attitude_error_deg",
                    pm.steady_state_attitude_error_deg,
                    e.steady_state_attitude_error_deg_max,
                ),
                expectation(
                    "steady_state_rate_error_deg_s",
                    pm.steady_state_rate_error_deg_s,
                    e.steady_state_rate_error_deg_s_max,
                ),
                expectation("steady_state_position_error_m", pos_ss,
                            e.steady_state_position_error_m_max),
                expectation("final_position_error_m", pos_final, e.final_position_error_m_max),
                settling_expectation("position_settling_time_s", pos_settling,
                                     e.position_settling_time_s_max, e.position_band_m, "m"),
            )
            if x is not None
        ]
        thr = self.plant.thrusters
        return {
            "scenario": sc.name,
            "scenario_file": sc.path,
            "overrides": list(sc.overrides),
            "mode": self.mode,
            "seed": self.seed,
            "bus": self.bus_spec,
            "bitrate_bps": sc.bus.bitrate_bps,
            "sim_time_s": sim_time_s,
            "wall_time_s": round(self.wall_s, 3),
            "wall_clock_origin_s": self.wall_origin_s,
            "realtime_factor": round(sim_time_s / self.wall_s, 2) if self.wall_s > 0 else None,
            "converged": pm.converged,
            "settling_band_deg": sc.expectations.settling_band_deg,
            "settling_time_s": pm.settling_time_s,
            "steady_state_attitude_error_deg": pm.steady_state_attitude_error_deg,
            "steady_state_rate_error_deg_s": pm.steady_state_rate_error_deg_s,
            "final_attitude_error_deg": pm.final_attitude_error_deg,
            "final_position_error_m": pos_final,
            "steady_state_position_error_m": pos_ss,
            "position_band_m": e.position_band_m,
            "position_settling_time_s": pos_settling,
            "rate_settling_band_deg_s": e.rate_settling_band_deg_s,
            "rate_settling_time_s": rate_settling,
            "reference_kind": sc.reference.kind,
            "translation": sc.dynamics.translation,
            "valve_model": sc.valve.model,
            "events": self.events_log,
            "propellant_kg": thr.total_propellant_kg,
            "valve_openings": {"total": int(sum(thr.openings)), "per_thruster": list(thr.openings)},
            "frames": frames,
            "rejected_other": other,
            "latency_us": {"sensor_to_command": latency_summary(self.latency_ns)},
            "lockstep_wall_us": None if self.mode != "lockstep" else {
                "cycle": latency_summary(self.cycle_wall_ns),
                "waiting_for_fsw": latency_summary(self.fsw_wait_ns),
                "spin_s": self.lockstep_spin_s,
            },
            "deadline_misses": {
                "bench_late": self.late_steps,
                "bench_max_lag_ms": round(self.max_lag_ns / 1e6, 3),
                "stalls": self.stalls,
                "fsw_overruns": int(self.fsw_status.get("Overruns", 0)),
            },
            "valve_watchdog_trips": self.watchdog_trips,
            "fsw_restarts": self.fsw_restarts,
            "faults": self.faults_log,
            "fault_effects": dict(self.fault_counts),
            "fdir": self.fdir,
            "expectations": exps,
            "passed": all(x["pass"] for x in exps) and pm.converged,
        }

    def close(self, sim_time_s: float) -> dict[str, Any]:
        """Finish files and write summary.json; returns the summary."""
        self.trace.close()
        self.telemetry.close()
        self.pulses.close()
        self.chains.close()
        summary = self.summary(sim_time_s)
        write_summary(self.run_dir / "summary.json", summary)
        return summary
