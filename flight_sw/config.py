"""Flight-software configuration: a JSON file -> the wired :class:`FlightComputer`.

The file (written by the bench's orchestrator from the scenario, or by hand for a real
vehicle) holds the nominal vehicle (mass, inertia), the thruster geometry, the manoeuvre
and the ``flight_sw`` table of the scenario: which estimator, controller, allocator and
modulator to use, with their parameters. Each strategy is chosen by ``kind`` from a
registry: a new algorithm is a new file plus one registry line. Every bad value raises
ConfigError naming the scenario file and the dotted key (``flight_sw.modulator.km``).
Angles are converted to radians here.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dbc.errors import ConfigError
from dbc.schema import Table
from flight_sw.allocation.base import Allocator
from flight_sw.allocation.effectiveness import effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.computer import FlightComputer, Timeline
from flight_sw.control.base import AttitudeController
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.estimation.base import AttitudeEstimator
from flight_sw.estimation.mekf import Mekf, MekfParams
from flight_sw.fdir.sensor_watchdog import SensorWatchdog
from flight_sw.modulation.base import Modulator
from flight_sw.modulation.pwpf import PwpfModulator, PwpfParams

DEG_RAD = math.pi / 180.0
ARCSEC_RAD = DEG_RAD / 3600.0
SQRT_HOUR_S = 60.0
NS_PER_S = 1_000_000_000
TORQUE_ROWS = slice(3, 6)


class Vehicle:
    """Nominal vehicle data the strategies are built from."""

    def __init__(self, t: Table, root: Table) -> None:
        self.mass_kg = t.number("mass_kg", lo=0.0, lo_open=True)
        self.inertia_B_kgm2 = np.array(t.matrix3("inertia_B_kgm2"))
        t.done()
        thr = root.tables("thrusters")
        if not thr:
            raise root.error("thrusters", [], "at least one thruster")
        self.r_thr_B_m = np.array([x.vector("r_thr_B_m", 3) for x in thr])
        self.d_thr_B = np.array([x.vector("d_thr_B", 3) for x in thr])
        for x in thr:
            x.done()
        self.max_thrust_N = root.number("max_thrust_N", lo=0.0, lo_open=True)
        self.min_on_s = root.number("min_on_s", lo=0.0)


def _mekf(t: Table, v: Vehicle) -> AttitudeEstimator:
    return Mekf(
        MekfParams(
            gyro_arw_rad_sqrt_s=t.number("gyro_arw_deg_sqrt_h", lo=0.0) * DEG_RAD / SQRT_HOUR_S,
            gyro_bias_rw_rad_s_sqrt_s=t.number("gyro_bias_rw_deg_h_sqrt_h", lo=0.0)
            * DEG_RAD
            / 3600.0
            / SQRT_HOUR_S,
            star_tracker_sigma_rad=t.number("star_tracker_noise_arcsec", lo=0.0, lo_open=True)
            * ARCSEC_RAD,
            initial_attitude_sigma_rad=t.number(
                "initial_attitude_sigma_deg", 0.1, lo=0.0, lo_open=True
            )
            * DEG_RAD,
            initial_bias_sigma_rad_s=t.number("initial_bias_sigma_deg_h", lo=0.0, lo_open=True)
            * DEG_RAD
            / 3600.0,
        )
    )


def _quaternion_pd(t: Table, v: Vehicle) -> AttitudeController:
    max_rate = (
        t.number("max_rate_deg_s", lo=0.0, lo_open=True) * DEG_RAD
        if t.has("max_rate_deg_s")
        else math.inf
    )
    if t.has("kp_Nm"):
        params = QuaternionPdParams(
            kp_Nm=t.vector3("kp_Nm"),
            kd_Nms=t.vector3("kd_Nms"),
            max_rate_rad_s=max_rate,
        )
    else:
        params = QuaternionPdParams.from_bandwidth(
            np.diag(v.inertia_B_kgm2).tolist(),
            t.number("natural_frequency_rad_s", lo=0.0, lo_open=True),
            t.number("damping_ratio", lo=0.0),
            max_rate,
        )
    return QuaternionPd(params)


def _pseudo_inverse(t: Table, v: Vehicle) -> Allocator:
    b = effectiveness_matrix(v.r_thr_B_m, v.d_thr_B)[TORQUE_ROWS]
    return PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_N=v.max_thrust_N))


def _pwpf(t: Table, v: Vehicle) -> Callable[[], Modulator]:
    params = PwpfParams(
        km=t.number("km", lo=0.0, lo_open=True),
        tm_s=t.number("tm_s", lo=0.0, lo_open=True),
        u_on=t.number("u_on", lo=0.0, lo_open=True),
        u_off=t.number("u_off", lo=0.0),
        min_on_s=v.min_on_s,
    )
    return lambda: PwpfModulator(params)


ESTIMATORS: dict[str, Callable[[Table, Vehicle], AttitudeEstimator]] = {"mekf": _mekf}
CONTROLLERS: dict[str, Callable[[Table, Vehicle], AttitudeController]] = {
    "quaternion_pd": _quaternion_pd
}
ALLOCATORS: dict[str, Callable[[Table, Vehicle], Allocator]] = {"pseudo_inverse": _pseudo_inverse}
MODULATORS: dict[str, Callable[[Table, Vehicle], Callable[[], Modulator]]] = {"pwpf": _pwpf}


def _strategy(parent: Table, key: str, registry: dict[str, Any], v: Vehicle) -> Any:
    t = parent.table(key)
    kind = t.string("kind", choices=tuple(registry))
    try:
        built = registry[kind](t, v)
    except ConfigError as exc:
        if exc.source == t.source:
            raise
        # a parameter class rejected a derived value: re-anchor the error in the file
        raise ConfigError(t.source, f"{t.path}.{exc.key}", exc.value, exc.expected) from exc
    t.done()
    return built


def build_computer(
    cfg: dict[str, Any],
    control_period_ns: int,
    imu_period_ns: int,
    watch_periods_ns: dict[str, int],
) -> FlightComputer:
    """Build the flight computer described by the configuration ``cfg``."""
    source = str(cfg.get("source", "<flight-software config>"))
    root = Table(cfg, source)
    root.raw("source", "")
    vehicle = Vehicle(root.table("vehicle"), root)
    man = root.table("manoeuvre")
    q_target = np.array(man.vector("q_target_BN", 4))
    if abs(float(np.linalg.norm(q_target)) - 1.0) > 1e-6:
        raise man.error("q_target_BN", q_target.tolist(), "a unit quaternion")
    t_start_ns = round(man.number("t_start_s", lo=0.0) * NS_PER_S)
    man.done()
    fsw = root.table("flight_sw", {})
    estimator = _strategy(fsw, "estimator", ESTIMATORS, vehicle)
    controller = _strategy(fsw, "controller", CONTROLLERS, vehicle)
    allocator = _strategy(fsw, "allocator", ALLOCATORS, vehicle)
    make_modulator = _strategy(fsw, "modulator", MODULATORS, vehicle)
    fsw.done()
    root.done()
    return FlightComputer(
        estimator=estimator,
        controller=controller,
        allocator=allocator,
        modulators=[make_modulator() for _ in range(len(vehicle.r_thr_B_m))],
        max_thrust_N=vehicle.max_thrust_N,
        control_period_ns=control_period_ns,
        imu_period_ns=imu_period_ns,
        timeline=Timeline(q_target, t_start_ns),
        watchdog=SensorWatchdog(watch_periods_ns),
    )


def load_config(path: str | Path) -> dict[str, Any]:
    """Read the configuration JSON at ``path``."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(
            str(p), "<file>", str(p), f"a readable configuration file ({exc.strerror})"
        ) from exc
    except json.JSONDecodeError as exc:
        raise ConfigError(str(p), "<syntax>", str(exc), "valid JSON") from exc
    if not isinstance(data, dict):
        raise ConfigError(str(p), "<root>", type(data).__name__, "a JSON object")
    return data
