"""The records that cross between bench and flight software besides frames: round trips,
versions, and errors that name the key."""

from __future__ import annotations

import json
import math
from typing import Any

import pytest

from dbc.contract import (
    CONFIG_SCHEMA,
    REFUSAL_SCHEMA,
    VERSION,
    FswConfig,
    FswRefusal,
    Manoeuvre,
    ThrusterConfig,
    ValveTiming,
)
from dbc.errors import ConfigError

SQRT_HALF = math.sqrt(0.5)


def _config(**kw: Any) -> FswConfig:
    args: dict[str, Any] = dict(
        source="s.toml", mass_kg=95.0,
        inertia_B_kgm2=((10.0, 0.0, 0.0), (0.0, 12.0, 0.0), (0.0, 0.0, 14.0)),
        thrusters=(ThrusterConfig((0.5, 0.0, 0.0), (0.0, 1.0, 0.0), 2.35),
                   ThrusterConfig((-0.5, 0.0, 0.0), (0.0, -1.0, 0.0), 2.3)),
        valves=ValveTiming(0.005, 0.003, 0.002, 0.002, 0.003),
        manoeuvre=Manoeuvre((SQRT_HALF, SQRT_HALF, 0.0, 0.0), 1.0),
        flight_sw={"controller": {"kind": "anything"}})
    args.update(kw)
    return FswConfig(**args)


def test_config_round_trips_through_json() -> None:
    """to_json, a JSON text and from_json give the same record back."""
    cfg = _config(manoeuvre=Manoeuvre((1.0, 0.0, 0.0, 0.0), 2.0, "mrp_polynomial",
                                      ((0.0, 1e-3), (0.0, 0.0), (0.0, 0.0)), (1.0, 2.0, 3.0)))
    data = json.loads(json.dumps(cfg.to_json()))
    assert (data["schema"], data["version"]) == (CONFIG_SCHEMA, VERSION)
    assert FswConfig.from_json(data, "f.json") == cfg


def test_another_major_version_is_refused_naming_it() -> None:
    """A version-2 file is refused: ConfigError on key ``version`` with the value 2."""
    data = _config().to_json()
    data["version"] = VERSION + 1
    with pytest.raises(ConfigError) as info:
        FswConfig.from_json(data, "f.json")
    assert (info.value.source, info.value.key, info.value.value) == ("f.json", "version", 2)


@pytest.mark.parametrize("path, value", [
    (("thrusters", 0, "max_thrust_N"), 0.0),
    (("valves", "open_delay_s"), -1.0),
    (("vehicle", "mass_kg"), "heavy"),
])
def test_bad_values_name_their_key(path: tuple[Any, ...], value: Any) -> None:
    """A bad value deep in the file is refused with its dotted key."""
    data = _config().to_json()
    node: Any = data
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    with pytest.raises(ConfigError) as info:
        FswConfig.from_json(data, "f.json")
    assert info.value.key.endswith(str(path[-1])) and info.value.value == value


def test_unknown_key_is_refused() -> None:
    """A key the contract does not define is an error (a misspelt key never goes unseen)."""
    data = _config().to_json()
    data["valve_model"] = "on_off"
    with pytest.raises(ConfigError, match="valve_model"):
        FswConfig.from_json(data, "f.json")


def test_a_non_unit_target_quaternion_is_refused() -> None:
    """q_target_BN must be a unit quaternion."""
    with pytest.raises(ConfigError, match="q_target_BN"):
        _config(manoeuvre=Manoeuvre((1.0, 1.0, 0.0, 0.0), 0.0))


def test_refusal_round_trips_and_words_itself_as_the_error() -> None:
    """A refusal record keeps source, key, value and expectation; its message is the
    ConfigError's own text; a value JSON cannot hold is kept as its text."""
    exc = ConfigError("cfg.json", "flight_sw.modulator.kind", "pwfp", "one of 'pwpf'")
    rec = FswRefusal.of(exc).to_json()
    assert rec["schema"] == REFUSAL_SCHEMA and rec["message"] == str(exc)
    assert FswRefusal.from_json(json.loads(json.dumps(rec)), "s.json") == FswRefusal.of(exc)
    odd = FswRefusal("cfg", "k", float("nan"), "a finite number").to_json()
    assert odd["value"] == "nan"
