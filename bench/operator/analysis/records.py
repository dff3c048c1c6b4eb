"""The records of a timing analysis: options in, figures out.

What
----
``TimingOptions`` (how the measurements are taken, validated on construction) and the
frozen result records: ``Percentiles`` (p50, p99, max of a sample), ``MessageTiming``
(one message over a run), ``ChainTiming`` (IMU sample -> command -> valve opening),
``LoadFigures`` and ``BusLoad`` (bus load per window). Each result has ``to_dict``, its
JSON-ready form (the content of ``timing.json``). Computed by
:mod:`bench.operator.analysis.measures` and :class:`bench.operator.analysis.timing.RunTiming`.

Outputs
-------
Frozen dataclasses; units in the field names (``_s``, ``_ms``, ``_us``, ``_pct``). An empty
statistic is ``nan`` with ``n = 0``, so an assertion ``x < limit`` on it fails; JSON has
no ``nan``, so ``to_dict`` gives None for it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from bench.operator.analysis.defaults import (
    DEFAULT_CYCLE_ABS_TOLERANCE_MS,
    DEFAULT_CYCLE_REL_TOLERANCE_PCT,
    DEFAULT_MISSED_GAP_PERIODS,
    DEFAULT_WINDOW_MS,
)
from dbc.errors import ConfigError
from dbc.records import percentile_summary

US_PER_S = 1e6
MS_PER_S = 1e3
PCT = 100.0
NAN = float("nan")
OPTIONS_SOURCE = "TimingOptions"


def _is_real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _json_num(value: float | None) -> float | None:
    """``nan``/``inf`` -> None (JSON has neither)."""
    return None if value is None or not math.isfinite(value) else value


@dataclass(frozen=True)
class TimingOptions:
    """How the measurements are taken.

    ``window_ms``: bus-load window length. ``cycle_abs_tolerance_ms``: absolute
    cycle-time window, ±ms around the DBC cycle time (None: not checked).
    ``cycle_rel_tolerance_pct``: relative window, ±% of the cycle time (None: not checked).
    ``missed_gap_periods``: an inter-arrival gap longer than this many cycle times misses
    at least one instance.
    """

    window_ms: float = DEFAULT_WINDOW_MS
    cycle_abs_tolerance_ms: float | None = DEFAULT_CYCLE_ABS_TOLERANCE_MS
    cycle_rel_tolerance_pct: float | None = DEFAULT_CYCLE_REL_TOLERANCE_PCT
    missed_gap_periods: float = DEFAULT_MISSED_GAP_PERIODS

    def __post_init__(self) -> None:
        if not _is_real(self.window_ms) or self.window_ms <= 0:
            raise ConfigError(OPTIONS_SOURCE, "window_ms", self.window_ms, "a finite number > 0")
        tol = self.cycle_abs_tolerance_ms
        if tol is not None and (not _is_real(tol) or tol < 0):
            raise ConfigError(
                OPTIONS_SOURCE, "cycle_abs_tolerance_ms", tol, "None or a finite number >= 0"
            )
        rel = self.cycle_rel_tolerance_pct
        if rel is not None and (not _is_real(rel) or not 0 <= rel < PCT):
            raise ConfigError(
                OPTIONS_SOURCE, "cycle_rel_tolerance_pct", rel, "None or a number in [0, 100)"
            )
        gap = self.missed_gap_periods
        if not _is_real(gap) or gap <= 1:
            raise ConfigError(OPTIONS_SOURCE, "missed_gap_periods", gap, "a finite number > 1")


@dataclass(frozen=True)
class Percentiles:
    """p50, p99 and maximum of a sample in microseconds, and the sample size ``n``."""

    p50_us: float
    p99_us: float
    max_us: float
    n: int

    @classmethod
    def of_seconds(cls, samples_s: np.ndarray | Sequence[float]) -> Percentiles:
        """Percentiles (linear interpolation) of the finite samples, given in seconds."""
        a = np.asarray(samples_s, dtype=float)
        a = a[np.isfinite(a)] * US_PER_S
        s = percentile_summary(a.tolist())
        if not s["n"]:
            return cls(NAN, NAN, NAN, 0)
        return cls(float(s["p50"] or NAN), float(s["p99"] or NAN), float(s["max"] or NAN),
                   int(s["n"] or 0))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        return {
            "p50_us": _json_num(self.p50_us),
            "p99_us": _json_num(self.p99_us),
            "max_us": _json_num(self.max_us),
            "n": self.n,
        }


@dataclass(frozen=True)
class MessageTiming:
    """Timing of one message over a run.

    ``count``: every frame of it; the statistics use its timed frames (``bits > 0``).
    ``time_source``: which time the periods use (``t_rx``, ``t_ready``, ``mixed``, ``none``).
    ``jitter_std_us`` / ``jitter_pp_us``: standard deviation / max - min of inter-arrival.
    ``latency``: ``t_rx - t_ready`` where both are known. ``cycle_violations_*``: None when
    not checked (no cycle time, or the window disabled). ``bound_us``: worst-case response
    time from :mod:`bench.operator.analysis.rta` (None for event-driven messages).
    """

    name: str
    can_id: int
    sender: str
    cycle_time_ms: float | None
    count: int
    time_source: str
    period_mean_ms: float
    jitter_std_us: float
    jitter_pp_us: float
    latency: Percentiles
    missed_cycles: int
    counter_gaps: int
    cycle_violations_abs: int | None
    cycle_violations_rel: int | None
    bound_us: float | None

    @property
    def above_bound(self) -> bool:
        """True when the measured maximum latency exceeds the worst-case bound."""
        return (
            self.bound_us is not None and self.latency.n > 0 and self.latency.max_us > self.bound_us
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        d = asdict(self)
        for k in ("period_mean_ms", "jitter_std_us", "jitter_pp_us", "bound_us"):
            d[k] = _json_num(d[k])
        d["latency"] = self.latency.to_dict()
        d["above_bound"] = self.above_bound
        return d


@dataclass(frozen=True)
class ChainTiming:
    """IMU sample -> command -> valve opening over the control cycles of a run.

    ``imu_to_command``: last command frame received minus the IMU sample's transmission;
    ``command_to_valve``: first valve opening minus the reception of the command frame
    that opened it (the valve's opening delay, longer under a valve fault); ``imu_to_valve``: the
    age of the IMU data when the first valve opens. Cycles where no valve fired have no
    valve samples (``cycles_without_valve``).
    """

    cycles: int
    imu_to_command: Percentiles
    command_to_valve: Percentiles
    imu_to_valve: Percentiles
    cycles_without_valve: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "cycles": self.cycles,
            "imu_to_command": self.imu_to_command.to_dict(),
            "command_to_valve": self.command_to_valve.to_dict(),
            "imu_to_valve": self.imu_to_valve.to_dict(),
            "cycles_without_valve": self.cycles_without_valve,
        }


@dataclass(frozen=True)
class LoadFigures:
    """Bus load of a set of frames: mean over the windows and the busiest window."""

    mean_pct: float
    peak_pct: float
    peak_window_start_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (nan -> None)."""
        return {k: _json_num(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class BusLoad:
    """Bus load per window: overall and per sending node (DBC sender; ``?`` if unknown)."""

    window_ms: float
    bitrate_bps: int
    n_windows: int
    total: LoadFigures
    per_node: Mapping[str, LoadFigures]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "window_ms": self.window_ms,
            "bitrate_bps": self.bitrate_bps,
            "n_windows": self.n_windows,
            "total": self.total.to_dict(),
            "per_node": {k: v.to_dict() for k, v in self.per_node.items()},
        }
