"""How both sides write their records: strict JSON, atomically, and one percentile summary.

* :func:`write_record`: a JSON object (``summary.json``, the flight software's statistics,
  a refusal) written to a temporary file beside ``path`` and renamed over it, so a reader
  never sees half a file and a crash leaves the previous version; NaN and infinities
  become ``null`` (strict JSON: every reader parses it).
* :func:`percentile_summary`: the median, the 99th percentile (linear interpolation between
  order statistics, Hyndman & Fan's method 7: numpy's default, to the bit), the maximum and
  the count of samples, each divided by a unit (e.g. 1000 for ns to µs) and optionally
  rounded: the form every latency and cycle-time figure of the records takes (``{"p50",
  "p99", "max", "n"}``; values None without samples). The samples are a sequence, or a
  :class:`Distribution`: integer samples kept as counts per value (rounded to a quantum),
  so that a run of any length keeps memory in the number of distinct values, not of
  samples, with the same figures as the whole list (``tests/dbc/test_records.py`` checks
  both against ``numpy.percentile``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

PERCENTILES = (50.0, 99.0)
TMP_SUFFIX = ".tmp"


def clean(x: Any) -> Any:
    """``x`` with every NaN and infinity replaced by None (recursively)."""
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    return x


def write_record(path: Path, data: dict[str, Any], indent: int = 2) -> None:
    """Write ``data`` to ``path`` as strict JSON, atomically (module docstring)."""
    tmp = path.with_suffix(path.suffix + TMP_SUFFIX)
    tmp.write_text(json.dumps(clean(data), indent=indent, allow_nan=False) + "\n",
                   encoding="utf-8")
    tmp.replace(path)


class Distribution:
    """Integer samples as counts per value, each rounded to the nearest multiple of
    ``quantum`` (1: exact); memory grows with the distinct values, not the samples."""

    def __init__(self, quantum: int = 1) -> None:
        if quantum < 1:
            raise ValueError(f"Distribution quantum = {quantum}: expected an integer >= 1")
        self.quantum = quantum
        self.counts: dict[int, int] = {}
        self.n = 0

    def add(self, value: int) -> None:
        """One sample."""
        q = self.quantum
        key = value if q == 1 else (value + q // 2) // q * q
        self.counts[key] = self.counts.get(key, 0) + 1
        self.n += 1

    def __len__(self) -> int:
        return self.n

    def order_statistics(self, ranks: Sequence[int]) -> list[int]:
        """The samples of the given 0-based ranks in ascending order (ranks sorted or not)."""
        wanted = sorted(set(ranks))
        found: dict[int, int] = {}
        seen, i = 0, 0
        for value in sorted(self.counts):
            seen += self.counts[value]
            while i < len(wanted) and wanted[i] < seen:
                found[wanted[i]] = value
                i += 1
        return [found[r] for r in ranks]


def _lerp(a: float, b: float, gamma: float) -> float:
    """numpy's linear interpolation between neighbours (exact at both ends)."""
    diff = b - a
    return b - diff * (1.0 - gamma) if gamma >= 0.5 else a + diff * gamma


def _neighbours(n: int, fraction: float) -> tuple[int, int, float]:
    """The ranks around quantile ``fraction`` of ``n`` samples and the weight between them
    (Hyndman & Fan method 7, computed as numpy does)."""
    virtual = (n - 1) * fraction
    if virtual >= n - 1:
        return n - 1, n - 1, virtual - math.floor(virtual)
    if virtual < 0:
        return 0, 0, virtual - math.floor(virtual)
    below = math.floor(virtual)
    return below, below + 1, virtual - below


def percentile_summary(samples: Sequence[float] | Distribution, unit: float = 1.0,
                       digits: int | None = None) -> dict[str, float | int | None]:
    r"""p50, p99 and max of ``samples`` in ``unit``\ s (each sample / ``unit``), rounded to
    ``digits`` if given, and the sample count (module docstring)."""
    n = len(samples)
    if n == 0:
        return {"p50": None, "p99": None, "max": None, "n": 0}
    picks = [_neighbours(n, q / 100.0) for q in PERCENTILES]
    ranks = [r for lo, hi, _ in picks for r in (lo, hi)] + [n - 1]
    if isinstance(samples, Distribution):
        stats = [float(v) for v in samples.order_statistics(ranks)]
    else:
        ordered = sorted(float(v) for v in samples)
        if any(v != v for v in ordered):  # NaN: every figure is NaN, as numpy's
            stats = [math.nan] * len(ranks)
        else:
            stats = [ordered[r] for r in ranks]
    a = [v / unit for v in stats]
    vals = [_lerp(a[0], a[1], picks[0][2]), _lerp(a[2], a[3], picks[1][2]), a[4]]
    if digits is not None:
        vals = [round(v, digits) for v in vals]
    return {"p50": vals[0], "p99": vals[1], "max": vals[2], "n": n}
