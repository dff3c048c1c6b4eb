"""Closed loop: the flight computer alone against a rigid body written here; a thruster fails.

The plant (not the bench's): 6-DoF rigid body with the seed-000 actual mass and inertia,
16 first-order valves (delays, rise and tail), gyro, accelerometer, star tracker and
relative navigation with noise, integrated at 0.5 ms. The flight computer is built from
``scenarios/fdir_16thr.toml``'s [flight_sw] table with the nominal mass and inertia. A
thruster sticks closed during the slew: it must be isolated, and the slew still converge
while the position is held.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dbc.contract import FswConfig, Manoeuvre, ThrusterConfig, ValveTiming
from flight_sw.config import build_computer
from flight_sw.fdir.base import FailureKind
from flight_sw.modes import FdirFlag, Mode
from flight_sw.quaternion import (
    error_quaternion,
    from_rotation_vector,
    multiply,
    normalise,
    rotation_angle_rad,
    to_dcm,
)

from .conftest import (
    SEED000_ACTUAL_INERTIA_KGM2,
    SEED000_ACTUAL_MASS_KG,
    SEED000_NOMINAL_INERTIA_KGM2,
    SEED000_NOMINAL_MASS_KG,
    SEED000_THRUST_N,
    seed000_layout,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "fdir_16thr.toml"
NS = 1_000_000_000
STEP_NS = 500_000
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
STR_NS = NAV_NS = 100_000_000
WATCH = {"IMU_RATE": IMU_NS, "STR_QUAT": STR_NS, "NAV_POS": NAV_NS}
CMD_DELAY_NS = 1_500_000
OPEN_DELAY_NS, CLOSE_DELAY_NS = 3_000_000, 2_000_000
RISE_TAU_S, TAIL_TAU_S = 0.002, 0.003
MIN_ON_NS = 5_000_000
GYRO_SIGMA, GYRO_LSB = 3e-5, 2e-5
ACCEL_SIGMA, ACCEL_BIAS = 5e-3, np.array([5e-4, -3e-4, 2e-4])
STR_SIGMA_RAD = 1.5e-5
NAV_SIGMA_M, NAV_SIGMA_M_S = 0.005, 0.0005
SLEW_RAD = math.radians(20.0)
T_START_S = 1.0
T_FAIL_S = 1.3
T_END_S = 14.0
FAILED = 1  # quad +y, thrust along -x: fires during this slew
SETTLED_DEG = 0.5  # the scenario's settling band
POSITION_TOL_M = 0.05
DETECT_MAX_S = 2.0  # the issue: every stuck-closed failure detected within 2 s


def config() -> dict[str, Any]:
    """Flight-software configuration: nominal vehicle, 16 thrusters, fdir_16thr's [flight_sw]."""
    r, d = seed000_layout()
    fsw = tomllib.loads(SCENARIO.read_text(encoding="utf-8"))["flight_sw"]
    fsw["thruster_fdir"]["precompute_masks"] = False  # one allocator is built at isolation
    axis = np.ones(3) / math.sqrt(3.0)
    q_target = np.concatenate(([math.cos(SLEW_RAD / 2)], math.sin(SLEW_RAD / 2) * axis))
    return FswConfig(
        source="test",
        mass_kg=SEED000_NOMINAL_MASS_KG,
        inertia_B_kgm2=tuple(tuple(row) for row in np.diag(SEED000_NOMINAL_INERTIA_KGM2)),
        thrusters=tuple(ThrusterConfig(tuple(a), tuple(b), SEED000_THRUST_N)
                        for a, b in zip(r, d, strict=True)),
        valves=ValveTiming(MIN_ON_NS / NS, OPEN_DELAY_NS / NS, CLOSE_DELAY_NS / NS, RISE_TAU_S,
                           TAIL_TAU_S),
        manoeuvre=Manoeuvre(tuple(q_target), T_START_S),
        flight_sw=fsw,
    ).to_json()


