"""Fault entries of a scenario: every kind parses with its target and parameters; bad ones named."""

from __future__ import annotations

from typing import Any

import pytest

from bench.station.faults import FaultSpec, parse_faults
from dbc.errors import ConfigError
from dbc.schema import Table

MESSAGES = frozenset({"IMU_RATE", "THR_CMD_0"})
NODES = frozenset({"BENCH", "FSW"})


def _parse(entry: dict[str, Any]) -> FaultSpec:
    return parse_faults([Table(entry, "f.toml", "faults[0]")], 60.0, 8, MESSAGES, NODES)[0]


@pytest.mark.parametrize(
    ("entry", "expected"),
    [
        ({"kind": "degraded", "thruster": 2, "factor": 0.5}, {"thruster": 2, "factor": 0.5}),
        (
            {"kind": "misaligned", "thruster": 1, "angle_deg": 2.0, "axis_B": [0, 0, 1]},
            {"angle_deg": 2.0, "axis_B": (0.0, 0.0, 1.0)},
        ),
        (
            {"kind": "drop", "message": "IMU_RATE", "probability": 0.1},
            {"message": "IMU_RATE", "probability": 0.1},
        ),
        ({"kind": "delay", "node": "FSW", "delay_s": 0.002}, {"node": "FSW", "delay_s": 0.002}),
        ({"kind": "babbling", "can_id": 1, "rate_hz": 500.0}, {"can_id": 1, "rate_hz": 500.0}),
        (
            {"kind": "bias_jump", "sensor": "gyro", "jump_rad_s": [0.001, 0, 0]},
            {"sensor": "gyro", "jump_rad_s": (0.001, 0.0, 0.0)},
        ),
        ({"kind": "noise", "sensor": "star_tracker", "factor": 3.0}, {"factor": 3.0}),
    ],
)
def test_each_kind_parses_with_its_target_and_parameters(entry: dict, expected: dict) -> None:  # type: ignore[type-arg]
    """The record of a parsed fault carries the target and parameters given."""
    rec = _parse({"t_s": 1.0, **entry}).record()
    for key, value in expected.items():
        assert rec[key] == value, key


@pytest.mark.parametrize(
    ("entry", "key"),
    [
        ({"kind": "degraded", "thruster": 8, "factor": 0.5}, "faults[0].thruster"),
        ({"kind": "degraded", "thruster": 1, "factor": 1.5}, "faults[0].factor"),
        ({"kind": "drop", "message": "NOPE"}, "faults[0].message"),
        ({"kind": "drop", "message": "IMU_RATE", "node": "FSW"}, "faults[0].message"),
        ({"kind": "babbling", "can_id": 0x800, "rate_hz": 10.0}, "faults[0].can_id"),
        ({"kind": "outage", "sensor": "magnetometer"}, "faults[0].sensor"),
        ({"kind": "stuck_open", "thruster": 1, "factor": 2.0}, "faults[0].factor"),
    ],
)
def test_bad_entries_name_the_key(entry: dict, key: str) -> None:  # type: ignore[type-arg]
    """Out-of-range targets, bad parameters and stray keys are ConfigErrors on their key."""
    with pytest.raises(ConfigError) as info:
        _parse({"t_s": 1.0, **entry})
    assert info.value.key == key
