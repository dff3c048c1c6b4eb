"""Run metrics: latency percentiles and the expectation rows of summary.json.

Pure functions. Inputs: latency samples [ns]; a figure of merit, its limit and a note.
Convergence, settling and steady-state errors are computed as the telemetry streams in
(bench.results.error_stats).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from dbc.records import Distribution, percentile_summary

NS_PER_US = 1e3
LATENCY_DIGITS = 3  # 1 ns in microseconds


def latency_summary(samples_ns: Sequence[int] | Distribution) -> dict[str, Any]:
    """p50, p99, max in microseconds (1 ns resolution) and the sample count."""
    return percentile_summary(samples_ns, NS_PER_US, LATENCY_DIGITS)


def expectation(
    name: str, value: float | None, limit: float | None, note: str | None = None
) -> dict[str, Any] | None:
    """One expectation row: value, limit, pass (value <= limit), optional note; None if no limit."""
    if limit is None:
        return None
    ok = value is not None and bool(np.isfinite(value)) and value <= limit
    row: dict[str, Any] = {"name": name, "value": value, "max": limit, "pass": ok}
    if note is not None:
        row["note"] = note
    return row


def settling_expectation(
    name: str, value: float | None, limit: float | None, band: float | None, unit: str
) -> dict[str, Any] | None:
    """A settling-time row; a settling time of 0 is noted as never having left the band.

    That pass says nothing about convergence from an offset (e.g. a tracking run that
    starts on its reference): the note makes it visible in summary.json and on the console.
    """
    note = f"never outside the {band:g} {unit} band" if value == 0.0 and band else None
    return expectation(name, value, limit, note)
