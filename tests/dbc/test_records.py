"""Percentile summaries equal numpy.percentile (the reference) to the bit, for lists and for
Distribution counts; atomic strict-JSON records."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from dbc.records import PERCENTILES, Distribution, percentile_summary, write_record

N_RANDOM = 60
NS_PER_US = 1e3


def _numpy(samples: list[float], unit: float = 1.0) -> list[float]:
    a = np.asarray(samples, dtype=float) / unit
    p50, p99 = np.percentile(a, PERCENTILES)
    return [float(p50), float(p99), float(a.max())]


@pytest.mark.parametrize("seed", range(N_RANDOM))
def test_list_percentiles_equal_numpy(seed: int) -> None:
    """Random lengths (1 to 5000) and values, floats and ints: p50, p99, max as numpy's."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 5000))
    ints = rng.integers(0, 10_000_000, n).tolist()
    floats = rng.normal(0.0, 3.0, n).tolist()
    for samples, unit in ((ints, NS_PER_US), (floats, 1.0)):
        s = percentile_summary(samples, unit)
        assert [s["p50"], s["p99"], s["max"]] == _numpy(samples, unit)
        assert s["n"] == n


@pytest.mark.parametrize("seed", range(N_RANDOM))
def test_distribution_equals_the_whole_list(seed: int) -> None:
    """Counts per value give the figures of the whole list (repeats and all)."""
    rng = np.random.default_rng(1000 + seed)
    n = int(rng.integers(1, 20_000))
    samples = rng.integers(1_500_000, 1_500_000 + int(rng.integers(1, 3000)), n).tolist()
    d = Distribution()
    for v in samples:
        d.add(v)
    got = percentile_summary(d, NS_PER_US, 3)
    want = percentile_summary(samples, NS_PER_US, 3)
    assert got == want
    assert [got["p50"], got["p99"], got["max"]] == [round(x, 3) for x in _numpy(samples,
                                                                                 NS_PER_US)]
    assert len(d.counts) <= len(set(samples))


def test_quantum_rounds_to_the_nearest_multiple() -> None:
    """A 1000-quantum keeps 1499 -> 1000, 1500 -> 2000; the figures are of rounded values."""
    d = Distribution(1000)
    for v in (1499, 1500, 2600, 999_999):
        d.add(v)
    assert d.counts == {1000: 1, 2000: 1, 3000: 1, 1_000_000: 1}
    assert percentile_summary(d)["max"] == 1_000_000.0
    with pytest.raises(ValueError, match="quantum = 0"):
        Distribution(0)


def test_empty_and_nan_samples() -> None:
    """No sample: None figures; a NaN among them: NaN figures, as numpy gives."""
    assert percentile_summary([]) == {"p50": None, "p99": None, "max": None, "n": 0}
    assert percentile_summary(Distribution())["n"] == 0
    s = percentile_summary([1.0, math.nan, 3.0])
    assert all(math.isnan(s[k]) for k in ("p50", "p99", "max"))  # type: ignore[arg-type]


def test_known_answer() -> None:
    """1..100: p50 50.5, p99 99.01, max 100 (method 7)."""
    s = percentile_summary(list(range(1, 101)))
    assert (s["p50"], s["max"]) == (50.5, 100.0)
    assert s["p99"] == pytest.approx(99.01, abs=1e-12)


def test_record_is_strict_json_written_whole(tmp_path: Path) -> None:
    """NaN and infinity become null; no temporary file is left."""
    path = tmp_path / "r.json"
    write_record(path, {"a": math.nan, "b": [math.inf, 1.5]})
    assert json.loads(path.read_text(encoding="utf-8")) == {"a": None, "b": [None, 1.5]}
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]
