"""Realtime cycle phase: cycles start a fixed time after the bench's control instants."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from bench.scenario.load import load_scenario
from dbc.errors import ConfigError
from flight_sw.computer import DEFAULT_CYCLE_PHASE_NS
from flight_sw.config import build_computer
from flight_sw.node import _next_phase_ns

PERIOD_NS = 20_000_000
PHASE_NS = 2_000_000
IMU_PERIOD_NS = 10_000_000
WATCH = {"IMU_RATE": 10_000_000, "STR_QUAT": 200_000_000}
QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"


@pytest.fixture
def cfg() -> dict[str, Any]:
    """The quickstart's flight-software configuration, as the orchestrator writes it."""
    return load_scenario(QUICKSTART).fsw_config()


@pytest.mark.parametrize(
    ("now_ns", "base_ns", "expected_ns"),
    [
        (0, 0, PHASE_NS),  # at the bench's time 0: its first cycle, 2 ms on
        (PHASE_NS, 0, PERIOD_NS + PHASE_NS),  # exactly at a phase point: the next one
        (35_000_000, 7_000_000, 7_000_000 + 2 * PERIOD_NS + PHASE_NS),
        (5_000_000, 9_000_000, 9_000_000 + PHASE_NS),  # the bench started after us
    ],
)
def test_next_phase_point_known_answers(now_ns: int, base_ns: int, expected_ns: int) -> None:
    """The first base + k·period + phase strictly after now."""
    assert _next_phase_ns(now_ns, base_ns, PERIOD_NS, PHASE_NS) == expected_ns


def test_phase_is_configurable_and_bounded(cfg: dict[str, Any]) -> None:
    """flight_sw.realtime_cycle_phase_s sets it (default 2 ms); a period or more is refused."""
    assert build_computer(cfg, PERIOD_NS, IMU_PERIOD_NS, WATCH).cycle_phase_ns == (
        DEFAULT_CYCLE_PHASE_NS)
    c = copy.deepcopy(cfg)
    c.setdefault("flight_sw", {})["realtime_cycle_phase_s"] = 0.005
    assert build_computer(c, PERIOD_NS, IMU_PERIOD_NS, WATCH).cycle_phase_ns == 5_000_000
    c["flight_sw"]["realtime_cycle_phase_s"] = 0.02
    with pytest.raises(ConfigError, match="realtime_cycle_phase_s"):
        build_computer(c, PERIOD_NS, IMU_PERIOD_NS, WATCH)
