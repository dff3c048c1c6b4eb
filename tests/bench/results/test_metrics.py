"""Run metrics: settling, convergence, steady state (streamed) and latency percentiles on
known series."""

from __future__ import annotations

import numpy as np

from bench.results.metrics import expectation, latency_summary, settling_expectation
from tests.bench.results.streamed import pointing_metrics, settling_time_s

BAND_DEG = 0.5
WINDOW_S = 10.0
DT_S = 0.01
TAU_S = 2.0


def test_exponential_decay_settles_when_analytic() -> None:
    """e(t) = 30 exp(-t/τ) enters a 0.5 deg band at t = τ ln(60), to one sample."""
    t = np.arange(0.0, 60.0, DT_S)
    err = 30.0 * np.exp(-t / TAU_S)
    m = pointing_metrics(t, err, 0.1 * err, BAND_DEG, WINDOW_S)
    assert m.converged
    assert abs(m.settling_time_s - TAU_S * np.log(30.0 / BAND_DEG)) <= DT_S
    assert m.steady_state_attitude_error_deg == err[t >= t[-1] - WINDOW_S].max()


def test_error_leaving_band_at_end_is_not_converged() -> None:
    """An error outside the band at the last sample: not settled, not converged."""
    t = np.arange(0.0, 20.0, DT_S)
    err = np.full_like(t, 0.1)
    err[-1] = 1.0
    m = pointing_metrics(t, err, err, BAND_DEG, WINDOW_S)
    assert m.settling_time_s is None and not m.converged


def test_latency_percentiles_in_microseconds() -> None:
    """Percentiles of 1..100 us samples, reported in us."""
    s = latency_summary([i * 1000 for i in range(1, 101)])
    assert s["n"] == 100 and s["max"] == 100.0
    assert s["p50"] == 50.5 and 99.0 <= s["p99"] <= 100.0
    assert latency_summary([])["n"] == 0


def test_expectation_rows() -> None:
    """Pass iff value <= max; None limit means no row; a missing value fails."""
    assert expectation("x", 1.0, 2.0)["pass"] is True
    assert expectation("x", 3.0, 2.0)["pass"] is False
    assert expectation("x", None, 2.0)["pass"] is False
    assert expectation("x", 1.0, None) is None


def test_short_run_steady_state_starts_at_settling() -> None:
    """A run shorter than the window: steady state is measured after settling, not from t=0."""
    t = np.arange(0.0, 9.5, DT_S)  # settles at tau ln(60) = 8.2 s, inside the 10 s window
    err = 30.0 * np.exp(-t / TAU_S)
    m = pointing_metrics(t, err, err, BAND_DEG, WINDOW_S)
    assert m.converged and m.steady_state_attitude_error_deg <= BAND_DEG


def test_position_settling_time_known_answer() -> None:
    """Error leaves the band last at t = 2 s: settled at the next sample, 3 s after a 0 s start."""
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    err = np.array([1.0, 0.01, 0.2, 0.01, 0.02])
    assert settling_time_s(t, err, 0.05) == 3.0
    assert settling_time_s(t, err, 0.05, t_start_s=1.0) == 2.0
    assert settling_time_s(t, np.array([0.0, 0.0, 0.0, 0.0, 0.1]), 0.05) is None


def test_settling_of_zero_is_noted_as_never_outside() -> None:
    """A zero settling time (the error never left its band) carries a note; others none."""
    t = np.arange(0.0, 5.0, DT_S)
    inside = settling_time_s(t, np.full_like(t, 0.1), BAND_DEG)
    row = settling_expectation("settling_time_s", inside, 10.0, BAND_DEG, "deg")
    assert inside == 0.0 and row is not None and row["pass"]
    assert row["note"] == f"never outside the {BAND_DEG:g} deg band"
    err = 30.0 * np.exp(-t / TAU_S)
    later = settling_expectation("settling_time_s", settling_time_s(t, err, 5.0), 10.0, 5.0, "deg")
    assert later is not None and later["value"] > 0.0 and "note" not in later
    assert settling_expectation("x", 0.0, None, BAND_DEG, "deg") is None
