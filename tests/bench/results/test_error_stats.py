"""Streamed convergence figures equal the array form (tests/.../metrics_reference.py) exactly,
and the memory they keep is the last window, whatever the run's length."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.results.error_stats import ErrorStats
from tests.bench.results import metrics_reference as ref
from tests.bench.results.streamed import pointing_metrics, settling_time_s

DT_S = 0.01
BAND = 0.5
WINDOW_S = 3.0
N_RANDOM = 40


def _series(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A decaying error with noise and random excursions, a random start and length."""
    n = int(rng.integers(1, 2000))
    t_start = float(rng.choice([0.0, 0.37, 2.0]))
    t = t_start + DT_S * np.arange(n)
    att = 5.0 * np.exp(-(t - t_start) / rng.uniform(0.2, 5.0)) + rng.uniform(0, 0.3, n)
    spikes = rng.random(n) < rng.uniform(0.0, 0.01)
    att[spikes] += 2.0
    rate = np.abs(rng.normal(0.0, 0.4, n))
    return t, att, rate, t_start


@pytest.mark.parametrize("seed", range(N_RANDOM))
def test_streamed_pointing_equals_the_array_form(seed: int) -> None:
    """Settling, convergence, steady-state and final errors: equal to the last bit."""
    t, att, rate, t0 = _series(np.random.default_rng(seed))
    got = pointing_metrics(t, att, rate, BAND, WINDOW_S, t0)
    want = ref.pointing_metrics(t, att, rate, BAND, WINDOW_S, t0)
    assert got.converged == want.converged
    assert got.settling_time_s == want.settling_time_s
    assert got.steady_state_attitude_error_deg == want.steady_state_attitude_error_deg
    assert got.steady_state_rate_error_deg_s == want.steady_state_rate_error_deg_s
    assert got.final_attitude_error_deg == want.final_attitude_error_deg


@pytest.mark.parametrize("seed", range(N_RANDOM))
def test_streamed_settling_equals_the_array_form(seed: int) -> None:
    """A band's settling time, streamed, equals the array form's."""
    t, _att, rate, t0 = _series(np.random.default_rng(seed))
    assert settling_time_s(t, rate, BAND, t0) == ref.settling_time_s(t, rate, BAND, t0)


def test_position_errors_over_the_last_window() -> None:
    """Final position error and its maximum over the last window, as the array form."""
    rng = np.random.default_rng(7)
    t = DT_S * np.arange(1000)
    pos = rng.uniform(0.0, 1.0, t.size)
    stats = ErrorStats(BAND, WINDOW_S, 0.0)
    for k in range(t.size):
        stats.add(float(t[k]), 0.0, 0.0, float(pos[k]))
    p = stats.position_errors()
    assert p.final_error_m == pos[-1]
    assert p.steady_state_error_m == pos[t >= t[-1] - WINDOW_S].max()


def test_no_sample_gives_the_empty_figures() -> None:
    """Without a sample: not converged, not settled, NaN errors, zero position errors."""
    stats = ErrorStats(BAND, WINDOW_S, 0.0, rate_band_deg_s=1.0, position_band_m=1.0)
    m = stats.pointing()
    assert not m.converged and m.settling_time_s is None
    assert all(math.isnan(x) for x in (m.steady_state_attitude_error_deg,
                                       m.final_attitude_error_deg))
    assert stats.position_errors().final_error_m == 0.0
    assert stats.rate is not None and stats.rate.settling_time_s() is None


def test_memory_is_the_last_window() -> None:
    """After 100 windows of samples only the last window's samples are kept."""
    stats = ErrorStats(BAND, WINDOW_S, 0.0)
    n = int(100 * WINDOW_S / DT_S)
    for k in range(n):
        stats.add(k * DT_S, 0.1, 0.1, 0.1)
    assert len(stats._recent) <= WINDOW_S / DT_S + 2
    assert stats.n == n


def test_nan_samples_propagate_like_numpy() -> None:
    """A NaN error counts as inside the band and makes the steady-state maximum NaN."""
    t = DT_S * np.arange(500)
    att = np.full(t.size, 0.1)
    att[-3] = math.nan
    got = pointing_metrics(t, att, att, BAND, WINDOW_S)
    want = ref.pointing_metrics(t, att, att, BAND, WINDOW_S)
    assert got.settling_time_s == want.settling_time_s == 0.0
    assert math.isnan(got.steady_state_attitude_error_deg)
    assert math.isnan(want.steady_state_attitude_error_deg)
