"""The flight software's statistics file (``--stats``): what it did, for the bench's summary.

In: the node's counters (cycles, overruns, restarts and refused restarts, frames sent per
message, cycle times [ns], allocation residuals [N m], [N]), the receive statistics of
its frame checker (dbc.codec.FrameChecker.summary), the flight computer's final state.
Out: one JSON object, written atomically (a reader never sees half a file), at the end
of a run and every ten status periods in realtime (dbc.records.write_record). The bench
merges it into
``summary.json`` under ``fsw`` (see docs/icd.md for the fields).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from dbc.records import percentile_summary

NS_PER_US = 1e3
CYCLE_TIME_DIGITS = 1  # 0.1 us
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


def spread(values: list[float]) -> dict[str, float | int | None]:
    """p50, p99, max (full precision; the bus carries 0.05 steps) and the count."""
    return percentile_summary(values)


def percentiles_us(samples_ns: list[int]) -> dict[str, float | int | None]:
    """p50, p99 and max of ``samples_ns`` in microseconds (0.1 us), and the count."""
    return percentile_summary(samples_ns, NS_PER_US, CYCLE_TIME_DIGITS)


def second_sender_evidence(received: dict[str, dict[str, Any]]) -> dict[str, int]:
    """Per message, frames that show a second sender (our own messages heard, counter
    regressions) in a receive summary."""
    out = {}
    for name, r in received.items():
        n = sum(int(r["rejected"].get(c, 0)) for c in EVIDENCE)
        if n:
            out[name] = n
    return out
