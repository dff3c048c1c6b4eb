"""Scenario keys of the bench models (disturbance, HCW, gravity gradient, events, valves,
tracking reference): defaults change nothing, new keys parse, bad values are named."""

from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import Any

import pytest

from bench.scenario.load import load_scenario
from bench.scenario.parse import parse_scenario
from bench.station.dynamics.hcw import hcw_closed_form, mean_motion_rad_s
from bench.station.dynamics.rigid_body import angular_momentum_N
from bench.station.plant import NS_PER_S, STEP_NS, Plant
from dbc.contract import CONFIG_SCHEMA, VERSION, FswConfig
from dbc.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SCENARIOS = Path(__file__).resolve().parents[3] / "scenarios"
QUICKSTART = SCENARIOS / "quickstart.toml"
FDIR16 = SCENARIOS / "fdir_16thr.toml"
IMU_PERIOD_NS = 10_000_000
CONTROL_PERIOD_NS = 20_000_000
REL_TOL = 1e-12


def _data(path: Path = QUICKSTART) -> dict[str, Any]:
    return tomllib.loads(path.read_text())


def test_fsw_config_is_the_contract_record() -> None:
    """The flight-software configuration is a thruster-hil/fsw-config record: every thruster
    with its own maximum, the valves' timing, a step manoeuvre; it reads back equal."""
    for path in (QUICKSTART, FDIR16):
        sc = load_scenario(path)
        cfg = sc.fsw_config()
        assert (cfg["schema"], cfg["version"]) == (CONFIG_SCHEMA, VERSION)
        assert set(cfg) == {"schema", "version", "source", "vehicle", "thrusters", "valves",
                            "manoeuvre", "flight_sw"}
        assert set(cfg["manoeuvre"]) == {"kind", "q_target_BN", "t_start_s"}
        assert [t["max_thrust_N"] for t in cfg["thrusters"]] == list(sc.max_thrusts_N)
        assert cfg["valves"]["open_delay_s"] == sc.valve.open_delay_s
        assert FswConfig.from_json(cfg, "test").to_json() == cfg
        assert sc.disturbance is None and not sc.events and sc.dynamics.translation == "inertial"


def test_new_keys_parse() -> None:
    """Seed 000's disturbance, HCW, gravity gradient, a capture and an MRP reference."""
    d = _data(FDIR16)
    d["disturbance"] = {
        "force_frame": "nav",
        "force_N": [0.06, 0.05, 0.04],
        "force_sinusoids": [{"amplitude_N": [0.03, 0.0, 0.0], "omega_rad_s": 0.6}],
        "torque_Nm": [2e-5, 3e-5, 1e-5],
        "torque_sinusoids": [{"amplitude_Nm": [5e-4, 0.0, 0.0], "omega_rad_s": 0.8,
                              "phase_rad": 0.1}],
    }
    d["dynamics"] = {"translation": "hcw"}
    d["environment"] = {"gravity_gradient": True}
    d["events"] = [{"kind": "capture", "t_s": 10.0, "mass_kg": 150.0,
                    "inertia_B_kgm2": [[25.0, 0, 0], [0, 20.0, 0], [0, 0, 15.0]],
                    "com_B_m": [0.0, -0.1, 0.0]}]
    d["manoeuvre"] = {"kind": "mrp_polynomial", "t_start_s": 5.0,
                      "mrp_coefficients": [[0.01, 0.0], [0.0], [0.0]],
                      "r_target_N_m": [1.0, 0.0, 0.0]}
    d["expectations"]["position_band_m"] = 0.05
    sc = parse_scenario(d, "m.toml")
    assert sc.disturbance is not None and sc.disturbance.force_frame == "nav"
    assert sc.environment.orbit_radius_m == sc.dynamics.orbit_radius_m == 42_240_000.0
    assert sc.events[0].com_B_m == (0.0, -0.1, 0.0)
    man = sc.fsw_config()["manoeuvre"]
    assert man["kind"] == "mrp_polynomial" and man["r_target_N_m"] == [1.0, 0.0, 0.0]
    assert sc.expectations.position_band_m == 0.05


@pytest.mark.parametrize(
    ("table", "value", "dotted"),
    [
        ("dynamics", {"translation": "kepler"}, "dynamics.translation"),
        ("environment", {"gravity_gradient": 1}, "environment.gravity_gradient"),
        ("disturbance", {"force_frame": "hill"}, "disturbance.force_frame"),
        ("disturbance", {"torque_Nm": [1.0, 2.0]}, "disturbance.torque_Nm"),
        ("events", [{"kind": "explode", "t_s": 1.0}], "events[0].kind"),
    ],
)
def test_bad_new_keys_are_named(table: str, value: object, dotted: str) -> None:
    """Bad values of the new tables raise ConfigError naming the dotted key."""
    d = _data()
    d[table] = value
    with pytest.raises(ConfigError) as info:
        parse_scenario(d, "b.toml")
    assert info.value.key == dotted


