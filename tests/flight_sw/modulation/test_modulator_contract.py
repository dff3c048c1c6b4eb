"""Interface contract of every Modulator implementation (PWPF, Schmitt, remainder, proportional)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from flight_sw.modulation.base import Modulator
from flight_sw.modulation.proportional import ProportionalModulator
from flight_sw.modulation.pwpf import PwpfModulator, PwpfParams
from flight_sw.modulation.remainder import RemainderModulator, RemainderParams
from flight_sw.modulation.schmitt import SchmittModulator, SchmittParams

PERIOD_S = 0.02  # 50 Hz control period
MIN_ON_S = 0.004  # below the period, as every strategy's min-pulse guarantee assumes
N_RANDOM = 2000
N_CONSTANT = 1000  # 20 s per constant demand: well past the PWPF transient
DEMAND_GRID = np.linspace(0.0, 1.0, 21)
MEAN_MONOTONE_TOL = 1e-3  # of the period: one PWPF limit cycle cut by the window
T_NS = 0
PERIOD_NS = 20_000_000

# Each entry: (name, factory, minimum on-time the strategy guarantees [s]).
STRATEGIES: list[tuple[str, Callable[[], Modulator], float]] = [
    (
        "pwpf",
        lambda: PwpfModulator(
            PwpfParams(km=4.5, tm_s=0.15, u_on=0.45, u_off=0.15, min_on_s=MIN_ON_S)
        ),
        MIN_ON_S,
    ),
    ("schmitt", lambda: SchmittModulator(SchmittParams(min_on_s=MIN_ON_S)), MIN_ON_S),
    ("remainder", lambda: RemainderModulator(RemainderParams(min_on_s=MIN_ON_S)), MIN_ON_S),
    ("proportional", ProportionalModulator, 0.0),
]
IDS = [s[0] for s in STRATEGIES]


@pytest.mark.parametrize(("name", "factory", "min_on_s"), STRATEGIES, ids=IDS)
def test_on_time_within_period_and_min_on(
    name: str, factory: Callable[[], Modulator], min_on_s: float
) -> None:
    """For random demands (outside [0, 1] too) 0 ≤ on ≤ P and on == 0 or on ≥ min_on_s."""
    rng = np.random.default_rng(7)
    mod = factory()
    for k, u in enumerate(rng.uniform(-0.5, 1.5, N_RANDOM)):
        on = mod.on_time_s(T_NS + k * PERIOD_NS, float(u), PERIOD_S)
        assert 0.0 <= on <= PERIOD_S, (name, u, on)
        assert on == 0.0 or on >= min_on_s, (name, u, on)


@pytest.mark.parametrize(("name", "factory", "min_on_s"), STRATEGIES, ids=IDS)
def test_nan_demand_fires_nothing(
    name: str, factory: Callable[[], Modulator], min_on_s: float
) -> None:
    """A NaN demand from rest gives no pulse, repeatedly."""
    mod = factory()
    for k in range(N_CONSTANT // 10):
        assert mod.on_time_s(T_NS + k * PERIOD_NS, math.nan, PERIOD_S) == 0.0, name


@pytest.mark.parametrize(("name", "factory", "min_on_s"), STRATEGIES, ids=IDS)
def test_mean_response_is_monotone_in_constant_demand(
    name: str, factory: Callable[[], Modulator], min_on_s: float
) -> None:
    """The mean on-time over a long constant-demand run (from rest) does not decrease with u."""
    means = []
    for u in DEMAND_GRID:
        mod = factory()
        on = [mod.on_time_s(T_NS + k * PERIOD_NS, float(u), PERIOD_S) for k in range(N_CONSTANT)]
        means.append(float(np.mean(on)) / PERIOD_S)
    assert means[0] == 0.0, name
    assert means[-1] > 0.0, name  # full demand fires (PWPF with U_off > 0 never saturates)
    assert np.all(np.diff(means) >= -MEAN_MONOTONE_TOL), (name, means)
