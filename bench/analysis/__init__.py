"""Analysis of run folders and live buses: timing (periods, jitter, latency, load, bounds).

:mod:`bench.analysis.timing` holds the measurements (pure functions and :class:`RunTiming`),
:mod:`bench.analysis.live` listens to a running bus, :mod:`bench.analysis.report` prints
tables and draws histograms. ``thruster-hil timing`` and the pytest plugin use them.
"""

from __future__ import annotations

from bench.analysis.timing import (
    BusLoad,
    ChainTiming,
    LoadFigures,
    MessageTiming,
    Percentiles,
    RunTiming,
    TimingOptions,
)

__all__ = [
    "BusLoad",
    "ChainTiming",
    "LoadFigures",
    "MessageTiming",
    "Percentiles",
    "RunTiming",
    "TimingOptions",
]
