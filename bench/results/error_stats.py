"""Convergence figures of a run computed as the telemetry streams in: flat memory.

In: one sample per telemetry instant from the manoeuvre's start on: time t [s], attitude
error [deg] (true attitude vs the target or the moving reference), rate error [deg/s],
position error [m]. Out (:meth:`ErrorStats.pointing`, :meth:`ErrorStats.position`,
:meth:`SettlingTracker.settling_time_s`): settling times, convergence, steady-state and
final errors, the figures ``summary.json`` reports (bench.results.summary).

Definitions (project convention; the settling time is the one the seed papers quote, read
from the error history):
- the settling time of a series in a band is ``t_j - t_start`` where ``j`` is the sample
  after the last one outside the band (error > band); 0 if no sample was outside; None
  (not settled) if the last sample is outside or there is no sample;
- converged: settled, and the final attitude error inside the band;
- steady-state error: the maximum over the samples with ``t >= max(t_end - window,
  t_start + settling)`` (the last window, or less if settling came later); the position's
  steady state is the maximum over the last window.

Memory: O(window / telemetry period) samples (the last window), whatever the run's
length; nothing else grows. ``tests/bench/results/test_error_stats.py`` checks every
figure against the array form (the whole history in numpy) on random and edge-case
series, exactly.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass

NAN = float("nan")


class SettlingTracker:
    """The settling time of one error series in a band, sample by sample."""

    def __init__(self, band: float, t_start_s: float) -> None:
        self.band = band
        self.t_start_s = t_start_s
        self.n = 0
        self._ever_outside = False
        self._last_outside = False  # the latest sample was outside the band
        self._t_settle_s = NAN  # time of the sample after the last one outside

    def add(self, t_s: float, err: float) -> None:
        """One sample (NaN counts as inside, as ``err > band`` is false for it)."""
        if self._last_outside:
            self._t_settle_s = t_s
        self._last_outside = err > self.band
        self._ever_outside = self._ever_outside or self._last_outside
        self.n += 1

    def settling_time_s(self) -> float | None:
        """Seconds from ``t_start_s`` to the sample after the last one outside the band;
        0.0 if none was outside; None if the last sample is outside or there is none."""
        if self.n == 0 or self._last_outside:
            return None
        if not self._ever_outside:
            return 0.0
        return self._t_settle_s - self.t_start_s


@dataclass(frozen=True)
class PointingMetrics:
    """Convergence figures of one run."""

    converged: bool
    settling_time_s: float | None
    steady_state_attitude_error_deg: float
    steady_state_rate_error_deg_s: float
    final_attitude_error_deg: float


@dataclass(frozen=True)
class PositionMetrics:
    """Position figures of one run [m]."""

    final_error_m: float
    steady_state_error_m: float


class ErrorStats:
    """Attitude, rate and position errors of a run, kept as settling trackers and the
    samples of the last ``window_s`` (module docstring)."""

    def __init__(self, band_deg: float, window_s: float, t_start_s: float,
                 rate_band_deg_s: float | None = None,
                 position_band_m: float | None = None) -> None:
        self.window_s = window_s
        self.t_start_s = t_start_s
        self.attitude = SettlingTracker(band_deg, t_start_s)
        self.rate = None if rate_band_deg_s is None else SettlingTracker(rate_band_deg_s,
                                                                         t_start_s)
        self.position = None if position_band_m is None else SettlingTracker(position_band_m,
                                                                             t_start_s)
        # (t [s], attitude [deg], rate [deg/s], position [m]) of the last window
        self._recent: deque[tuple[float, float, float, float]] = deque()

    def add(self, t_s: float, att_err_deg: float, rate_err_deg_s: float,
            pos_err_m: float) -> None:
        """One telemetry sample (times increasing)."""
        self.attitude.add(t_s, att_err_deg)
        if self.rate is not None:
            self.rate.add(t_s, rate_err_deg_s)
        if self.position is not None:
            self.position.add(t_s, pos_err_m)
        recent = self._recent
        recent.append((t_s, att_err_deg, rate_err_deg_s, pos_err_m))
        # a sample older than t - window is older than t_end - window too: never needed
        oldest = t_s - self.window_s
        while recent[0][0] < oldest:
            recent.popleft()

    @property
    def n(self) -> int:
        """Samples taken."""
        return self.attitude.n

    def pointing(self) -> PointingMetrics:
        """Settling, convergence, steady-state and final attitude and rate errors."""
        if not self._recent:
            return PointingMetrics(False, None, NAN, NAN, NAN)
        settling = self.attitude.settling_time_s()
        t_end, final = self._recent[-1][0], self._recent[-1][1]
        start = t_end - self.window_s
        if settling is not None:
            start = max(start, self.t_start_s + settling)
        last = [s for s in self._recent if s[0] >= start]
        return PointingMetrics(
            converged=settling is not None and final <= self.attitude.band,
            settling_time_s=settling,
            steady_state_attitude_error_deg=_nanmax(s[1] for s in last),
            steady_state_rate_error_deg_s=_nanmax(s[2] for s in last),
            final_attitude_error_deg=final,
        )

    def position_errors(self) -> PositionMetrics:
        """Final position error and its maximum over the last window (0 without samples)."""
        if not self._recent:
            return PositionMetrics(0.0, 0.0)
        start = self._recent[-1][0] - self.window_s
        return PositionMetrics(self._recent[-1][3],
                               _nanmax(s[3] for s in self._recent if s[0] >= start))


def _nanmax(values: Iterable[float]) -> float:
    """The maximum, NaN if any value is NaN (as numpy's max)."""
    out = -math.inf
    for v in values:
        if v != v:  # NaN
            return NAN
        out = max(out, v)
    return out
