"""Fault entries of a scenario: every kind parses with its target and parameters; bad ones named."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from bench.station.faults import NO_FATE, FaultSpec, frame_fate, parse_faults
from dbc.errors import ConfigError
from dbc.schema import Table

MESSAGES = frozenset({"IMU_RATE", "THR_CMD_0"})
NODES = frozenset({"BENCH", "FSW"})
N_FATES = 20_000
P = 0.3
SIGMAS = 5.0


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


def test_frame_fate_probability_and_targeting() -> None:
    """A drop at p hits about p of matching frames and never a frame of another message."""
    spec = _parse({"t_s": 0.0, "kind": "drop", "message": "IMU_RATE", "probability": P})
    rng = np.random.default_rng(1)
    hits = sum(frame_fate([spec], "IMU_RATE", "BENCH", rng).drop for _ in range(N_FATES))
    sigma = (N_FATES * P * (1 - P)) ** 0.5
    assert abs(hits - P * N_FATES) <= SIGMAS * sigma
    assert frame_fate([spec], "THR_CMD_0", "FSW", rng) is NO_FATE