class Plant:
    """Rigid body, first-order valves and sensors (see the module docstring)."""

    def __init__(self, rng: np.random.Generator) -> None:
        r, d = seed000_layout()
        self.n = len(r)
        self.force_B = d.T * SEED000_THRUST_N  # (3, n)
        self.torque_B = np.cross(r, d).T * SEED000_THRUST_N
        self.j = np.diag(SEED000_ACTUAL_INERTIA_KGM2)
        self.j_inv = np.linalg.inv(self.j)
        self.m = SEED000_ACTUAL_MASS_KG
        self.q = np.array([1.0, 0.0, 0.0, 0.0])
        self.w = np.zeros(3)
        self.r = np.zeros(3)
        self.v = np.zeros(3)
        self.f = np.zeros(self.n)  # thrust fraction per valve
        self.coil_on = np.full(self.n, -1, dtype=np.int64)
        self.coil_off = np.full(self.n, -1, dtype=np.int64)
        self.stuck_closed = np.zeros(self.n, dtype=bool)
        self.rng = rng

    def command(self, t_ns: int, on_s: tuple[float, ...]) -> None:
        """Valve commands received at ``t_ns`` (continuing an energised coil)."""
        for k, on in enumerate(on_s):
            on_ns = round(on * NS)
            if on_ns <= 0:
                if self.coil_on[k] <= t_ns < self.coil_off[k]:
                    self.coil_off[k] = t_ns
                continue
            if self.coil_on[k] <= t_ns <= self.coil_off[k]:
                self.coil_off[k] = max(t_ns + on_ns, self.coil_on[k] + MIN_ON_NS)
            else:
                self.coil_on[k], self.coil_off[k] = t_ns, t_ns + max(on_ns, MIN_ON_NS)

    def step(self, t_ns: int) -> None:
        """Advance [t, t + h]: valves (exact step average), then the rigid body."""
        h = STEP_NS / NS
        mid = t_ns + STEP_NS // 2
        driven = (mid >= self.coil_on + OPEN_DELAY_NS) & (mid < self.coil_off + CLOSE_DELAY_NS)
        driven &= ~self.stuck_closed
        target = driven.astype(float)
        tau = np.where(driven, RISE_TAU_S, TAIL_TAU_S)
        decay = np.exp(-h / tau)
        f_avg = target + (self.f - target) * tau / h * (1.0 - decay)
        self.f = target + (self.f - target) * decay
        torque = self.torque_B @ f_avg
        force_b = self.force_B @ f_avg
        w_mid = self.w + 0.5 * h * self.j_inv @ (torque - np.cross(self.w, self.j @ self.w))
        self.w = self.w + h * self.j_inv @ (torque - np.cross(w_mid, self.j @ w_mid))
        self.q = normalise(multiply(self.q, from_rotation_vector(0.5 * (w_mid + self.w) * h)))
        a_n = to_dcm(self.q).T @ force_b / self.m
        self.r = self.r + self.v * h + 0.5 * a_n * h * h
        self.v = self.v + a_n * h

    def gyro(self) -> np.ndarray:
        """Measured rate (noise, LSB)."""
        w = self.w + self.rng.normal(0.0, GYRO_SIGMA, 3)
        return np.round(w / GYRO_LSB) * GYRO_LSB

    def accel(self) -> np.ndarray:
        """Measured specific force (instantaneous thrust, noise, bias)."""
        f = self.force_B @ self.f / self.m
        return f + ACCEL_BIAS + self.rng.normal(0.0, ACCEL_SIGMA, 3)

    def star(self) -> np.ndarray:
        """Measured attitude."""
        return multiply(self.q, from_rotation_vector(self.rng.normal(0.0, STR_SIGMA_RAD, 3)))


def run(rng: np.random.Generator) -> tuple[list[Any], Plant, Any, np.ndarray]:
    """The closed loop from 0 to T_END_S; returns per-cycle results, plant, computer, errors."""
    fc = build_computer(config(), PERIOD_NS, IMU_NS, WATCH)
    plant = Plant(rng)
    fc.watchdog.start(0)
    pending: list[tuple[int, tuple[float, ...]]] = []
    results = []
    att_err = []
    counter = 0
    q_target = fc.timeline.q_target_BN
    for t in range(0, round(T_END_S * NS), STEP_NS):
        if t == round(T_FAIL_S * NS):
            plant.stuck_closed[FAILED] = True
        while pending and pending[0][0] <= t:
            plant.command(t, pending.pop(0)[1])
        if t % IMU_NS == 0:
            counter = (counter + 1) % 15
            if fc.on_imu_rate(t, plant.gyro(), counter, 0):
                fc.watchdog.seen("IMU_RATE", t)
            fc.on_imu_accel(t, plant.accel(), counter, 0)
        if t % STR_NS == 0 and fc.on_star_tracker(t, plant.star()):
            fc.watchdog.seen("STR_QUAT", t)
        if t % NAV_NS == 0:
            fc.on_nav_pos(t, plant.r + rng.normal(0.0, NAV_SIGMA_M, 3))
            fc.on_nav_vel(t, plant.v + rng.normal(0.0, NAV_SIGMA_M_S, 3))
        if t % PERIOD_NS == 0:
            res = fc.cycle(t)
            results.append(res)
            pending.append((t + CMD_DELAY_NS, res.on_time_s))
            att_err.append(math.degrees(rotation_angle_rad(error_quaternion(q_target, plant.q))))
        plant.step(t)
    return results, plant, fc, np.array(att_err)


@pytest.mark.slow
def test_stuck_closed_during_slew_is_isolated_and_the_slew_converges(
    rng: np.random.Generator,
) -> None:
    """Thruster 1 sticks closed at 1.3 s: isolated correctly, attitude settles, position held."""
    results, plant, fc, att_err = run(rng)
    assert fc.thruster_fdir is not None
    failures = fc.thruster_fdir.failures
    assert [(f.thruster, f.kind) for f in failures] == [(FAILED, FailureKind.STUCK_CLOSED)]
    assert (failures[0].t_detect_ns - T_FAIL_S * NS) / NS <= DETECT_MAX_S
    last = results[-1]
    assert last.mode == Mode.NOMINAL
    assert last.fdir_flags & FdirFlag.THRUSTER_ISOLATED
    assert not last.fdir_flags & FdirFlag.NAV_LOST
    assert last.on_time_s[FAILED] == 0.0
    final_window = att_err[-round(2.0 * NS / PERIOD_NS) :]
    assert final_window.max() < SETTLED_DEG
    assert np.linalg.norm(plant.r) < POSITION_TOL_M
