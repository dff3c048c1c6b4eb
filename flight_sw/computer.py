"""The flight computer's application: one control cycle from sensor data to valve on-times.

In (decoded ICD signals, via the node): IMU_RATE (omega_meas_B, rad/s) each gyro sample,
STR_QUAT (q_meas_BN) each star-tracker sample, THR_STATUS (valve telemetry, kept for FDIR).
Out of :meth:`FlightComputer.cycle`: per thruster an on-time [s] for the coming control
period, mode, FDIR flags and the allocator's saturation and residual, and the alive counter
of the newest IMU_RATE sample used (so the bench can measure sensor-to-actuator latency).

Chain (seed 003's architecture): estimator (gyro propagation + star-tracker correction) ->
attitude controller (torque demand, body axes, N m) -> allocator (thrust per thruster, N,
bounded to [0, Tmax]) -> one modulator per thruster (demanded fraction -> on-time).
Safe mode: IMU_RATE silent for 3 of its periods latches SAFE: every valve closed.
Strategies are injected (one interface each); time is an argument; no I/O here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flight_sw.allocation.base import Allocator
from flight_sw.control.base import AttitudeController
from flight_sw.estimation.base import AttitudeEstimator
from flight_sw.fdir.sensor_watchdog import SensorWatchdog
from flight_sw.modes import FdirFlag, Mode
from flight_sw.modulation.base import Modulator

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class CycleResult:
    """What one control cycle decided."""

    on_time_s: tuple[float, ...]
    mode: Mode
    fdir_flags: int
    saturated: bool
    residual_Nm: float
    imu_counter: int
    torque_cmd_B_Nm: tuple[float, float, float]


@dataclass
class Timeline:
    """The manoeuvre: hold until ``t_start_ns``, then point at ``q_target_BN``."""

    q_target_BN: np.ndarray
    t_start_ns: int


@dataclass
class FlightComputer:
    """Estimator, controller, allocator and modulators wired into one cycle."""

    estimator: AttitudeEstimator
    controller: AttitudeController
    allocator: Allocator
    modulators: list[Modulator]
    max_thrust_N: float
    control_period_ns: int
    imu_period_ns: int
    timeline: Timeline
    watchdog: SensorWatchdog
    mode: Mode = Mode.BOOT
    safe_latched: bool = False
    imu_counter: int = 0
    _imu_t_ns: int | None = None
    _q_hold_BN: np.ndarray | None = None
    thr_status: dict[str, Any] = field(default_factory=dict)

    def on_imu_rate(self, t_ns: int, omega_meas_B: np.ndarray, counter: int, gap: int) -> None:
        """One gyro sample; its time is rebuilt from the IMU period and counter gaps."""
        if self._imu_t_ns is None:
            self._imu_t_ns = t_ns
        else:
            self._imu_t_ns += self.imu_period_ns * (1 + gap)
        self.estimator.propagate(self._imu_t_ns, omega_meas_B)
        self.imu_counter = counter

    def on_star_tracker(self, t_ns: int, q_meas_BN: np.ndarray) -> None:
        """One valid star-tracker attitude."""
        self.estimator.update_star_tracker(
            self._imu_t_ns if self._imu_t_ns is not None else t_ns, q_meas_BN
        )

    def cycle(self, t_ns: int) -> CycleResult:
        """Run one control cycle at ``t_ns``; returns the valve on-times for the next period."""
        n = len(self.modulators)
        flags = 0
        if self.watchdog.lost("IMU_RATE", t_ns):
            self.safe_latched = True
            flags |= FdirFlag.IMU_LOST
        if self.watchdog.lost("STR_QUAT", t_ns):
            flags |= FdirFlag.STR_LOST
        est = self.estimator.estimate()
        if self.safe_latched:
            self.mode = Mode.SAFE
            flags |= FdirFlag.SAFE_LATCHED
            return CycleResult(
                (0.0,) * n, self.mode, flags, False, 0.0, self.imu_counter, (0.0, 0.0, 0.0)
            )
        if not est.initialised:
            self.mode = Mode.BOOT
            return CycleResult(
                (0.0,) * n, self.mode, flags, False, 0.0, self.imu_counter, (0.0, 0.0, 0.0)
            )
        self.mode = Mode.NOMINAL
        if t_ns >= self.timeline.t_start_ns:
            q_ref = self.timeline.q_target_BN
        else:
            if self._q_hold_BN is None:
                self._q_hold_BN = np.array(est.q_BN, dtype=float)
            q_ref = self._q_hold_BN
        torque = self.controller.torque_B_Nm(t_ns, est.q_BN, est.omega_BN_B, q_ref, np.zeros(3))
        alloc = self.allocator.allocate(torque)
        period_s = self.control_period_ns / NS_PER_S
        on_times = tuple(
            mod.on_time_s(t_ns, float(thrust) / self.max_thrust_N, period_s)
            for mod, thrust in zip(self.modulators, alloc.thrust_N, strict=True)
        )
        return CycleResult(
            on_times,
            self.mode,
            flags,
            bool(alloc.saturated),
            float(alloc.residual_norm),
            self.imu_counter,
            (float(torque[0]), float(torque[1]), float(torque[2])),
        )
