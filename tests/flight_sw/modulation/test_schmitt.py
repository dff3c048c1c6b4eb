"""Tests of the Schmitt firing logic (Basilisk thrFiringSchmitt semantics)."""

from __future__ import annotations

import math

import pytest

from dbc.errors import ConfigError
from flight_sw.modulation.schmitt import SchmittModulator, SchmittParams

PERIOD_S = 0.02  # 50 Hz control period
MIN_ON_S = 0.004
LEVEL_ON, LEVEL_OFF = 0.75, 0.25
T_NS = 0
TOL_S = 1e-15


def make() -> SchmittModulator:
    """A modulator with the test parameters, at rest (off)."""
    return SchmittModulator(
        SchmittParams(min_on_s=MIN_ON_S, level_on=LEVEL_ON, level_off=LEVEL_OFF)
    )


def u_for_level(level: float) -> float:
    """The demand whose on-time is ``level`` × the minimum fire time."""
    return level * MIN_ON_S / PERIOD_S


def test_above_min_on_is_proportional() -> None:
    """A demand above the minimum fire time gives on = u · P and turns the trigger on."""
    mod = make()
    assert math.isclose(mod.on_time_s(T_NS, 0.5, PERIOD_S), 0.5 * PERIOD_S, abs_tol=TOL_S)
    assert mod.trigger_on


def test_saturation_fires_whole_period() -> None:
    """u ≥ 1 fires the whole period (capped, not Basilisk's 1.1 P)."""
    assert make().on_time_s(T_NS, 1.5, PERIOD_S) == PERIOD_S


def test_short_request_hysteresis() -> None:
    """Between the levels the previous state holds: min pulse if on, nothing if off."""
    mid = u_for_level(0.5 * (LEVEL_ON + LEVEL_OFF))
    mod = make()
    assert mod.on_time_s(T_NS, mid, PERIOD_S) == 0.0  # off stays off
    assert mod.on_time_s(T_NS, u_for_level(LEVEL_ON), PERIOD_S) == MIN_ON_S  # turns on
    assert mod.on_time_s(T_NS, mid, PERIOD_S) == MIN_ON_S  # on stays on
    assert mod.on_time_s(T_NS, u_for_level(LEVEL_OFF), PERIOD_S) == 0.0  # turns off
    assert not mod.trigger_on
    assert mod.on_time_s(T_NS, mid, PERIOD_S) == 0.0


def test_previous_long_pulse_counts_as_on() -> None:
    """After a proportional pulse, a mid-band request fires the minimum pulse."""
    mod = make()
    mod.on_time_s(T_NS, 0.5, PERIOD_S)
    mid = u_for_level(0.5 * (LEVEL_ON + LEVEL_OFF))
    assert mod.on_time_s(T_NS, mid, PERIOD_S) == MIN_ON_S


def test_nan_and_negative_demands_fire_nothing() -> None:
    """NaN and negative demands are treated as 0 and turn the trigger off."""
    mod = make()
    mod.on_time_s(T_NS, 0.5, PERIOD_S)
    assert mod.on_time_s(T_NS, math.nan, PERIOD_S) == 0.0
    assert not mod.trigger_on
    assert mod.on_time_s(T_NS, -0.3, PERIOD_S) == 0.0


def test_min_on_longer_than_period_is_capped() -> None:
    """With t_min > P (level 1/1.2 ≥ level_on) a triggered minimum pulse is capped at the period."""
    mod = SchmittModulator(SchmittParams(min_on_s=1.2 * PERIOD_S))
    assert mod.on_time_s(T_NS, 1.0, PERIOD_S) == PERIOD_S


def test_reset_sets_trigger_state() -> None:
    """reset(True) makes a mid-band request fire the minimum pulse."""
    mod = make()
    mod.reset(trigger_on=True)
    assert mod.on_time_s(T_NS, u_for_level(0.5), PERIOD_S) == MIN_ON_S


@pytest.mark.parametrize(
    ("key", "kwargs"),
    [
        ("min_on_s", {"min_on_s": -1e-3}),
        ("min_on_s", {"min_on_s": math.inf}),
        ("level_on", {"level_on": 1.5}),
        ("level_on", {"level_on": 0.0}),
        ("level_off", {"level_off": 0.8}),
        ("level_off", {"level_off": -0.1}),
        ("min_on_s", {"min_on_s": True}),
    ],
)
def test_invalid_params_are_rejected(key: str, kwargs: dict[str, float]) -> None:
    """Each out-of-range parameter raises a ConfigError naming it."""
    with pytest.raises(ConfigError) as info:
        SchmittParams(**kwargs)
    assert info.value.key == key


def test_invalid_period_is_rejected() -> None:
    """A non-positive period raises ValueError."""
    with pytest.raises(ValueError, match="period_s"):
        make().on_time_s(T_NS, 0.5, 0.0)
