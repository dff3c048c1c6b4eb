"""Analysis of run folders and live buses: timing (periods, jitter, latency, load, bounds).

:mod:`bench.operator.analysis.timing` holds :class:`RunTiming` (the timing of one run),
:mod:`bench.operator.analysis.tables` reads a run folder's timing files into arrays,
:mod:`bench.operator.analysis.measures` holds the pure measurements,
:mod:`bench.operator.analysis.records` the options and result records,
:mod:`bench.operator.analysis.live` listens to a running bus,
:mod:`bench.operator.analysis.report` prints
tables and draws histograms, :mod:`bench.operator.analysis.defaults` the default settings.
``thruster-hil timing`` and the pytest plugin (:mod:`bench.operator.pytest_plugin`) use them.
The names below are imported lazily, so ``bench.operator.analysis.defaults`` stays light.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "BusLoad": "records",
    "ChainTiming": "records",
    "LoadFigures": "records",
    "MessageTiming": "records",
    "Percentiles": "records",
    "RunTiming": "timing",
    "TimingOptions": "records",
}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
