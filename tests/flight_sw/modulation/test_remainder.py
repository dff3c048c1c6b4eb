"""Tests of the remainder firing logic (Basilisk thrFiringRemainder semantics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.modulation.remainder import RemainderModulator, RemainderParams

PERIOD_S = 0.02  # 50 Hz control period
MIN_ON_S = 0.004
N_PERIODS = 5000
T_NS = 0
ROUND_OFF_S = 1e-9  # float round-off of summing N_PERIODS on-times (≲ N·eps·100 s)


def make() -> RemainderModulator:
    """A modulator with the test minimum on-time and no remainder."""
    return RemainderModulator(RemainderParams(min_on_s=MIN_ON_S))


@pytest.mark.parametrize("u", [0.01, 0.05, 0.123, 0.19, 0.2, 0.5, 0.97])
def test_total_impulse_equals_demand_within_one_min_pulse(u: float) -> None:
    """Σ on-time = N u P − r with 0 ≤ r < t_min at every step, for constant demands."""
    mod = make()
    fired = 0.0
    for k in range(1, N_PERIODS + 1):
        on = mod.on_time_s(T_NS, u, PERIOD_S)
        assert on == 0.0 or on >= MIN_ON_S
        fired += on
        owed = k * u * PERIOD_S - fired
        assert -ROUND_OFF_S <= owed < MIN_ON_S + ROUND_OFF_S
        assert math.isclose(owed, mod.remainder_s, abs_tol=ROUND_OFF_S)


def test_varying_demand_impulse_is_conserved() -> None:
    """With a random sub-saturating demand the fired impulse trails the demand by r < t_min."""
    rng = np.random.default_rng(3)
    demands = rng.uniform(0.0, 0.3, N_PERIODS)
    mod = make()
    on = np.array([mod.on_time_s(T_NS, float(u), PERIOD_S) for u in demands])
    assert np.all((on == 0.0) | (on >= MIN_ON_S))
    owed = demands.sum() * PERIOD_S - on.sum()
    assert -ROUND_OFF_S <= owed < MIN_ON_S + ROUND_OFF_S


def test_small_demand_fires_min_pulses_periodically() -> None:
    """u P = t_min/4 fires one pulse of exactly t_min every fourth period."""
    mod = make()
    u = 0.25 * MIN_ON_S / PERIOD_S
    on = [mod.on_time_s(T_NS, u, PERIOD_S) for _ in range(8)]
    assert on[:3] == [0.0, 0.0, 0.0]
    assert math.isclose(on[3], MIN_ON_S, rel_tol=1e-12)
    assert math.isclose(on[7], MIN_ON_S, rel_tol=1e-12)


def test_saturation_drops_excess() -> None:
    """u = 1 after a remainder fires the whole period and clears the remainder."""
    mod = make()
    mod.on_time_s(T_NS, 0.5 * MIN_ON_S / PERIOD_S, PERIOD_S)
    assert mod.remainder_s > 0.0
    assert mod.on_time_s(T_NS, 1.0, PERIOD_S) == PERIOD_S
    assert mod.remainder_s == 0.0


def test_nan_adds_nothing_and_reset_clears() -> None:
    """NaN counts as 0 demand (the remainder is kept); reset() forgets it."""
    mod = make()
    mod.on_time_s(T_NS, 0.5 * MIN_ON_S / PERIOD_S, PERIOD_S)
    before = mod.remainder_s
    assert mod.on_time_s(T_NS, math.nan, PERIOD_S) == 0.0
    assert mod.remainder_s == before
    mod.reset()
    assert mod.remainder_s == 0.0


@pytest.mark.parametrize("value", [-1e-3, math.nan, math.inf, True, "4 ms"])
def test_invalid_min_on_is_rejected(value: object) -> None:
    """An invalid min_on_s raises a ConfigError naming it."""
    with pytest.raises(ConfigError) as info:
        RemainderParams(min_on_s=value)  # type: ignore[arg-type]
    assert info.value.key == "min_on_s"