def test_seed001_layout_per_thruster_maxima_reach_fsw_config() -> None:
    """seed001_table1_16: 2.35/2.3 N per valve in the plant and the FSW config; top = max."""
    d = _data()
    d["thrusters"].update(layout="seed001_table1_16", arm_R_m=0.75, length_L_m=0.75,
                          max_thrust_N=2.35)
    sc = parse_scenario(d, "s.toml")
    cfg = sc.fsw_config()
    assert [t["max_thrust_N"] for t in cfg["thrusters"]] == [2.35] * 8 + [2.3] * 8
    plant = Plant(sc, 0, IMU_PERIOD_NS)
    assert [v.params.max_thrust_N for v in plant.thrusters.valves] == [2.35] * 8 + [2.3] * 8


def test_explicit_per_thruster_max() -> None:
    """An explicit [[thrusters.list]] entry may carry its own max_thrust_N."""
    d = _data()
    d["thrusters"] = {k: v for k, v in d["thrusters"].items()
                      if k not in ("layout", "arm_R_m", "length_L_m")}
    d["thrusters"]["list"] = [
        {"r_thr_B_m": [0.5, 0.0, 0.0], "d_thr_B": [0.0, 1.0, 0.0], "max_thrust_N": 3.0},
        {"r_thr_B_m": [-0.5, 0.0, 0.0], "d_thr_B": [0.0, -1.0, 0.0]},
    ]
    sc = parse_scenario(d, "e.toml")
    assert sc.max_thrusts_N == (3.0, 15.0)
    assert [t["max_thrust_N"] for t in sc.fsw_config()["thrusters"]] == [3.0, 15.0]


def test_capture_event_applied_by_the_plant_at_its_step() -> None:
    """The plant swaps mass properties at the event's step; H_N of the free body is conserved."""
    d = copy.deepcopy(_data())
    d["initial"]["omega_BN_B_deg_s"] = [2.0, -1.0, 3.0]
    d["events"] = [{"kind": "capture", "t_s": 0.0105, "mass_kg": 150.0,
                    "inertia_B_kgm2": [[25.0, 0, 0], [0, 80.0, 0], [0, 0, 75.0]],
                    "com_B_m": [0.0, 0.1, 0.0]}]
    sc = parse_scenario(d, "c.toml")
    plant = Plant(sc, 0, IMU_PERIOD_NS)
    plant.advance_to(10 * STEP_NS)
    h_before = angular_momentum_N(plant.state, plant.mp)
    plant.advance_to(12 * STEP_NS)
    assert plant.applied_events and plant.applied_events[0][0] == 11 * STEP_NS
    assert plant.mp.mass_kg == 150.0 and plant.thrusters.com_B_m == (0.0, 0.1, 0.0)
    assert angular_momentum_N(plant.state, plant.mp) == pytest.approx(h_before, rel=REL_TOL)


def test_hcw_plant_matches_closed_form() -> None:
    """[dynamics] translation = hcw: the free plant follows the closed-form HCW motion."""
    d = _data()
    d["dynamics"] = {"translation": "hcw"}
    d["initial"]["r_N_m"] = [-20.0, -10.0, -10.0]
    d["initial"]["v_N_m_s"] = [0.01, -0.02, 0.005]
    sc = parse_scenario(d, "h.toml")
    plant = Plant(sc, 0, IMU_PERIOD_NS)
    plant.advance_to(100 * STEP_NS)
    n = mean_motion_rad_s(sc.dynamics.orbit_radius_m)
    r, v = hcw_closed_form(n, sc.r0_N_m, sc.v0_N_m_s, 0.1)
    assert plant.state[7:10] == pytest.approx(r, abs=1e-12)
    assert plant.state[10:13] == pytest.approx(v, abs=1e-14)


def test_throttled_plant_and_fsw_config() -> None:
    """valve_model = throttled: the plant's valves are ideal; the FSW sees min_on_s = 0."""
    d = _data()
    d["thrusters"]["valve_model"] = "throttled"
    sc = parse_scenario(d, "t.toml")
    cfg = sc.fsw_config()
    assert cfg["valves"]["min_on_s"] == 0.0 and "valve_model" not in cfg  # the bench's own
    plant = Plant(sc, 0, IMU_PERIOD_NS, CONTROL_PERIOD_NS)
    plant.thrusters.command(0, 0, CONTROL_PERIOD_NS // 2)
    plant.advance_to(CONTROL_PERIOD_NS)
    impulse = plant.thrusters.impulse_Ns[0]
    assert impulse == pytest.approx(CONTROL_PERIOD_NS / 2 / NS_PER_S * 15.0, rel=REL_TOL)


def test_rate_settling_expectation_parses() -> None:
    """rate_settling_band_deg_s and rate_settling_time_s_max reach the expectations."""
    d = _data()
    d["expectations"].update(rate_settling_band_deg_s=0.2, rate_settling_time_s_max=5.0)
    e = parse_scenario(d, "r.toml").expectations
    assert (e.rate_settling_band_deg_s, e.rate_settling_time_s_max) == (0.2, 5.0)


@pytest.mark.parametrize(
    ("key", "band"),
    [("rate_settling_time_s_max", "rate_settling_band_deg_s"),
     ("position_settling_time_s_max", "position_band_m")],
)
def test_settling_limit_without_its_band_is_named(key: str, band: str) -> None:
    """A settling-time limit without the band it settles into: ConfigError naming both."""
    d = _data()
    d["expectations"][key] = 5.0
    with pytest.raises(ConfigError) as info:
        parse_scenario(d, "b.toml")
    assert info.value.key == f"expectations.{key}" and band in str(info.value)
