"""The results room: everything a run measures, written as it goes, and summary.json.

In (from the node, as the run goes): telemetry instants (bench.results.telemetry), valve
pulses, the IMU_RATE samples sent (alive counter -> time sent [ns]) and, per control
cycle, the IMU sample a command was computed from, the last command's and the first
firing command's reception [ns] (-> ``chains.csv`` and the sensor-to-command latency),
stalls, the lockstep cycle's wall time and its wait for the flight software [ns], the
realtime plant's lag behind the wall clock [ns]. Out: ``telemetry.csv``, ``chains.csv``,
``valve_pulses.csv`` (flushed as the run goes; at the lean record level telemetry at a
tenth of the rate and no chains or pulses, bench.results.record) and the bench's part of
``summary.json`` (:meth:`Results.summary`), built from these and from the station, the
wire and the receive path at the end.

Units: times in the files and the summary in seconds, latencies in microseconds.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bench.results.counts import frame_table, merge_counts
from bench.results.fsw_view import FswView
from bench.results.metrics import latency_summary
from bench.results.record import LEAN_TELEMETRY_EVERY, RECORD_FULL, file_name, writes_tables
from bench.results.summary import expectations_and_metrics, net_translation
from bench.results.telemetry import Telemetry
from bench.results.writers import CHAIN_COLUMNS, PULSE_COLUMNS, TelemetryWriter
from bench.scenario.spec import Scenario
from bench.station.station import Pulse, Station
from bench.wire.receipt import Receipt
from bench.wire.wire import Wire
from dbc.icd import BENCH, Icd
from dbc.records import Distribution

NAN = float("nan")
NS_PER_S = 1_000_000_000
NS_PER_MS = 1e6
MEASURED_QUANTUM_NS = 1000  # resolution kept of wall-clock measurements [ns]


class Results:
    """One run's measurements (see the module docstring)."""

    def __init__(self, sc: Scenario, icd: Icd, run_dir: Path, mode: str, seed: int,
                 bus_spec: str, n_thrusters: int, open_delay_ns: int,
                 record: str = RECORD_FULL) -> None:
        self.sc, self.icd, self.mode, self.seed, self.bus_spec = sc, icd, mode, seed, bus_spec
        self.record = record
        deferred = mode == "lockstep"

        def path(base: str) -> Path:
            return run_dir / file_name(base, record)

        tables = writes_tables(record)
        self.telemetry = Telemetry(sc, path("telemetry.csv"), n_thrusters, deferred,
                                   1 if tables else LEAN_TELEMETRY_EVERY)
        # chains.csv and valve_pulses.csv: not at the lean level (their figures are streamed)
        self.chains: TelemetryWriter | None = None
        self.pulses: TelemetryWriter | None = None
        if tables:
            self.chains = TelemetryWriter(path("chains.csv"), CHAIN_COLUMNS, deferred)
            self.pulses = TelemetryWriter(path("valve_pulses.csv"), PULSE_COLUMNS, deferred)
        self.fsw = FswView(icd)
        self._open_delay_ns = open_delay_ns
        self.imu_tx_ns: dict[int, int] = {}
        # per control cycle, as counts per value (memory in distinct values, not cycles):
        # modelled lockstep latencies exact to the ns, wall-clock measures to the us
        self.latency_ns = Distribution(1 if mode == "lockstep" else MEASURED_QUANTUM_NS)
        self.cycle_wall_ns = Distribution(MEASURED_QUANTUM_NS)
        self.fsw_wait_ns = Distribution(MEASURED_QUANTUM_NS)
        # the rest of a lockstep cycle, in its order (bench.lockstep): the samples and SYNC
        # handed over; the bench's work while the flight software computes, until it waits;
        # (the wait); the commands delivered and the integration to the next cycle
        self.before_sync_ns = Distribution(MEASURED_QUANTUM_NS)
        self.meanwhile_ns = Distribution(MEASURED_QUANTUM_NS)
        self.after_commands_ns = Distribution(MEASURED_QUANTUM_NS)
        self.stalls = 0
        self.late_steps = 0
        self.max_lag_ns = 0
        self.wall_s = 0.0
        self.wall_origin_s: float | None = None
        self.lockstep_spin_s = 0.0

    # -- as the run goes -------------------------------------------------------------
    def add_pulses(self, pulses: list[Pulse]) -> None:
        """Commanded valve pulses (valve_pulses.csv)."""
        if self.pulses is None:
            return
        for p in pulses:
            self.pulses.row([p[0], p[1], p[2]])

    def chain(self, cycle: int, imu_counter: int, t_cmd_ns: int, t_fire_ns: int | None) -> None:
        """One row of chains.csv: IMU sample -> last command frame -> first valve opening.

        ``t_fire_ns``: receipt of the first command frame that fires a valve (the opening
        follows it by the valve's opening delay), None when no valve fires this cycle.
        """
        t_imu = self.imu_tx_ns.get(imu_counter)
        if t_imu is not None:
            self.latency_ns.add(t_cmd_ns - t_imu)
        if self.chains is None:
            return
        t_fire = NAN if t_fire_ns is None else t_fire_ns / NS_PER_S
        t_open = NAN if t_fire_ns is None else (t_fire_ns + self._open_delay_ns) / NS_PER_S
        self.chains.row([cycle, imu_counter, NAN if t_imu is None else t_imu / NS_PER_S,
                         t_cmd_ns / NS_PER_S, t_fire, t_open])

    def note_lag(self, lag_ns: int, period_ns: int) -> None:
        """Realtime: the plant is ``lag_ns`` behind the wall clock."""
        self.max_lag_ns = max(self.max_lag_ns, lag_ns)
        if lag_ns > period_ns:
            self.late_steps += 1

    def write_pending(self) -> None:
        """Format the deferred rows (lockstep: while the flight software computes)."""
        self.telemetry.writer.write_pending()
        for w in (self.pulses, self.chains):
            if w is not None:
                w.write_pending()

    def flush(self) -> None:
        """Flush the files to disk."""
        self.telemetry.writer.flush()
        for w in (self.pulses, self.chains):
            if w is not None:
                w.flush()

    def close(self) -> None:
        """Finish the files."""
        self.telemetry.writer.close()
        for w in (self.pulses, self.chains):
            if w is not None:
                w.close()

    # -- at the end ------------------------------------------------------------------
    def summary(self, sim_time_s: float, station: Station, wire: Wire,
                receipt: Receipt) -> dict[str, Any]:
        """summary.json content from the bench's side."""
        sc = self.sc
        frames = frame_table(self.icd)
        other: dict[str, dict[str, int]] = {}
        merge_counts(frames, other, BENCH, wire.sent, receipt.checker.summary())
        thr = station.plant.thrusters
        out: dict[str, Any] = {
            "scenario": sc.name,
            "scenario_file": sc.path,
            "overrides": list(sc.overrides),
            "mode": self.mode,
            "seed": self.seed,
            "record": self.record,
            "bus": self.bus_spec,
            "bitrate_bps": sc.bus.bitrate_bps,
            "sim_time_s": sim_time_s,
            "wall_time_s": round(self.wall_s, 3),
            "wall_clock_origin_s": self.wall_origin_s,
            "realtime_factor": round(sim_time_s / self.wall_s, 2) if self.wall_s > 0 else None,
        }
        moved = net_translation(sc, tuple(station.plant.state[7:10]),
                                tuple(station.plant.state[10:13]))
        out.update(expectations_and_metrics(sc, self.telemetry.errors, moved["delta_v_m_s"]))
        out.update({
            "reference_kind": sc.reference.kind,
            "translation": sc.dynamics.translation,
            "valve_model": sc.valve.model,
            "events": station.captures,
            "net_translation": moved,
            "propellant_kg": thr.total_propellant_kg,
            "valve_openings": {"total": int(sum(thr.openings)),
                               "per_thruster": list(thr.openings)},
            "frames": frames,
            "rejected_other": other,
            "second_sender_evidence": dict(sorted(receipt.second_sender.items())),
            "latency_us": {"sensor_to_command": latency_summary(self.latency_ns)},
            "lockstep_wall_us": None if self.mode != "lockstep" else {
                "cycle": latency_summary(self.cycle_wall_ns),
                "waiting_for_fsw": latency_summary(self.fsw_wait_ns),
                "before_sync": latency_summary(self.before_sync_ns),
                "meanwhile": latency_summary(self.meanwhile_ns),
                "after_commands": latency_summary(self.after_commands_ns),
                "spin_s": self.lockstep_spin_s,
            },
            "deadline_misses": {
                "bench_late": self.late_steps,
                "bench_max_lag_ms": round(self.max_lag_ns / NS_PER_MS, 3),
                "stalls": self.stalls,
                "fsw_overruns": self.fsw.overruns,
            },
            "valve_watchdog_trips": station.watchdog_trips,
            "fsw_mode_changes": {"count": self.fsw.mode_change_count,
                                 "first": list(self.fsw.mode_changes)},
            "fsw_restarts": self.fsw.restarts,
            "fsw_restarts_refused": self.fsw.restarts_refused,
            "faults": station.faults.log,
            "fault_effects": dict(wire.fault_counts),
            "fdir": self.fsw.fdir,
        })
        out["passed"] = all(x["pass"] for x in out["expectations"]) and out["converged"]
        return out
