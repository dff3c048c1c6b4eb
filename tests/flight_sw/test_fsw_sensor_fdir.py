"""Sensor FDIR: frozen IMU and star tracker, star-tracker outage with gyro-only propagation."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bench.scenario.load import load_scenario
from dbc.errors import ConfigError
from flight_sw.computer import FlightComputer
from flight_sw.config import build_computer
from flight_sw.fdir.frozen_sensor import FrozenSensorMonitor, FrozenSensorParams
from flight_sw.modes import FdirFlag, Mode, SensorFlag
from flight_sw.quaternion import from_rotation_vector, multiply, rotation_angle_rad

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
STR_NS = 100_000_000
WATCH = {"IMU_RATE": IMU_NS, "STR_QUAT": STR_NS}
RATE_B = np.array([0.002, -0.001, 0.0015])  # a slow tumble [rad/s]
GYRO_SIGMA = 3e-5
STR_SIGMA_RAD = 2e-5
PROPAGATION_TOL_RAD = 2e-4  # gyro-only attitude after 1 s of outage vs truth


class Spy:
    """Counts the calls to the estimator it wraps."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.updates = 0

    def propagate(self, t_ns: int, omega: np.ndarray) -> None:
        """Forward."""
        self.inner.propagate(t_ns, omega)

    def update_star_tracker(self, t_ns: int, q: np.ndarray) -> None:
        """Count and forward."""
        self.updates += 1
        self.inner.update_star_tracker(t_ns, q)

    def estimate(self) -> Any:
        """Forward."""
        return self.inner.estimate()


class Bench:
    """Feeds the computer as the node would: samples, watchdog, one cycle per period."""

    def __init__(self, fc: FlightComputer, rng: np.random.Generator) -> None:
        self.fc, self.rng = fc, rng
        self.t = 0
        self.imu_counter = 0
        fc.watchdog.start(0)

    def truth(self, t_ns: int) -> np.ndarray:
        """True attitude: constant rate from identity."""
        return from_rotation_vector(RATE_B * t_ns / 1e9)

    def cycle(self, imu: str = "live", star: str = "live") -> Any:
        """One control period of samples (IMU 100 Hz, STR 10 Hz), then the cycle."""
        for dt in (IMU_NS, 2 * IMU_NS):
            t = self.t + dt
            if imu != "off":
                w = RATE_B + self.rng.normal(0.0, GYRO_SIGMA, 3) if imu == "live" else RATE_B
                self.imu_counter = (self.imu_counter + 1) % 15
                if self.fc.on_imu_rate(t, w, self.imu_counter, 0):
                    self.fc.watchdog.seen("IMU_RATE", t)
            if t % STR_NS == 0 and star != "off":
                q = self.truth(t)
                if star == "live":
                    q = multiply(q, from_rotation_vector(self.rng.normal(0.0, STR_SIGMA_RAD, 3)))
                    payload = tuple(q.tolist())
                else:
                    payload = (0.0, 1.0, 2.0, 3.0)  # the same payload every time
                if self.fc.on_star_tracker(t, q, payload):
                    self.fc.watchdog.seen("STR_QUAT", t)
        self.t += PERIOD_NS
        return self.fc.cycle(self.t)


@pytest.fixture
def bench(rng: np.random.Generator) -> Bench:
    """The quickstart flight computer with a scripted sample source."""
    cfg = load_scenario(QUICKSTART).fsw_config()
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    fc.estimator = Spy(fc.estimator)
    return Bench(fc, rng)


def test_monitor_declares_after_n_identical_and_recovers() -> None:
    """N identical samples: frozen from the N-th on; a different one clears and is kept."""
    mon = FrozenSensorMonitor({"IMU_RATE": 4})
    results = [mon.check("IMU_RATE", (1.0, 2.0, 3.0)) for _ in range(6)]
    assert results == [False, False, False, True, True, True]
    assert mon.frozen("IMU_RATE")
    assert mon.check("IMU_RATE", (1.0, 2.0, 3.5)) is False
    assert not mon.frozen("IMU_RATE")
    assert mon.check("OTHER", (0.0,)) is False


def test_monitor_params_are_checked() -> None:
    """A count below 2 is a named ConfigError."""
    with pytest.raises(ConfigError) as err:
        FrozenSensorParams(imu_rate_samples=1)
    assert err.value.key == "imu_rate_samples"


def test_live_sensors_raise_no_flag(bench: Bench) -> None:
    """Noisy live samples: nominal, no sensor flag."""
    for _ in range(100):
        res = bench.cycle()
    assert res.mode == Mode.NOMINAL and res.sensor_flags == 0 and res.fdir_flags == 0


def test_frozen_imu_is_flagged_ignored_and_ends_in_safe_mode(bench: Bench) -> None:
    """Identical gyro samples: IMU_FROZEN, samples ignored, the IMU watchdog latches SAFE."""
    for _ in range(20):
        bench.cycle()
    n_frozen = FrozenSensorParams().imu_rate_samples
    for _ in range(n_frozen // 2 + 4):  # 2 IMU samples per cycle
        res = bench.cycle(imu="frozen")
    assert res.sensor_flags & SensorFlag.IMU_FROZEN
    assert res.fdir_flags & FdirFlag.SENSOR_FROZEN
    assert res.mode == Mode.SAFE and res.fdir_flags & FdirFlag.IMU_LOST
    assert all(x == 0.0 for x in res.on_time_s)


def test_frozen_star_tracker_is_ignored_and_flagged_degraded(bench: Bench) -> None:
    """Identical STR payloads: STR_FROZEN and STR_DEGRADED, no filter update from them."""
    for _ in range(20):
        bench.cycle()
    spy = bench.fc.estimator
    assert isinstance(spy, Spy)
    before = spy.updates
    n_frozen = FrozenSensorParams().str_quat_samples
    for _ in range(5 * (n_frozen + 4)):  # one STR sample every 5 cycles
        res = bench.cycle(star="frozen")
    assert res.sensor_flags & SensorFlag.STR_FROZEN and res.sensor_flags & SensorFlag.STR_DEGRADED
    assert spy.updates - before == n_frozen - 1  # the ones before the declaration
    assert res.mode == Mode.NOMINAL
    for _ in range(10):
        res = bench.cycle()
    assert not res.sensor_flags & (SensorFlag.STR_FROZEN | SensorFlag.STR_DEGRADED)


def test_star_tracker_outage_propagates_on_gyro_and_recovers(bench: Bench) -> None:
    """No STR for > 3 periods: degraded flag, still NOMINAL on the gyro; flag clears on return."""
    for _ in range(25):
        bench.cycle()
    for _ in range(14):  # 3 STR periods = 15 cycles: not yet
        res = bench.cycle(star="off")
    assert not res.sensor_flags & SensorFlag.STR_DEGRADED
    for _ in range(36):  # 1 s of outage in total
        res = bench.cycle(star="off")
    assert res.sensor_flags & SensorFlag.STR_DEGRADED and res.fdir_flags & FdirFlag.STR_LOST
    assert res.mode == Mode.NOMINAL
    est = bench.fc.estimator.estimate()
    err = multiply(np.array([est.q_BN[0], *(-est.q_BN[1:])]), bench.truth(bench.t))
    assert rotation_angle_rad(err) < PROPAGATION_TOL_RAD
    for _ in range(6):
        res = bench.cycle()
    assert not res.sensor_flags & SensorFlag.STR_DEGRADED
    assert not res.fdir_flags & FdirFlag.STR_LOST
