"""Flight-software configuration: the scenario's [flight_sw] builds a computer; errors are named."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
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


FORCE_FREE_ATOL_N = 1e-9  # net force of a pure-torque allocation (round-off) [N]
PURE_TORQUE_DEMAND_NM = 2.0  # scale of the random torque demands (inside the authority) [N m]


def test_attitude_only_allocates_torque_with_zero_force(cfg: dict[str, Any]) -> None:
    """Quickstart (attitude only): the allocator gets the 6 wrench rows and its thrusts for
    a torque demand with zero force give that torque and no net force."""
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert fc.pure_torque and fc.allocator.effectiveness.shape == (6, 8)  # type: ignore[attr-defined]
    b = fc.allocator.effectiveness  # type: ignore[attr-defined]
    rng = np.random.default_rng(5)
    for _ in range(20):
        torque = rng.normal(size=3) * PURE_TORQUE_DEMAND_NM
        res = fc.allocator.allocate(np.concatenate((np.zeros(3), torque)))
        assert np.linalg.norm(b[:3] @ res.thrust_N) <= FORCE_FREE_ATOL_N
        assert not res.saturated and res.residual_norm <= FORCE_FREE_ATOL_N


def test_pure_torque_false_allocates_the_torque_rows_only(cfg: dict[str, Any]) -> None:
    """pure_torque = false: the 3 torque rows (the seed papers' allocation)."""
    cfg["flight_sw"]["pure_torque"] = False
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert not fc.pure_torque and fc.allocator.effectiveness.shape == (3, 8)  # type: ignore[attr-defined]


def test_layout_without_force_free_torque_is_warned(cfg: dict[str, Any]) -> None:
    """Thruster 0 removed: +z torque needs a net force, so the torque rows are used and
    the statistics' warnings name the axis."""
    del cfg["thrusters"][0]
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert not fc.pure_torque and fc.allocator.effectiveness.shape == (3, 7)  # type: ignore[attr-defined]
    assert any("pure_torque" in w and "+z" in w for w in fc.warnings)


def test_pure_torque_false_with_a_6dof_law_is_refused() -> None:
    """The 6-DoF NFTSM allocates the wrench already: pure_torque = false is named an error."""
    cfg = load_scenario(QUICKSTART.parent / "formation_keeping_nftsm.toml").fsw_config()
    cfg["flight_sw"]["pure_torque"] = False
    with pytest.raises(ConfigError) as info:
        build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == "flight_sw.pure_torque"


def test_seed000_scenario_builds_a_fine_hold() -> None:
    """formation_keeping_nftsm: the NFTSM wrapped in a fine hold with the scenario's PD pair."""
    from flight_sw.control.fine_hold import FineHold
    from flight_sw.control.nftsm_dq import NftsmDq

    cfg = load_scenario(QUICKSTART.parent / "formation_keeping_nftsm.toml").fsw_config()
    fc = build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert isinstance(fc.pose, FineHold) and isinstance(fc.pose.coarse, NftsmDq)
    assert fc.pose.params.leave_position_m == cfg["flight_sw"]["fine_hold"]["leave_position_m"]


def test_fine_hold_with_an_attitude_only_law_is_refused(cfg: dict[str, Any]) -> None:
    """A fine_hold table beside an attitude controller is named an error."""
    cfg["flight_sw"]["fine_hold"] = {}
    with pytest.raises(ConfigError) as info:
        build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
    assert info.value.key == "flight_sw.fine_hold"


def test_fine_hold_misspelt_threshold_is_refused() -> None:
    """An unknown key in the fine_hold table is an error, not a silent default."""
    cfg = load_scenario(QUICKSTART.parent / "formation_keeping_nftsm.toml").fsw_config()
    cfg["flight_sw"]["fine_hold"]["enter_positon_m"] = 0.1
    with pytest.raises(ConfigError, match="enter_positon_m"):
        build_computer(cfg, PERIOD_NS, IMU_NS, WATCH)
