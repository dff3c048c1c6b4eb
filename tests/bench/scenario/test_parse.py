"""Scenario loading: the quickstart is the seed-003 vehicle; every bad field is named."""

from __future__ import annotations

import contextlib
import math
import random
import sys
from pathlib import Path

import pytest

from bench.scenario.load import apply_overrides, load_scenario
from bench.scenario.parse import parse_scenario, quat_from_euler_zyx
from dbc.codec import bitrate_range_bps
from dbc.database import load_database
from dbc.errors import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

QUICKSTART = Path(__file__).resolve().parents[3] / "scenarios" / "quickstart.toml"
SEED003_INERTIA = (15.95, 72.19, 72.19)
SEED003_THRUST_N = 15.0
N_FUZZ = 300
SEED = 8


def _data() -> dict:  # type: ignore[type-arg]
    return tomllib.loads(QUICKSTART.read_text())


def test_quickstart_is_the_seed003_vehicle() -> None:
    """Table 1's inertia, thrust level and 8 thrusters at R = 0.45 m, L = 0.22 m."""
    sc = load_scenario(QUICKSTART)
    assert tuple(sc.actual.inertia_B_kgm2[i][i] for i in range(3)) == SEED003_INERTIA
    assert sc.valve.max_thrust_N == SEED003_THRUST_N and len(sc.thrusters) == 8
    arms = {abs(c) for t in sc.thrusters for c in t.r_thr_B_m}
    assert arms == {0.0, 0.45, 0.22}
    assert sc.flight_sw["modulator"]["u_on"] - sc.flight_sw["modulator"]["u_off"] == pytest.approx(
        0.1
    )


def test_euler_target_known_answer() -> None:
    """A pure 90 deg yaw is q = (cos 45, 0, 0, sin 45)."""
    q = quat_from_euler_zyx(math.pi / 2, 0.0, 0.0)
    assert q == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)))


@pytest.mark.parametrize(
    ("section", "key", "value", "dotted"),
    [
        ("thrusters", "max_thrust_N", -1.0, "thrusters.max_thrust_N"),
        ("thrusters", "layout", "nope", "thrusters.layout"),
        (
            "vehicle",
            "inertia_B_kgm2",
            [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
            "vehicle.inertia_B_kgm2",
        ),
        (  # symmetric, positive definite, but no body has it (triangle inequality)
            "vehicle",
            "inertia_B_kgm2",
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5.0]],
            "vehicle.inertia_B_kgm2",
        ),
        ("scenario", "duration_s", "60", "scenario.duration_s"),
        ("sensors.gyro", "range_rad_s", 10.0, "sensors.gyro.range_rad_s"),  # beyond the DBC
        ("sensors.accelerometer", "range_m_s2", 5.0, "sensors.accelerometer.range_m_s2"),
        (
            "sensors.star_tracker",
            "boresight_B",
            [0.0, 0.0, 2.0],
            "sensors.star_tracker.boresight_B",
        ),
        ("bus", "bitrate_bps", 2_000_000, "bus.bitrate_bps"),
        ("manoeuvre", "t_start_s", 1e9, "manoeuvre.t_start_s"),
        ("thrusters", "max_thrust", 15.0, "thrusters.max_thrust"),  # misspelt key
        (  # beyond a full turn: a unit slip (e.g. an angle in arcminutes)
            "manoeuvre",
            "target_euler_zyx_deg",
            [2000.0, 0.0, 0.0],
            "manoeuvre.target_euler_zyx_deg",
        ),
    ],
)
def test_bad_field_names_file_key_and_value(
    section: str, key: str, value: object, dotted: str
) -> None:
    """The error carries the file, the dotted key and the bad value."""
    data = _data()
    table = data
    for part in section.split("."):
        table = table[part]
    table[key] = value
    with pytest.raises(ConfigError) as info:
        parse_scenario(data, "my.toml")
    assert info.value.source == "my.toml" and info.value.key == dotted
    assert repr(value) in str(info.value)


def test_fault_on_missing_thruster_is_rejected() -> None:
    """A fault naming thruster 8 of 8 is an error on faults[0].thruster."""
    data = _data()
    data["faults"] = [{"t_s": 1.0, "kind": "stuck_open", "thruster": 8}]
    with pytest.raises(ConfigError, match=r"faults\[0\]\.thruster"):
        parse_scenario(data, "f.toml")


