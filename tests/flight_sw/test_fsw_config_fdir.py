"""Configuration of 6-DoF control and FDIR: optional tables, strict keys, the wired computer."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bench.scenario.load import load_scenario
from dbc.errors import ConfigError
from flight_sw.config import build_computer
from flight_sw.control.position_pd import PositionPd
from flight_sw.control.quaternion_pid import QuaternionPid
from flight_sw.fdir.rate_residual import RateResidualFdir
from flight_sw.fdir.valve_status import ValveStatusFdir

ROOT = Path(__file__).resolve().parents[2]
FDIR16 = ROOT / "scenarios" / "fdir_16thr.toml"
QUICKSTART = ROOT / "scenarios" / "quickstart.toml"
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
WATCH = {"IMU_RATE": IMU_NS, "STR_QUAT": 100_000_000, "NAV_POS": 100_000_000}


@pytest.fixture
def cfg16() -> dict[str, Any]:
    """fdir_16thr's flight-software configuration (mask precomputation off for speed)."""
    cfg = load_scenario(FDIR16).fsw_config()
    cfg["flight_sw"]["thruster_fdir"]["precompute_masks"] = False
    return cfg


def test_fdir_16thr_builds_a_6dof_computer_with_both_fdir_strategies(
    cfg16: dict[str, Any],
) -> None:
    """Translation PD, 6-row allocator, valve-status then residual FDIR, PID attitude law."""
    fc = build_computer(cfg16, PERIOD_NS, IMU_NS, WATCH)
    assert isinstance(fc.translation, PositionPd)
    assert isinstance(fc.controller, QuaternionPid)
    assert fc.effectiveness is not None and fc.effectiveness.shape == (6, 16)
    assert fc.allocator.allocate(np.zeros(6)).thrust_N.shape == (16,)
    assert fc.thruster_fdir is not None
    kinds = [type(s) for s in fc.thruster_fdir.strategies]
    assert kinds == [ValveStatusFdir, RateResidualFdir]
    assert fc.timeline.r_target_N_m is not None and not fc.timeline.r_target_N_m.any()
    assert fc.nav_timeout_ns == 3 * WATCH["NAV_POS"]


def test_quickstart_stays_attitude_only_without_fdir() -> None:
    """No translation or thruster_fdir table: attitude only (pure torque: the 6 wrench rows
    with a zero force demand), no thruster FDIR."""
    fc = build_computer(load_scenario(QUICKSTART).fsw_config(), PERIOD_NS, IMU_NS, WATCH)
    assert fc.translation is None and fc.thruster_fdir is None and fc.pure_torque
    assert fc.effectiveness is not None and fc.effectiveness.shape == (6, 8)


def test_single_failure_allocators_are_precomputed() -> None:
    """precompute_masks (default): one allocator per single-thruster mask, before the run."""
    cfg = load_scenario(QUICKSTART).fsw_config()
    cfg["flight_sw"]["thruster_fdir"] = {"valve_status": {}}
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert len(fc.allocators_by_mask) == 8
    for mask, alloc in fc.allocators_by_mask.items():
        failed = mask.index(False)
        assert alloc.allocate(np.array([0.0, 0.0, 0.0, 0.5, -0.2, 0.1])).thrust_N[failed] == 0.0


@pytest.mark.parametrize(
    ("path", "value", "key"),
    [
        (("thruster_fdir", "kalman"), {}, "flight_sw.thruster_fdir.kalman"),
        (
            ("thruster_fdir", "rate_residual", "windw_s"),
            0.3,
            "flight_sw.thruster_fdir.rate_residual.windw_s",
        ),
        (
            ("thruster_fdir", "valve_status", "quiet_cycles"),
            0,
            "flight_sw.thruster_fdir.valve_status.quiet_cycles",
        ),
        (("translation", "kind"), "lqr", "flight_sw.translation.kind"),
        (("translation", "max_force_N"), -1.0, "flight_sw.translation.max_force_N"),
        (("sensor_fdir", "imu_rate_samples"), 1, "flight_sw.sensor_fdir.imu_rate_samples"),
        (("controller", "integral_time_s"), 0.0, "flight_sw.controller.integral_time_s"),
    ],
)
def test_bad_fdir_and_6dof_keys_are_named(
    cfg16: dict[str, Any], path: tuple[str, ...], value: object, key: str
) -> None:
    """Unknown or bad keys of the new tables raise ConfigError naming the dotted key."""
    bad = copy.deepcopy(cfg16)
    table = bad["flight_sw"]
    for part in path[:-1]:
        table = table[part]
    table[path[-1]] = value
    with pytest.raises(ConfigError) as info:
        build_computer(bad, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == key and info.value.source == str(FDIR16)


def test_empty_thruster_fdir_table_is_an_error(cfg16: dict[str, Any]) -> None:
    """thruster_fdir must name at least one strategy."""
    bad = copy.deepcopy(cfg16)
    bad["flight_sw"]["thruster_fdir"] = {}
    with pytest.raises(ConfigError) as info:
        build_computer(bad, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == "flight_sw.thruster_fdir"


def _residual_fdir(cfg: dict[str, Any]) -> RateResidualFdir:
    """The rate-residual strategy of the computer built from ``cfg``."""
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert fc.thruster_fdir is not None
    (found,) = [s for s in fc.thruster_fdir.strategies if isinstance(s, RateResidualFdir)]
    return found


def test_vehicle_valve_timing_is_the_residual_fdirs_default(cfg16: dict[str, Any]) -> None:
    """The file's valves table (the bench's valve data) sets the model's timing unless the
    FDIR table says; a negative delay there is refused naming its key."""
    table = cfg16["flight_sw"]["thruster_fdir"]["rate_residual"]
    for key in ("valve_open_delay_s", "valve_tail_tau_s"):
        del table[key]
    cfg16["valves"].update(open_delay_s=0.004, tail_tau_s=0.005, close_delay_s=0.001)
    timing = _residual_fdir(cfg16).model.timing
    assert (timing.open_delay_s, timing.tail_tau_s) == (0.004, 0.005)  # the vehicle's
    assert timing.close_delay_s == table["valve_close_delay_s"]  # the FDIR table's
    cfg16["valves"]["open_delay_s"] = -1.0
    with pytest.raises(ConfigError) as info:
        build_computer(cfg16, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == "valves.open_delay_s"


def test_residual_fdir_gets_each_thrusters_maximum(cfg16: dict[str, Any]) -> None:
    """Per-thruster maxima in the file reach the residual model, thruster by thruster."""
    maxima = [5.0 if k % 2 else 4.0 for k in range(16)]
    for entry, m in zip(cfg16["thrusters"], maxima, strict=True):
        entry["max_thrust_N"] = m
    fdir = _residual_fdir(cfg16)
    b = build_computer(cfg16, PERIOD_NS, IMU_NS, WATCH).effectiveness
    assert b is not None
    mass_kg = float(cfg16["vehicle"]["mass_kg"])
    np.testing.assert_array_equal(fdir._res.lin, b[0:3] * (np.array(maxima) / mass_kg))
