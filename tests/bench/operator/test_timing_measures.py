"""Timing measurements and records on known answers: options, periods, percentiles,
cycle-time windows, missed cycles, data age, busy time per window."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.operator.analysis.measures import (
    cycle_time_violations,
    data_age_s,
    missed_cycles,
    period_stats_s,
    window_busy_s,
)
from bench.operator.analysis.records import Percentiles, TimingOptions
from bench.wire.timing.arbiter import Delivery
from bench.wire.timing.load import busy_ns_per_window
from dbc.errors import ConfigError

# Tolerances, named: float sums of seconds near 0.1 s carry ~1e-17 s error each.
TIME_TOL_S = 1e-12
TIME_TOL_US = 1e-6

US = 1e-6
MS = 1e-3
NAN = float("nan")
IMU_PERIOD_S = 10 * MS  # GenMsgCycleTime of IMU_RATE


# -- options -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("window_ms", 0.0),
        ("window_ms", float("inf")),
        ("cycle_abs_tolerance_ms", -1.0),
        ("cycle_rel_tolerance_pct", 100.0),
        ("cycle_rel_tolerance_pct", True),
        ("missed_gap_periods", 1.0),
    ],
)
def test_options_reject_bad_values(key: str, value: object) -> None:
    """Each invalid option raises ConfigError naming the key."""
    with pytest.raises(ConfigError, match=key):
        TimingOptions(**{key: value})  # type: ignore[arg-type]


def test_options_defaults_documented() -> None:
    """Defaults: 10 ms windows, ±1 ms and ±10 % cycle windows, gaps over 1.5 periods."""
    o = TimingOptions()
    assert (o.window_ms, o.cycle_abs_tolerance_ms, o.cycle_rel_tolerance_pct) == (10, 1, 10)
    assert o.missed_gap_periods == 1.5


# -- pure functions ----------------------------------------------------------------------


def test_period_mean_and_jitter_known_answer() -> None:
    """Intervals alternating P+d, P-d: mean P, std d, max-min 2d."""
    period, d, n = 10 * MS, 300 * US, 11
    t = np.array([k * period + (d if k % 2 else 0.0) for k in range(n)])
    mean, std, pp = period_stats_s(t)
    assert mean == pytest.approx(period, abs=TIME_TOL_S)
    assert std == pytest.approx(d, abs=TIME_TOL_S)
    assert pp == pytest.approx(2 * d, abs=TIME_TOL_S)


def test_period_of_single_frame_is_nan() -> None:
    """Fewer than two frames: no period."""
    assert all(math.isnan(x) for x in period_stats_s(np.array([1.0])))


def test_percentiles_known_answer() -> None:
    """Latencies 0..100 us: p50 50, p99 99, max 100, n 101 (linear interpolation)."""
    p = Percentiles.of_seconds(np.arange(101) * US)
    assert (p.p50_us, p.p99_us, p.max_us, p.n) == pytest.approx((50, 99, 100, 101), abs=TIME_TOL_US)


def test_percentiles_of_nothing_fail_assertions() -> None:
    """No samples: nan everywhere and n = 0, so `p99_us < limit` is False."""
    p = Percentiles.of_seconds([NAN])
    assert p.n == 0 and not p.p99_us < 1e9


def test_cycle_time_violations_absolute_and_relative_windows() -> None:
    """10 ms cycle, ±1 ms and ±4 %: 10.5 and 9.5 break only the relative window; 11.5, 8.5 both."""
    intervals = np.array([10.0, 10.5, 9.5, 11.5, 8.5, 10.2, 10.0]) * MS
    n_abs, n_rel = cycle_time_violations(intervals, 10 * MS, 1 * MS, 0.04)
    assert (n_abs, n_rel) == (2, 4)
    assert cycle_time_violations(intervals, 10 * MS, None, None) == (None, None)


def test_missed_cycles_from_gaps_and_counters() -> None:
    """Drop 1 then 3 frames: 4 missed; counters agree; a counter skip alone counts too."""
    period = IMU_PERIOD_S
    kept = [0, 1, 2, 4, 5, 9, 10]  # frame 3 lost, frames 6..8 lost
    t = np.array(kept) * period
    c = np.array(kept) % 15
    assert missed_cycles(t, c, period, 1.5) == (4, 4)
    t_ok = np.arange(4) * period
    c_skip = np.array([0, 1, 3, 4])  # the sender skipped counter 2, timing is regular
    assert missed_cycles(t_ok, c_skip, period, 1.5) == (1, 1)


def test_missed_cycles_long_gap_beats_counter_wrap() -> None:
    """20 frames lost: the counter (mod 15) shows 5, the gap shows 20; 20 counts."""
    period = IMU_PERIOD_S
    t = np.array([0.0, 21 * period])
    c = np.array([0, 21 % 15])
    assert missed_cycles(t, c, period, 1.5) == (20, 5)


def test_counter_wrap_and_repeat_are_not_misses() -> None:
    """14 -> 0 is the normal wrap; a repeated counter is rejected, not missed."""
    period = IMU_PERIOD_S
    t = np.arange(3) * period
    assert missed_cycles(t, np.array([13, 14, 0]), period, 1.5) == (0, 0)
    assert missed_cycles(t, np.array([5, 5, 6]), period, 1.5) == (0, 0)


def test_data_age_uses_newest_source_received_before_queuing() -> None:
    """A source received after the destination was queued is not used; no source: no sample."""
    src_ready = np.array([0.0, 10.0, 20.9]) * MS
    src_rx = np.array([0.2, 10.2, 21.1]) * MS  # the third arrives after dst is queued
    dst_ready = np.array([-1.0, 21.0]) * MS  # the first has no earlier source
    dst_rx = np.array([-0.8, 21.15]) * MS
    age = data_age_s(src_rx, src_ready, dst_ready, dst_rx)
    assert age == pytest.approx([11.15 * MS], abs=TIME_TOL_S)


def test_window_busy_splits_intervals_exactly() -> None:
    """Intervals inside, across one and across three 10 ms windows: 1.5, 5.5, 10, 5 ms."""
    start = np.array([1.0, 9.5, 15.0]) * MS
    end = np.array([2.0, 10.5, 35.0]) * MS
    busy = window_busy_s(start, end, 0.0, 10 * MS, 4)
    assert busy == pytest.approx(np.array([1.5, 5.5, 10.0, 5.0]) * MS, abs=TIME_TOL_S)


def test_window_busy_agrees_with_bus_model_load() -> None:
    """Same busy time per window as bench.wire.timing.load.busy_ns_per_window (independent
    code)."""
    rng = np.random.default_rng(7)
    window_ns, n_windows = 10_000_000, 50
    starts = np.sort(rng.integers(0, (n_windows - 1) * window_ns, 400))
    ends = starts + rng.integers(50_000, 3 * window_ns, starts.size)
    dels = [
        Delivery(0, int(a), int(b), 1, i)
        for i, (a, b) in enumerate(zip(starts, ends, strict=True))
    ]
    t1 = n_windows * window_ns + 3 * window_ns
    ref = [busy for _, busy in busy_ns_per_window(dels, window_ns, 0, t1)]
    mine = window_busy_s(starts / 1e9, ends / 1e9, 0.0, window_ns / 1e9, len(ref))
    assert mine * 1e9 == pytest.approx(ref, abs=1.0)  # 1 ns: float seconds vs integer ns