def test_unreadable_and_malformed_files(tmp_path: Path) -> None:
    """Missing file and TOML syntax errors are ConfigErrors naming the file."""
    with pytest.raises(ConfigError, match=r"nope\.toml"):
        load_scenario(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scenario\nname = 1")
    with pytest.raises(ConfigError, match=r"bad\.toml"):
        load_scenario(bad)


def test_fuzzed_scenarios_raise_only_config_errors() -> None:
    """Random type/value mutations of the quickstart load or fail with ConfigError, nothing else."""
    rng = random.Random(SEED)
    junk = [None, -1, 0, 1e308, float("nan"), "x", [], [1, 2], {"a": 1}, True, [[1]], 10**30]
    for _ in range(N_FUZZ):
        data = _data()
        table = data
        path = []
        while isinstance(table, dict) and table:
            key = rng.choice(sorted(table))
            path.append(key)
            if not isinstance(table[key], dict) or rng.random() < 0.3:
                table[key] = rng.choice(junk)
                break
            table = table[key]
        with contextlib.suppress(ConfigError):
            parse_scenario(data, "fuzz.toml")


def test_overrides_set_nested_keys_and_are_validated() -> None:
    """KEY=VALUE overrides reach nested tables as TOML values and are validated like the file."""
    sc = load_scenario(QUICKSTART, ["bus.bitrate_bps=125000", "flight_sw.modulator.km=10.0"])
    assert sc.bus.bitrate_bps == 125_000 and sc.flight_sw["modulator"]["km"] == 10.0
    with pytest.raises(ConfigError, match=r"bus\.bitrate_bps"):
        load_scenario(QUICKSTART, ["bus.bitrate_bps=fast"])
    with pytest.raises(ConfigError, match="KEY=VALUE") as err:
        load_scenario(QUICKSTART, ["bitrate"])
    assert err.value.source == f"command line (--set on {QUICKSTART})"


def test_a_bad_override_is_blamed_on_the_command_line() -> None:
    """A bad or misspelt --set value names --set and the file it was applied to; a bad value
    from the file itself still names only the file."""
    for item, key in (("bus.bitrate_bps=fast", "bus.bitrate_bps"),
                      ("bus.bitrate_bs=125000", "bus.bitrate_bs")):
        with pytest.raises(ConfigError) as err:
            load_scenario(QUICKSTART, [item])
        assert err.value.source == f"command line --set {item} (on {QUICKSTART})"
        assert err.value.key == key
    sc = load_scenario(QUICKSTART, ["flight_sw.modulator.km=10.0", "bus.bitrate_bps=125000"])
    assert sc.fsw_config()["source"] == (
        f"command line --set flight_sw.modulator.km=10.0 (on {QUICKSTART})")
    assert load_scenario(QUICKSTART).fsw_config()["source"] == str(QUICKSTART)


def test_bitrate_range_is_the_dbc_baudrate_definition() -> None:
    """bus.bitrate_bps: the DBC's Baudrate minimum and maximum are accepted, beyond refused."""
    lo, hi = bitrate_range_bps(load_database())
    for ok in (lo, hi):
        assert load_scenario(QUICKSTART, [f"bus.bitrate_bps={ok}"]).bus.bitrate_bps == ok
    for bad in (lo - 1, hi + 1):
        with pytest.raises(ConfigError, match=rf"bus\.bitrate_bps = {bad}"):
            load_scenario(QUICKSTART, [f"bus.bitrate_bps={bad}"])


def test_override_addresses_an_element_of_an_array_of_tables() -> None:
    """--set faults[1].t_s=30 changes that fault only; out-of-range and bare indices are named."""
    data = {"faults": [{"t_s": 1.0, "kind": "a"}, {"t_s": 2.0, "kind": "b"}]}
    apply_overrides(data, ["faults[1].t_s=30.0"], "s.toml")
    assert data["faults"] == [{"t_s": 1.0, "kind": "a"}, {"t_s": 30.0, "kind": "b"}]
    with pytest.raises(ConfigError, match=r"an element 2 \(it has 2\)"):
        apply_overrides(data, ["faults[2].t_s=1"], "s.toml")
    with pytest.raises(ConfigError, match=r"the whole array: faults=\[\.\.\.\]"):
        apply_overrides(data, ["faults[0]=1"], "s.toml")
    with pytest.raises(ConfigError, match=r"name\[i\]"):
        apply_overrides(data, ["faults[x].t_s=1"], "s.toml")


def test_key_of_another_kind_lists_what_the_table_takes() -> None:
    """A key the table does not read: the error lists the keys it does (and a near miss)."""
    with pytest.raises(ConfigError) as err:
        load_scenario(QUICKSTART, ["bus.bitrate_bs=125000"])
    assert "did you mean 'bitrate_bps'?" in str(err.value)
    assert "this table takes: bitrate_bps," in str(err.value)
