"""The flight computer's application: one control cycle from sensor data to valve on-times.

In (decoded ICD signals, via the node): IMU_RATE (omega_meas_B, rad/s) and IMU_ACCEL
(specific force f_B, m/s²) each sample, STR_QUAT (q_meas_BN) each star-tracker sample,
NAV_POS / NAV_VEL (r_N [m], v_N [m/s] in the navigation frame N) in 6-DoF runs, THR_STATUS
(valve telemetry, the FDIR input). Out of :meth:`FlightComputer.cycle`: per thruster an
on-time [s] for the coming control period, mode, FDIR flags, sensor flags and the thruster
FDIR report (FSW_FDIR), the allocator's saturation and torque residual, and the alive
counter of the newest IMU_RATE sample used (sensor-to-actuator latency).

Chain (seed 003's architecture, extended to 6 DoF after seed 000): estimator (gyro
propagation + star-tracker correction) -> attitude controller (torque demand, body axes,
N m) and, when a translation controller is configured, translation controller (force
demand, body axes, N, from the navigation solution rotated with the estimated attitude)
-> allocator (thrust per thruster, N, bounded to [0, Tmax]; the 6 wrench rows in 6 DoF,
and in attitude-only control too when ``pure_torque`` (the torque with a zero force
demand, so the thrusters fire in force-free sets), else the 3 torque rows) -> one
modulator per thruster (demanded fraction -> on-time).

FDIR (docs/fdir.md):
- Safe mode: IMU_RATE silent for 3 of its periods latches SAFE: every valve closed. A
  frozen IMU (identical samples, :mod:`flight_sw.fdir.frozen_sensor`) is ignored, so it
  ends the same way.
- Star tracker silent for 3 periods, or frozen: attitude propagated on the gyro only,
  SensorFlags bit 0 (degraded); it recovers when valid, changing samples return.
- Navigation (6 DoF) older than ``nav_timeout_ns``: the force demand is zero (attitude-only
  control, translation coasting), FdirFlags NAV_LOST.
- Thrusters (:mod:`flight_sw.fdir.thruster_fdir`): on isolation the allocator is replaced
  by one built with the availability mask (cached per mask); a masked thruster's on-time
  is 0 and its modulator restarts; for a stuck-open thruster its known wrench
  (its column × Tmax) is subtracted from the demand, so the others counter it.
- Bench restart (:meth:`FlightComputer.restart`, called by the node): estimator,
  modulators, FDIR, watchdog, safe latch and manoeuvre timeline start again from the
  bench's new time; SensorFlags bit 3 and FdirFlags BENCH_RESTART stay set.
Strategies are injected (one interface each); time is an argument; no I/O here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from dbc import validation as check
from flight_sw.allocation.base import Allocator
from flight_sw.allocation.dense import mat_vec, norm
from flight_sw.control.base import (
    AttitudeController,
    PoseController,
    TranslationController,
)
from flight_sw.estimation.base import AttitudeEstimator, InertiaIdentifier
from flight_sw.fdir.base import ThrusterFailure
from flight_sw.fdir.frozen_sensor import FrozenSensorMonitor
from flight_sw.fdir.layout_check import LayoutCheck
from flight_sw.fdir.layout_check import describe as describe_layout
from flight_sw.fdir.sensor_watchdog import SensorWatchdog
from flight_sw.fdir.thruster_fdir import FdirReport, ThrusterFdir
from flight_sw.fdir.valve_status import status_flags
from flight_sw.modes import FdirFlag, Mode, SensorFlag
from flight_sw.modulation.base import Modulator
from flight_sw.reference import References, Timeline

if TYPE_CHECKING:
    from flight_sw.guidance.base import AttitudeGuidance

NS_PER_S = 1_000_000_000
TORQUE_DIM = 3
WRENCH_DIM = 6
ZERO3 = (0.0, 0.0, 0.0)
DEFAULT_NAV_TIMEOUT_NS = 300_000_000  # 3 NAV_POS periods of 100 ms
# realtime: the cycle 2 ms after the bench's control instant (its samples of that instant
# have arrived; lockstep models the same answer 1 ms after SYNC)
DEFAULT_CYCLE_PHASE_NS = 2_000_000


@dataclass(frozen=True)
class CycleResult:
    """What one control cycle decided."""

    on_time_s: tuple[float, ...]
    mode: Mode
    fdir_flags: int
    saturated: bool
    residual_Nm: float  # torque part of the allocation residual ‖demand − B T‖ [N m]
    imu_counter: int
    torque_cmd_B_Nm: tuple[float, float, float]
    force_cmd_B_N: tuple[float, float, float] = ZERO3
    sensor_flags: int = 0
    fdir: FdirReport | None = None
    residual_force_N: float = 0.0  # force part (6-DoF allocation) [N]

    @classmethod
    def idle(cls, n: int, mode: Mode, fdir_flags: int, imu_counter: int, sensor_flags: int,
             fdir: FdirReport | None) -> CycleResult:
        """Every valve closed (boot, safe mode): no demand, nothing allocated."""
        return cls((0.0,) * n, mode, fdir_flags, False, 0.0, imu_counter, ZERO3, ZERO3,
                   sensor_flags, fdir)


def _sensor_flags(monitor: FrozenSensorMonitor, str_lost: bool, restarted: bool) -> int:
    """FSW_FDIR.SensorFlags: frozen data, a degraded or lost star tracker, a bench restart."""
    flags = 0
    if monitor.frozen("IMU_RATE"):
        flags |= SensorFlag.IMU_FROZEN
    if monitor.frozen("STR_QUAT"):
        flags |= SensorFlag.STR_FROZEN | SensorFlag.STR_DEGRADED
    if str_lost:
        flags |= SensorFlag.STR_DEGRADED
    if restarted:
        flags |= SensorFlag.BENCH_RESTART
    return flags


@dataclass
class FlightComputer:
    """Estimator, controllers, allocator, modulators and FDIR wired into one cycle."""

    estimator: AttitudeEstimator
    controller: AttitudeController
    allocator: Allocator
    modulators: list[Modulator]
    max_thrust_N: np.ndarray  # per thruster [N], shape (n,)
    control_period_ns: int
    imu_period_ns: int
    timeline: Timeline
    watchdog: SensorWatchdog
    translation: TranslationController | None = None
    effectiveness: np.ndarray | None = None  # the allocator's rows (m×n), for feed-forward
    thruster_fdir: ThrusterFdir | None = None
    sensor_monitor: FrozenSensorMonitor = field(default_factory=lambda: FrozenSensorMonitor({}))
    make_estimator: Callable[[], AttitudeEstimator] | None = None
    make_modulator: Callable[[], Modulator] | None = None
    allocators_by_mask: dict[tuple[bool, ...], Allocator] = field(default_factory=dict)
    nav_timeout_ns: int = DEFAULT_NAV_TIMEOUT_NS
    guidance: AttitudeGuidance | None = None  # a moving reference (else the Timeline's step)
    pose: PoseController | None = None  # a coupled 6-DoF law (replaces both controllers)
    pure_torque: bool = False  # attitude-only: allocate (0 N, torque) on the wrench rows
    inertia_id: InertiaIdentifier | None = None
    # realtime: each cycle starts this long after one of the bench's control instants
    cycle_phase_ns: int = DEFAULT_CYCLE_PHASE_NS
    warnings: tuple[str, ...] = ()  # what this configuration cannot do (authority)
    # what the thrusters an isolation leaves can do (flight_sw.fdir.layout_check)
    layout_check: Callable[[np.ndarray], LayoutCheck] | None = None
    #: one line per isolation that cost full control (the run's warnings)
    layout_notes: list[str] = field(default_factory=list)
    mode: Mode = Mode.BOOT
    safe_latched: bool = False
    imu_counter: int = 0
    restarts: int = 0
    thr_status: dict[str, Any] = field(default_factory=dict)
    _imu_t_ns: int | None = None
    _acc_t_ns: int | None = None
    _nav_r: tuple[int, np.ndarray] | None = None
    _nav_v: tuple[int, np.ndarray] | None = None
    _allocator_full: Allocator | None = None
    _torque_applied_B_Nm: np.ndarray | None = None  # last cycle's allocated torque
    inertia_B_kgm2: np.ndarray | None = None  # latest identified inertia (telemetry)

    def __post_init__(self) -> None:
        self._refs = References(self.timeline, self.guidance)
        self._allocator_full = self.allocator
        n = len(self.modulators)
        self.max_thrust_N = np.array(check.vector("FlightComputer", "max_thrust_N",
                                                  self.max_thrust_N, n, 0.0, lo_open=True))
        self._max_thrust_list: list[float] = self.max_thrust_N.tolist()
        # the torque rows as lists, for the per-cycle product (dense.mat_vec: no BLAS)
        self._torque_rows: list[list[float]] = (
            [] if self.effectiveness is None else self.effectiveness[-TORQUE_DIM:].tolist())

    # --- sensor input -------------------------------------------------------------------

    def on_imu_rate(self, t_ns: int, omega_meas_B: np.ndarray, counter: int, gap: int) -> bool:
        """One gyro sample; its time is rebuilt from the IMU period and counter gaps.

        Returns False if the sample was ignored as frozen data (then it does not count as
        seen for the IMU watchdog).
        """
        if self._imu_t_ns is None:
            self._imu_t_ns = t_ns
        else:
            self._imu_t_ns += self.imu_period_ns * (1 + gap)
        omega = np.asarray(omega_meas_B, dtype=float)
        if self.sensor_monitor.check("IMU_RATE", tuple(omega.tolist())):
            return False
        self.estimator.propagate(self._imu_t_ns, omega)
        self.imu_counter = counter
        if self.thruster_fdir is not None:
            self.thruster_fdir.on_gyro(self._imu_t_ns, omega)
        return True

    def on_imu_accel(self, t_ns: int, f_meas_B: np.ndarray, counter: int, gap: int) -> bool:
        """One accelerometer sample (the residual FDIR's linear channel)."""
        if self._acc_t_ns is None:
            self._acc_t_ns = t_ns
        else:
            self._acc_t_ns += self.imu_period_ns * (1 + gap)
        if self.thruster_fdir is not None:
            self.thruster_fdir.on_accel(self._acc_t_ns, np.asarray(f_meas_B, dtype=float))
        return True

    def on_star_tracker(
        self, t_ns: int, q_meas_BN: np.ndarray, payload: tuple[float, ...] | None = None
    ) -> bool:
        """One valid star-tracker attitude; False if ignored as frozen data.

        ``payload``: the frame's raw signal values for the frozen test (default: q).
        """
        q = np.asarray(q_meas_BN, dtype=float)
        if self.sensor_monitor.check("STR_QUAT", payload if payload else tuple(q.tolist())):
            return False
        self.estimator.update_star_tracker(
            self._imu_t_ns if self._imu_t_ns is not None else t_ns, q
        )
        return True

    def on_nav_pos(self, t_ns: int, r_N_m: np.ndarray) -> bool:
        """One valid navigation position [m, frame N] received at ``t_ns``."""
        self._nav_r = (t_ns, np.array(r_N_m, dtype=float))
        return True

    def on_nav_vel(self, t_ns: int, v_N_m_s: np.ndarray) -> bool:
        """One valid navigation velocity [m/s, frame N] received at ``t_ns``."""
        self._nav_v = (t_ns, np.array(v_N_m_s, dtype=float))
        return True

    def on_thr_status(self, t_ns: int, signals: dict[str, Any]) -> None:
        """One THR_STATUS sample (Cmd/Open/Current flags per thruster)."""
        self.thr_status = signals
        if self.thruster_fdir is None:
            return
        cmd, opened, current = status_flags(signals, len(self.modulators))
        self.thruster_fdir.on_valve_status(t_ns, cmd, opened, current)

    # --- restart ------------------------------------------------------------------------

    def restart(self, t_ns: int, bench_time_ns: int) -> None:
        """The bench restarted (its time went back to ``bench_time_ns`` at our ``t_ns``)."""
        if self.make_estimator is not None:
            self.estimator = self.make_estimator()
        for stateful in (self.controller, self.translation, self.pose):
            reset = getattr(stateful, "reset", None)
            if callable(reset):
                reset()  # e.g. an integral term
        if self.make_modulator is not None:
            self.modulators = [self.make_modulator() for _ in self.modulators]
        if self._allocator_full is not None:
            self.allocator = self._allocator_full
        if self.thruster_fdir is not None:
            self.thruster_fdir.reset()
            self.thruster_fdir.time_base_ns = t_ns - bench_time_ns
        self.sensor_monitor.reset()
        self.watchdog.last_ns.clear()
        self.watchdog.start(t_ns)
        self.timeline.time_base_ns = t_ns - bench_time_ns
        self.safe_latched = False
        self.mode = Mode.BOOT
        self.imu_counter = 0
        self._imu_t_ns = self._acc_t_ns = None
        self._refs.clear()
        self._nav_r = self._nav_v = None
        self.restarts += 1

    # --- cycle --------------------------------------------------------------------------

    def _reconfigure(self, failures: list[ThrusterFailure], t_ns: int) -> None:
        """New allocator for the FDIR's mask; restart the failed thrusters' modulators;
        note what the thrusters left cannot do (:attr:`layout_notes`)."""
        assert self.thruster_fdir is not None
        mask = self.thruster_fdir.mask
        if self.layout_check is not None:
            note = describe_layout(self.layout_check(mask), t_ns / NS_PER_S)
            if note is not None:
                self.layout_notes.append(note)
        key = tuple(bool(x) for x in mask)
        alloc = self.allocators_by_mask.get(key)
        if alloc is None:
            base = self._allocator_full or self.allocator
            alloc = base.with_mask(mask.copy())
            self.allocators_by_mask[key] = alloc
        self.allocator = alloc
        if self.make_modulator is not None:
            for f in failures:
                self.modulators[f.thruster] = self.make_modulator()

    def _nav(self, t_ns: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The navigation position and velocity if both are fresh."""
        if self._nav_r is None or self._nav_v is None:
            return None
        (t_r, r), (t_v, v) = self._nav_r, self._nav_v
        if t_ns - t_r > self.nav_timeout_ns or t_ns - t_v > self.nav_timeout_ns:
            return None
        return r, v

    def _identify_inertia(self, t_ns: int, omega_BN_B: np.ndarray) -> None:
        """Feed the inertia identifier; hand a new estimate to the laws that use one."""
        if self.inertia_id is None or self._torque_applied_B_Nm is None:
            return
        j = self.inertia_id.update(t_ns, omega_BN_B, self._torque_applied_B_Nm)
        if j is None:
            return
        self.inertia_B_kgm2 = j
        for law in (self.controller, self.pose):
            setter = getattr(law, "set_inertia_B_kgm2", None)
            if callable(setter):  # an InertiaAware law
                setter(j)

    def cycle(self, t_ns: int) -> CycleResult:
        """Run one control cycle at ``t_ns``; returns the valve on-times for the next period."""
        n = len(self.modulators)
        flags = 0
        if self.watchdog.lost("IMU_RATE", t_ns):
            self.safe_latched = True
            flags |= FdirFlag.IMU_LOST
        str_lost = self.watchdog.lost("STR_QUAT", t_ns)
        if str_lost:
            flags |= FdirFlag.STR_LOST
        sensor_flags = _sensor_flags(self.sensor_monitor, str_lost, self.restarts > 0)
        if sensor_flags & (SensorFlag.IMU_FROZEN | SensorFlag.STR_FROZEN):
            flags |= FdirFlag.SENSOR_FROZEN
        if self.restarts:
            flags |= FdirFlag.BENCH_RESTART
        six_dof = self.translation is not None or self.pose is not None
        nav = self._nav(t_ns) if six_dof else None
        if six_dof and nav is None:
            flags |= FdirFlag.NAV_LOST
        fdir = self.thruster_fdir
        report = None
        if fdir is not None:
            new = fdir.update(t_ns)
            if new:
                self._reconfigure(new, t_ns)
            report = fdir.report()
            if report.detected:
                flags |= FdirFlag.THRUSTER_FAULT_DETECTED
            if report.isolated:
                flags |= FdirFlag.THRUSTER_ISOLATED
        est = self.estimator.estimate()
        if self.safe_latched or not est.initialised:
            if self.safe_latched:
                self.mode = Mode.SAFE
                flags |= FdirFlag.SAFE_LATCHED
            else:
                self.mode = Mode.BOOT
            if fdir is not None:
                fdir.on_command(t_ns, np.zeros(n))
            return CycleResult.idle(n, self.mode, flags, self.imu_counter, sensor_flags, report)
        self.mode = Mode.NOMINAL
        self._identify_inertia(t_ns, est.omega_BN_B)
        q_ref, w_ref_B, dw_ref_B = self._refs.attitude(t_ns, est.q_BN)
        force = np.zeros(3)
        r, v, r_ref = np.zeros(3), np.zeros(3), np.zeros(3)
        if nav is not None:
            r, v = nav
            r_ref = self._refs.position(r)
        if self.pose is not None:
            # without fresh navigation: attitude only, translation coasts
            wrench = self.pose.wrench_B(
                t_ns, est.q_BN, est.omega_BN_B, r, v, q_ref, w_ref_B, r_ref, np.zeros(3)
            )
            force = wrench[:3] if nav is not None else np.zeros(3)
            torque = wrench[3:]
            demand = np.concatenate((force, torque))
        else:
            torque = self.controller.torque_B_Nm(
                t_ns, est.q_BN, est.omega_BN_B, q_ref, w_ref_B, dw_ref_B
            )
            if self.translation is not None:
                if nav is not None:
                    force = self.translation.force_B_N(t_ns, est.q_BN, r, v, r_ref, np.zeros(3))
                demand = np.concatenate((force, torque))
            elif self.pure_torque:
                demand = np.concatenate((force, torque))  # zero force: couples only
            else:
                demand = torque
        if fdir is not None and self.effectiveness is not None:
            for j in fdir.stuck_open:  # feed-forward: the others counter its known wrench
                demand = demand - self.effectiveness[:, j] * self.max_thrust_N[j]
        alloc = self.allocator.allocate(demand)
        period_s = self.control_period_ns / NS_PER_S
        # on floats (one conversion each): the same divisions and products as numpy's
        thrust_N, max_N = alloc.thrust_N.tolist(), self._max_thrust_list
        usable = fdir.mask.tolist() if fdir is not None else None
        on_list = [0.0] * len(thrust_N)
        for k, (mod, t_N) in enumerate(zip(self.modulators, thrust_N, strict=True)):
            if usable is None or usable[k]:
                on_list[k] = mod.on_time_s(t_ns, t_N / max_N[k], period_s)
        on_times = tuple(on_list)
        if fdir is not None:
            fdir.on_command(t_ns, np.array(on_times))
        if self.effectiveness is not None:  # the torque the valves are told to give
            mean_thrust_N = [on / period_s * m for on, m in zip(on_list, max_N, strict=True)]
            self._torque_applied_B_Nm = np.array(mat_vec(self._torque_rows, mean_thrust_N))
        r_demand = (demand - alloc.achieved).tolist()
        r_torque = r_demand[-TORQUE_DIM:]
        r_force = norm(r_demand[:-TORQUE_DIM])  # 0 with the torque rows alone
        return CycleResult(
            on_times,
            self.mode,
            flags,
            bool(alloc.saturated),
            norm(r_torque),
            self.imu_counter,
            (float(torque[0]), float(torque[1]), float(torque[2])),
            (float(force[0]), float(force[1]), float(force[2])),
            sensor_flags,
            report,
            r_force,
        )
