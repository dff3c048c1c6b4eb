"""Ideal throttled valve: constant thrust (on/P)·Fmax over the period, exact impulse on any grid."""

from __future__ import annotations

import pytest

from bench.station.valves.params import ValveParams
from bench.station.valves.throttled import ThrottledValve
from bench.station.valves.thruster_set import ThrusterGeometry, ThrusterSet
from dbc.errors import ConfigError

PERIOD_NS = 20_000_000
STEP_NS = 1_000_000
F_MAX_N = 2.35
REL_TOL = 1e-12
PARAMS = ValveParams(F_MAX_N, 220.0, 0.003, 0.002, 0.002, 0.003, 0.005)


def _set() -> ThrusterSet:
    return ThrusterSet(
        [ThrusterGeometry((0.0, 0.0, 0.0), (1.0, 0.0, 0.0))], PARAMS,
        valve_factory=lambda p, rng: ThrottledValve(p, PERIOD_NS, rng),
    )


@pytest.mark.parametrize("offset_ns", [0, 123_457, 500_000, 999_999])
def test_impulse_over_a_period_is_on_time_times_fmax(offset_ns: int) -> None:
    """Commands off the 1 ms grid still book exactly on·Fmax over the RK4 steps."""
    ts = _set()
    on_ns = 7_300_000
    ts.command(offset_ns, 0, on_ns)
    for k in range(2 * PERIOD_NS // STEP_NS):
        ts.stage_wrenches(k * STEP_NS, STEP_NS)
    assert ts.impulse_Ns[0] == pytest.approx(on_ns * 1e-9 * F_MAX_N, rel=REL_TOL)


def test_thrust_is_constant_over_the_period_then_zero() -> None:
    """F = (on/P)·Fmax from the command for one period, no delay, no rise, then 0 and idle."""
    v = ThrottledValve(PARAMS, PERIOD_NS)
    v.command(0, PERIOD_NS // 4)
    level = F_MAX_N / 4
    assert {v.thrust_N(t) for t in range(0, PERIOD_NS, STEP_NS)} == {level}
    assert v.thrust_N(PERIOD_NS) == 0.0 and v.idle_from_ns == PERIOD_NS
    assert v.stage_thrusts_N(STEP_NS, STEP_NS) == (level, level, level)


def test_a_newer_command_replaces_the_current_one() -> None:
    """A command mid-period sets the new level from its arrival; an on-time > P saturates."""
    v = ThrottledValve(PARAMS, PERIOD_NS)
    v.command(0, PERIOD_NS // 2)
    v.command(5_000_000, 2 * PERIOD_NS)
    assert v.thrust_N(4_999_999) == F_MAX_N / 2
    assert v.thrust_N(5_000_000) == F_MAX_N
    assert v.openings == 1


def test_faults_stuck_closed_and_unsupported() -> None:
    """stuck_closed zeroes the thrust; delayed (opening physics) is a ConfigError."""
    v = ThrottledValve(PARAMS, PERIOD_NS)
    v.command(0, PERIOD_NS)
    v.set_fault("stuck_closed", 1_000_000)
    assert v.thrust_N(2_000_000) == 0.0
    with pytest.raises(ConfigError, match="kind"):
        v.set_fault("delayed", 2_000_000, extra_delay_s=0.01)
