"""Residual FDIR: detection and isolation of every thruster, stuck closed and open, with noise.

Synthetic truth, independent of the flight software's own chain: random valve commands,
a truth valve model with a slightly different command delay, actual mass and inertia
different from the nominal ones (seed 000: 95 kg vs 100, diag(17, 17, 22) vs
diag(18, 18, 24)), a gyro with white noise and quantisation, an accelerometer with noise
and bias. The failure starts at ``T_FAIL_S``; the strategy must isolate the right thruster
with the right kind, quickly, and say nothing before.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.fdir.base import FailureKind, ThrusterFailure
from flight_sw.fdir.rate_residual import RateResidualFdir, RateResidualParams
from flight_sw.fdir.thrust_model import ThrustModel
from flight_sw.fdir.valve_timing import DEFAULT_TIMING

from .conftest import (
    SEED000_ACTUAL_INERTIA_KGM2,
    SEED000_ACTUAL_MASS_KG,
    SEED000_NOMINAL_INERTIA_KGM2,
    SEED000_NOMINAL_MASS_KG,
    SEED000_THRUST_N,
    SEED003_INERTIA_KGM2,
    SEED003_THRUST_N,
    seed000_layout,
    seed003_layout,
)

NS = 1_000_000_000
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
MIN_ON_S = 0.005
T_FAIL_S = 1.0
T_END_S = 2.2
P_FIRE = 0.3  # chance that a thruster is commanded in a cycle
GYRO_SIGMA_RAD_S = 3e-5  # ARW 0.01 deg/sqrt(h) at 100 Hz
GYRO_LSB_RAD_S = 2e-5
ACCEL_SIGMA_M_S2 = 5e-3  # VRW 0.03 m/s/sqrt(h) at 100 Hz
ACCEL_BIAS_M_S2 = np.array([5e-4, -3e-4, 2e-4])
TRUTH_EXTRA_DELAY_S = 0.0003  # the truth's command delay differs from the model's
DETECT_OPEN_MAX_S = 0.5  # the issue: stuck open within 1 s
DETECT_CLOSED_MAX_S = 1.0  # the issue: stuck closed within 2 s
SEED003_MASS_KG = 100.0
SEED003_ACTUAL_FACTOR = 0.95  # truth inertia and mass 5 % below nominal
# A non-uniform layout: every other seed-003 thruster has this fraction of the maximum.
WEAK_FRACTION = 0.7


def unequal_maxima(t_max_n: float, n: int) -> np.ndarray:
    """T_max for even thrusters, WEAK_FRACTION × T_max for odd ones."""
    return np.array([t_max_n * (WEAK_FRACTION if k % 2 else 1.0) for k in range(n)])


def vehicles() -> dict[str, dict[str, object]]:
    """The two layouts with nominal (FSW) and actual (truth) mass properties."""
    r8, d8 = seed003_layout()
    r16, d16 = seed000_layout()
    j8 = np.diag(SEED003_INERTIA_KGM2)
    return {
        "seed003_8": {
            "b": effectiveness_matrix(r8, d8),
            "tmax": np.full(8, SEED003_THRUST_N),
            "j_nom": j8,
            "m_nom": SEED003_MASS_KG,
            "j_act": SEED003_ACTUAL_FACTOR * j8,
            "m_act": SEED003_ACTUAL_FACTOR * SEED003_MASS_KG,
        },
        "seed003_8_unequal": {
            "b": effectiveness_matrix(r8, d8),
            "tmax": unequal_maxima(SEED003_THRUST_N, 8),
            "j_nom": j8,
            "m_nom": SEED003_MASS_KG,
            "j_act": SEED003_ACTUAL_FACTOR * j8,
            "m_act": SEED003_ACTUAL_FACTOR * SEED003_MASS_KG,
        },
        "seed000_16": {
            "b": effectiveness_matrix(r16, d16),
            "tmax": np.full(16, SEED000_THRUST_N),
            "j_nom": np.diag(SEED000_NOMINAL_INERTIA_KGM2),
            "m_nom": SEED000_NOMINAL_MASS_KG,
            "j_act": np.diag(SEED000_ACTUAL_INERTIA_KGM2),
            "m_act": SEED000_ACTUAL_MASS_KG,
        },
    }


VEHICLES = vehicles()


def simulate(
    name: str, failed: int | None, kind: FailureKind, seed: int,
    fsw_tmax: np.ndarray | None = None,
) -> tuple[list[tuple[int, ThrusterFailure]], list[int], RateResidualFdir]:
    """Run the strategy against the synthetic truth; (isolations, detection times, strategy).

    ``fsw_tmax``: the maxima the strategy is told (default: the truth's).
    """
    v = VEHICLES[name]
    b = np.asarray(v["b"])
    n = b.shape[1]
    tmax = np.asarray(v["tmax"])
    rng = np.random.default_rng(seed)
    n_cycles = round(T_END_S * NS / PERIOD_NS)
    t_fail = round(T_FAIL_S * NS)
    # random commands: fire with probability P_FIRE, on-time 5..20 ms
    fire = rng.random((n_cycles, n)) < P_FIRE
    on = np.where(fire, rng.uniform(MIN_ON_S, PERIOD_NS / NS, (n_cycles, n)), 0.0)
    truth_timing = dataclasses.replace(
        DEFAULT_TIMING, command_delay_s=DEFAULT_TIMING.command_delay_s + TRUTH_EXTRA_DELAY_S
    )
    truth = ThrustModel(n, MIN_ON_S, truth_timing, 10 * NS)
    for k in range(n_cycles):
        cmd = on[k].copy()
        if failed is not None and kind == FailureKind.STUCK_CLOSED and k * PERIOD_NS >= t_fail:
            cmd[failed] = 0.0  # the valve never opens again
        truth.command(k * PERIOD_NS, cmd)
    j_act = np.asarray(v["j_act"])
    j_inv = np.linalg.inv(j_act)
    ang = j_inv @ b[3:6] * tmax
    lin = b[0:3] * tmax / float(v["m_act"])  # type: ignore[arg-type]
    t_imu = np.arange(0, n_cycles * PERIOD_NS + 1, IMU_NS)
    frac, _ = truth.fraction_at(t_imu)
    omega = np.zeros((t_imu.size, 3))
    for s in range(1, t_imu.size):
        a, c = int(t_imu[s - 1]), int(t_imu[s])
        tau = truth.thrust_time_s(a, c)
        if failed is not None and kind == FailureKind.STUCK_OPEN and c > t_fail:
            frac[s, failed] = 1.0
            tau[failed] = (c - max(a, t_fail)) / NS + (tau[failed] if a < t_fail else 0.0)
        w = omega[s - 1]
        omega[s] = w + ang @ tau - j_inv @ np.cross(w, j_act @ w) * (c - a) / NS
    gyro = omega + rng.normal(0.0, GYRO_SIGMA_RAD_S, omega.shape)
    gyro = np.round(gyro / GYRO_LSB_RAD_S) * GYRO_LSB_RAD_S
    accel = frac @ lin.T + ACCEL_BIAS_M_S2 + rng.normal(0.0, ACCEL_SIGMA_M_S2, (t_imu.size, 3))
    fdir = RateResidualFdir(
        b,
        np.asarray(v["j_nom"]),
        float(v["m_nom"]),  # type: ignore[arg-type]
        tmax if fsw_tmax is None else fsw_tmax,
        MIN_ON_S,
        PERIOD_NS,
        IMU_NS,
        RateResidualParams(),  # the model's valve timing: the defaults, as the truth's
    )
    isolations: list[tuple[int, ThrusterFailure]] = []
    detections: list[int] = []
    s = 0
    for k in range(n_cycles):
        t = k * PERIOD_NS
        while s < t_imu.size and t_imu[s] <= t:
            fdir.on_gyro(int(t_imu[s]), gyro[s])
            fdir.on_accel(int(t_imu[s]), accel[s])
            s += 1
        verdict = fdir.evaluate(t)
        if verdict.detected:
            detections.append(t)
        if verdict.failure is not None:
            isolations.append((t, verdict.failure))
            fdir.set_failures(t, [verdict.failure])
        fdir.on_command(t, on[k])
    return isolations, detections, fdir


CASES = [
    (name, k, kind)
    for name, v in VEHICLES.items()
    for k in range(np.asarray(v["b"]).shape[1])
    for kind in (FailureKind.STUCK_CLOSED, FailureKind.STUCK_OPEN)
]


@pytest.mark.parametrize(("name", "failed", "kind"), CASES)
def test_every_thruster_isolated_with_its_kind(name: str, failed: int, kind: FailureKind) -> None:
    """The first isolation names the failed thruster and kind, soon after the failure."""
    isolations, detections, _ = simulate(name, failed, kind, seed=1000 + failed)
    assert isolations, "not isolated"
    _, f = isolations[0]
    assert (f.thruster, f.kind) == (failed, kind)
    assert all(d >= T_FAIL_S * NS for d in detections), "detection before the failure"
    limit = DETECT_OPEN_MAX_S if kind == FailureKind.STUCK_OPEN else DETECT_CLOSED_MAX_S
    assert (f.t_detect_ns - T_FAIL_S * NS) / NS <= limit
    assert f.t_isolate_ns >= f.t_detect_ns


@pytest.mark.parametrize("name", list(VEHICLES))
def test_no_false_alarm_without_failure(name: str) -> None:
    """Healthy thrusters, model errors and noise only: nothing detected over the run."""
    for seed in range(3):
        isolations, detections, fdir = simulate(name, None, FailureKind.NONE, seed=seed)
        assert not isolations and not detections
        assert fdir.last is not None and fdir.last.norm < RateResidualParams().threshold


def test_bad_parameters_are_named() -> None:
    """Bad settings raise ConfigError naming the key."""
    for key, value in (
        ("window_s", 0.0),
        ("persistence_cycles", 0),
        ("explained_fraction", 2.0),
        ("gyro_noise_rad_s", -1.0),
        ("use_accel", 1),
    ):
        with pytest.raises(ConfigError) as err:
            RateResidualParams(**{key: value})  # type: ignore[arg-type]
        assert err.value.key == key
    assert math.isfinite(RateResidualParams().threshold)


def test_one_top_level_maximum_misreads_a_non_uniform_layout() -> None:
    """Told one maximum for all (the largest), the weak thrusters look failed: false alarms
    that the per-thruster maxima above do not raise."""
    v = VEHICLES["seed003_8_unequal"]
    top = np.full(8, float(np.max(np.asarray(v["tmax"]))))
    alarms = 0
    for seed in range(3):
        isolations, detections, _ = simulate("seed003_8_unequal", None, FailureKind.NONE,
                                             seed=seed, fsw_tmax=top)
        alarms += len(detections) + len(isolations)
    assert alarms > 0


def test_maxima_of_the_wrong_shape_are_refused() -> None:
    """One number, or n − 1 maxima, for n thrusters: ConfigError naming max_thrust_N."""
    v = VEHICLES["seed003_8"]
    for bad in (SEED003_THRUST_N, np.full(7, SEED003_THRUST_N), np.zeros(8)):
        with pytest.raises(ConfigError) as err:
            RateResidualFdir(np.asarray(v["b"]), np.asarray(v["j_nom"]), SEED003_MASS_KG,
                             bad, MIN_ON_S, PERIOD_NS, IMU_NS, RateResidualParams())
        assert err.value.key == "max_thrust_N"


def test_a_window_with_one_accelerometer_sample_has_no_linear_channel() -> None:
    """Gyro samples throughout but one accelerometer sample in the window: evaluated on the
    angular channel alone (linear z = 0), nothing raised."""
    v = next(iter(VEHICLES.values()))
    b = np.asarray(v["b"])
    n = b.shape[1]
    fdir = RateResidualFdir(b, np.asarray(v["j_nom"]), float(v["m_nom"]),  # type: ignore[arg-type]
                            np.asarray(v["tmax"]), MIN_ON_S, PERIOD_NS, IMU_NS,
                            RateResidualParams())
    n_cycles = round(T_END_S * NS / PERIOD_NS)
    for k in range(n_cycles):
        t = k * PERIOD_NS
        for s in range(PERIOD_NS // IMU_NS):
            fdir.on_gyro(t + s * IMU_NS, np.zeros(3))
        if k == n_cycles - 2:
            fdir.on_accel(t, np.zeros(3))
        fdir.evaluate(t)
        fdir.on_command(t, np.zeros(n))
    assert fdir.last is not None
    assert np.array_equal(fdir.last.z[3:], np.zeros(3))
