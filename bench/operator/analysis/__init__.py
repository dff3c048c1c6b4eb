"""Analysis of run folders and live buses: timing (periods, jitter, latency, load, bounds).

:mod:`bench.operator.analysis.timing` holds the measurements (pure functions and
:class:`RunTiming`), :mod:`bench.operator.analysis.live` listens to a running bus,
:mod:`bench.operator.analysis.report` prints
tables and draws histograms, :mod:`bench.operator.analysis.defaults` the default settings.
``thruster-hil timing`` and the pytest plugin (:mod:`bench.operator.pytest_plugin`) use them.
The names below are imported lazily, so ``bench.operator.analysis.defaults`` stays light.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = [
    "BusLoad",
    "ChainTiming",
    "LoadFigures",
    "MessageTiming",
    "Percentiles",
    "RunTiming",
    "TimingOptions",
]


def __getattr__(name: str) -> Any:
    if name in __all__:
        return getattr(importlib.import_module("bench.operator.analysis.timing"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
