"""Telemetry of a run: truth and the flight software's estimate every 10 ms, and the errors.

In: the station at a telemetry instant ``t_ns`` (true state q_BN, omega_BN_B [rad/s],
r_N [m], v_N [m/s]; per-thruster thrust [N] at that instant; propellant [kg]; active
faults) and the flight software's last estimate (bench.results.fsw_view). Out: one row of
``telemetry.csv`` (columns in :func:`telemetry_columns`, units in their names), and the
attitude error [deg], rate error [deg/s] and position error [m] from the manoeuvre's
start on, streamed into the run's convergence figures (bench.results.error_stats: flat
memory, however long the run).

Errors: against the step target q_target_BN (rate error = |omega_BN_B|), or against the
moving reference q_RN(t), omega_RN(t) of an MRP polynomial manoeuvre
(bench.station.reference); the position error is the distance to the manoeuvre's
r_target_N_m, else to the initial position. Thrust is the value at the instant, not a
10 ms mean (pulses of a few ms fall between rows).
"""

from __future__ import annotations

import math
from pathlib import Path

from bench.results.error_stats import ErrorStats
from bench.results.fsw_view import RAD_DEG, FswView, quat_error_deg
from bench.results.writers import TelemetryWriter
from bench.scenario.spec import Scenario
from bench.station.reference import KIND_STEP, attitude_error_deg, rate_error_B, reference
from bench.station.station import Station

TELEMETRY_PERIOD_NS = 10_000_000
# Telemetry values: 7 significant digits, the decimal precision of a float32 (what an MF4
# or a DBC physical value usually holds): an error of 0.01 deg reads to 1e-9 deg, a
# quaternion component to 1e-7 (~1e-5 deg). t_s keeps 10 digits (10 ms at 1e6 s, the
# longest run). Three digits fewer than the timing tables make the compressed file ~30 %
# smaller, which pays for trace.blf at the default record level (bench.wire.trace).
TIME_FORMAT = "%.10g"
VALUE_FORMAT = "%.7g"
NS_PER_S = 1_000_000_000
STATE_COLUMNS = ["t_s", "q0", "q1", "q2", "q3", "wx_rad_s", "wy_rad_s", "wz_rad_s", "rx_m",
                 "ry_m", "rz_m", "vx_m_s", "vy_m_s", "vz_m_s", "att_err_deg", "rate_err_deg_s",
                 "fsw_q0", "fsw_q1", "fsw_q2", "fsw_q3", "fsw_est_err_deg", "fsw_mode"]


def telemetry_columns(n_thrusters: int) -> list[str]:
    """The columns of telemetry.csv for a vehicle of ``n_thrusters``."""
    return [*STATE_COLUMNS, *(f"thrust_T{k:02d}_N" for k in range(n_thrusters)),
            "propellant_kg", "active_faults"]


class Telemetry:
    """telemetry.csv and the streamed error figures (:class:`ErrorStats`)."""

    def __init__(self, sc: Scenario, path: Path, n_thrusters: int, deferred: bool,
                 every: int = 1) -> None:
        """``every``: write one instant in this many (the error figures take every one)."""
        self.sc = sc
        self.every = every
        self._instants = 0
        columns = telemetry_columns(n_thrusters)
        self.writer = TelemetryWriter(path, columns, deferred,
                                      [TIME_FORMAT] + [VALUE_FORMAT] * (len(columns) - 1))
        self._start_ns = sc.manoeuvre_start_s * NS_PER_S
        e = sc.expectations
        self.errors = ErrorStats(e.settling_band_deg, e.steady_state_window_s,
                                 sc.manoeuvre_start_s, e.rate_settling_band_deg_s,
                                 e.position_band_m)

    def row(self, t_ns: int, station: Station, fsw: FswView) -> None:
        """Sample the station at ``t_ns`` (a telemetry instant)."""
        s = station.plant.state
        sc = self.sc
        write = self._instants % self.every == 0
        self._instants += 1
        if sc.reference.kind == KIND_STEP:
            err = quat_error_deg(s[0:4], sc.q_target_BN)
            rate_err = math.sqrt(s[4] ** 2 + s[5] ** 2 + s[6] ** 2) * RAD_DEG
        else:  # a moving reference: errors w.r.t. q_RN(t), omega_RN(t)
            q_ref, w_ref = reference(sc.reference, t_ns / NS_PER_S)
            q_t = (s[0], s[1], s[2], s[3])
            err = attitude_error_deg(q_t, q_ref)
            dw = rate_error_B(q_t, (s[4], s[5], s[6]), q_ref, w_ref)
            rate_err = math.sqrt(dw[0] ** 2 + dw[1] ** 2 + dw[2] ** 2) * RAD_DEG
        if write:
            thr = station.plant.thrusters
            row: list[float | int] = [t_ns / NS_PER_S, *s[0:4], *s[4:13], err, rate_err]
            row += fsw.estimate_row()
            row += [thr.valves[k].thrust_N(t_ns) for k in range(station.n_thr)]
            row.append(thr.total_propellant_kg)
            row.append(len(station.faults.active))
            self.writer.row(row)
        if t_ns >= self._start_ns:
            self.errors.add(t_ns / NS_PER_S, err, rate_err,
                            math.dist(s[7:10], sc.r_reference_N_m))
