"""Whole series fed sample by sample through bench.results.error_stats, for tests."""

from __future__ import annotations

import numpy as np

from bench.results.error_stats import ErrorStats, PointingMetrics, SettlingTracker


def pointing_metrics(t_s: np.ndarray, att_err_deg: np.ndarray, rate_err_deg_s: np.ndarray,
                     band_deg: float, window_s: float, t_start_s: float = 0.0
                     ) -> PointingMetrics:
    """ErrorStats.pointing() after every sample of the arrays."""
    stats = ErrorStats(band_deg, window_s, t_start_s)
    for t, a, r in zip(t_s.tolist(), att_err_deg.tolist(), rate_err_deg_s.tolist(),
                       strict=True):
        stats.add(t, a, r, 0.0)
    return stats.pointing()


def settling_time_s(t_s: np.ndarray, err: np.ndarray, band: float,
                    t_start_s: float = 0.0) -> float | None:
    """SettlingTracker.settling_time_s() after every sample of the arrays."""
    tracker = SettlingTracker(band, t_start_s)
    for t, e in zip(t_s.tolist(), err.tolist(), strict=True):
        tracker.add(t, e)
    return tracker.settling_time_s()
