"""The flight software's statistics file (``--stats``): what it did, for the bench's summary.

In: the node's counters (cycles, overruns, restarts and refused restarts, frames sent per
message, cycle times [ns], allocation residuals [N m], [N]), the receive statistics of
its frame checker (dbc.codec.FrameChecker.summary), the flight computer's final state.
Out: one JSON object, written atomically (a reader never sees half a file), at the end
of a run and every ten status periods in realtime. The bench merges it into
``summary.json`` under ``fsw`` (see docs/icd.md for the fields).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

PERCENTILES = (50.0, 99.0)
US_PER_NS = 1e-3
EVIDENCE = ("unexpected", "sequence")  # receive causes that show a second sender


@dataclass
class NodeStats:
    """Counters the node reports at exit."""

    cycles: int = 0
    overruns: int = 0
    restarts: int = 0
    restarts_refused: int = 0
    sent: dict[str, int] = field(default_factory=dict)
    cycle_ns: list[int] = field(default_factory=list)  # cycle start -> last frame sent
    residual_Nm: list[float] = field(default_factory=list)  # allocation torque residual
    residual_N: list[float] = field(default_factory=list)  # allocation force residual
    saturated_cycles: int = 0


def spread(values: list[float]) -> dict[str, float | None]:
    """p50, p99 and max of ``values`` (full precision; the bus carries 0.05 steps)."""
    if not values:
        return {"p50": None, "p99": None, "max": None}
    p50, p99 = np.percentile(np.asarray(values, dtype=float), PERCENTILES)
    return {"p50": float(p50), "p99": float(p99), "max": float(max(values))}


def percentiles_us(samples_ns: list[int]) -> dict[str, float | int | None]:
    """p50, p99 and max of ``samples_ns`` in microseconds (0.1 us), and the count."""
    if not samples_ns:
        return {"p50": None, "p99": None, "max": None, "n": 0}
    a = np.asarray(samples_ns, dtype=float) * US_PER_NS
    p50, p99 = np.percentile(a, PERCENTILES)
    return {"p50": round(float(p50), 1), "p99": round(float(p99), 1),
            "max": round(float(a.max()), 1), "n": len(samples_ns)}


def second_sender_evidence(received: dict[str, dict[str, Any]]) -> dict[str, int]:
    """Per message, frames that show a second sender (our own messages heard, counter
    regressions) in a receive summary."""
    out = {}
    for name, r in received.items():
        n = sum(int(r["rejected"].get(c, 0)) for c in EVIDENCE)
        if n:
            out[name] = n
    return out


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file and a rename."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=2), encoding="utf-8")
    tmp.replace(path)
