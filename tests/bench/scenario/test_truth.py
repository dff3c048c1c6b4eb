"""The bench's truth the flight software is not told: thrust scale, misalignment, centre-of-
mass offset and initial attitude offset reach the plant and stay out of fsw_config."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bench.scenario.load import load_scenario
from bench.station.plant import Plant
from dbc.errors import ConfigError

REPO = Path(__file__).resolve().parents[3]
QUICKSTART = REPO / "scenarios" / "quickstart.toml"
IMU_PERIOD_NS = 10_000_000
TOL = 1e-12


def test_thrust_scale_reaches_the_valves_not_the_flight_software() -> None:
    """Thruster 2 at 0.9: its valve's maximum thrust is 13.5 N; fsw_config still says 15."""
    scales = [1.0, 1.0, 0.9, 1.0, 1.0, 1.0, 1.0, 1.0]
    sc = load_scenario(QUICKSTART, [f"thrusters.actual_thrust_scale={scales}"])
    plant = Plant(sc, 1, IMU_PERIOD_NS)
    assert [v.params.max_thrust_N for v in plant.thrusters.valves] == pytest.approx(
        [15.0 * s for s in scales], abs=TOL)
    assert {t["max_thrust_N"] for t in sc.fsw_config()["thrusters"]} == {15.0}


def test_misalignment_turns_the_direction_by_its_angle() -> None:
    """A 2 deg rotation vector about an axis normal to d: the plant's direction is 2 deg off
    the nominal one, which fsw_config keeps."""
    nominal = load_scenario(QUICKSTART)
    d0 = nominal.thrusters[0].d_thr_B
    axis = (d0[1], -d0[0], 0.0) if abs(d0[2]) < 0.9 else (1.0, 0.0, 0.0)
    n = math.hypot(*axis)
    rv = [2.0 * a / n for a in axis]
    rows = [rv] + [[0.0, 0.0, 0.0]] * 7
    sc = load_scenario(QUICKSTART, [f"thrusters.actual_misalignment_deg={rows}"])
    d = Plant(sc, 1, IMU_PERIOD_NS).thrusters.geometries[0].d_thr_B
    cos = sum(a * b for a, b in zip(d, d0, strict=True))
    assert math.degrees(math.acos(min(1.0, cos))) == pytest.approx(2.0, abs=1e-9)
    assert sc.fsw_config()["thrusters"] == nominal.fsw_config()["thrusters"]


def test_com_offset_moves_the_arms() -> None:
    """A 5 cm offset: every thruster position in the plant is 5 cm less along x."""
    sc = load_scenario(QUICKSTART, ["vehicle.com_offset_B_m=[0.05, 0.0, 0.0]"])
    geo = Plant(sc, 1, IMU_PERIOD_NS).thrusters.geometries
    for g, t in zip(geo, sc.thrusters, strict=True):
        assert g.r_thr_B_m[0] == pytest.approx(t.r_thr_B_m[0] - 0.05, abs=TOL)


def test_attitude_offset_turns_the_initial_attitude() -> None:
    """A 3 deg offset about z from identity: q0 = (cos 1.5 deg, 0, 0, sin 1.5 deg)."""
    sc = load_scenario(QUICKSTART, ["initial.attitude_offset_deg=[0.0, 0.0, 3.0]"])
    h = math.radians(1.5)
    assert sc.q0_BN == pytest.approx((math.cos(h), 0.0, 0.0, math.sin(h)), abs=TOL)


@pytest.mark.parametrize("override, key", [
    ("thrusters.actual_thrust_scale=[1.0, 1.0]", "thrusters.actual_thrust_scale"),
    ("thrusters.actual_thrust_scale=[0, 1, 1, 1, 1, 1, 1, 1]", "thrusters.actual_thrust_scale"),
    ("thrusters.actual_misalignment_deg=[[0, 0, 0]]", "thrusters.actual_misalignment_deg"),
    ("thrusters.actual_misalignment_deg=[[200, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], "
     "[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]]", "thrusters.actual_misalignment_deg[0]"),
    ("vehicle.com_offset_B_m=[20.0, 0.0, 0.0]", "vehicle.com_offset_B_m"),
])
def test_bad_truth_is_refused_naming_the_key(override: str, key: str) -> None:
    """Wrong length, a zero scale, a turn beyond 180 deg, a 20 m offset: refused by key."""
    with pytest.raises(ConfigError) as e:
        load_scenario(QUICKSTART, [override])
    assert e.value.key == key
