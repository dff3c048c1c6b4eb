"""Flight-software configuration: the scenario's [flight_sw] builds a computer; errors are named."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from bench.scenario.load import load_scenario
from dbc.errors import ConfigError
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator
from flight_sw.config import build_computer
from flight_sw.control.quaternion_pd import QuaternionPd
from flight_sw.estimation.mekf import Mekf
from flight_sw.modulation.pwpf import PwpfModulator

QUICKSTART = Path(__file__).resolve().parents[2] / "scenarios" / "quickstart.toml"
PERIOD_NS = 20_000_000
IMU_NS = 10_000_000
WATCH = {"IMU_RATE": IMU_NS, "STR_QUAT": 100_000_000}


@pytest.fixture
def cfg() -> dict[str, Any]:
    """The quickstart's flight-software configuration, as the orchestrator writes it."""
    return load_scenario(QUICKSTART).fsw_config()


def test_quickstart_builds_the_baseline_chain(cfg: dict[str, Any]) -> None:
    """MEKF, quaternion PD, pseudo-inverse allocator and one PWPF per thruster."""
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert isinstance(fc.estimator, Mekf)
    assert isinstance(fc.controller, QuaternionPd)
    assert isinstance(fc.allocator, PseudoInverseAllocator)
    assert len(fc.modulators) == 8 and all(isinstance(m, PwpfModulator) for m in fc.modulators)


def test_unknown_strategy_is_named(cfg: dict[str, Any]) -> None:
    """kind = 'lqr' names flight_sw.controller.kind and the scenario file."""
    bad = copy.deepcopy(cfg)
    bad["flight_sw"]["controller"]["kind"] = "lqr"
    with pytest.raises(ConfigError) as info:
        build_computer(bad, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == "flight_sw.controller.kind" and info.value.source == str(QUICKSTART)


def test_parameter_class_errors_are_anchored_in_the_file(cfg: dict[str, Any]) -> None:
    """u_off above u_on is rejected by PwpfParams and reported at flight_sw.modulator.*."""
    bad = copy.deepcopy(cfg)
    bad["flight_sw"]["modulator"]["u_off"] = 0.9
    with pytest.raises(ConfigError) as info:
        build_computer(bad, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key.startswith("flight_sw.modulator.")
    assert info.value.source == str(QUICKSTART)


def test_misspelt_key_is_rejected(cfg: dict[str, Any]) -> None:
    """An unknown key in a strategy table is an error, not a silent default."""
    bad = copy.deepcopy(cfg)
    bad["flight_sw"]["estimator"]["gyro_arw"] = 0.1
    with pytest.raises(ConfigError, match=r"flight_sw\.estimator\.gyro_arw"):
        build_computer(bad, PERIOD_NS, IMU_NS, WATCH)


def test_every_consumer_gets_each_thrusters_maximum() -> None:
    """Seed 001's unequal valves (2.35 N, 2.3 N): the pseudo-inverse bounds each thruster by
    its own maximum, and the flight computer scales each on-time by it."""
    capture = QUICKSTART.parent / "capture_inertia_identification.toml"
    cfg = load_scenario(capture).fsw_config()
    expected = [float(t["max_thrust_N"]) for t in cfg["thrusters"]]
    assert len(set(expected)) > 1  # the layout really is non-uniform
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert isinstance(fc.allocator, PseudoInverseAllocator)
    assert fc.allocator.bounds_N[1].tolist() == expected
    assert fc.max_thrust_N.tolist() == expected
