"""How both sides write their records: strict JSON, atomically, and one percentile summary.

* :func:`write_record`: a JSON object (``summary.json``, the flight software's statistics,
  a refusal) written to a temporary file beside ``path`` and renamed over it, so a reader
  never sees half a file and a crash leaves the previous version; NaN and infinities
  become ``null`` (strict JSON: every reader parses it).
* :func:`percentile_summary`: the median, the 99th percentile (numpy's linear
  interpolation), the maximum and the count of a list of samples, each divided by a unit
  (e.g. 1000 for ns to µs) and optionally rounded: the form every latency and cycle-time
  figure of the records takes (``{"p50", "p99", "max", "n"}``; values None without
  samples).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

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


def percentile_summary(samples: Sequence[float], unit: float = 1.0,
                       digits: int | None = None) -> dict[str, float | int | None]:
    r"""p50, p99 and max of ``samples`` in ``unit``\ s (each sample / ``unit``), rounded to
    ``digits`` if given, and the sample count."""
    if not samples:
        return {"p50": None, "p99": None, "max": None, "n": 0}
    a = np.asarray(samples, dtype=float) / unit
    p50, p99 = np.percentile(a, PERCENTILES)
    vals = [float(p50), float(p99), float(a.max())]
    if digits is not None:
        vals = [round(v, digits) for v in vals]
    return {"p50": vals[0], "p99": vals[1], "max": vals[2], "n": len(samples)}
