"""A small version of the campaign benchmark (slow): a real Dask scheduler and two workers
started with Dask's own commands give the local results; three reruns are identical; a
killed worker loses nothing and doubles nothing; both margin searches bracket a boundary."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "benchmarks" / "campaign_scale.py"
TIMEOUT_S = 1200.0  # a hang guard

pytestmark = pytest.mark.slow


def test_campaign_scale_small() -> None:
    """Every section of benchmarks/campaign_scale.py, small: its invariants hold."""
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--single-runs", "1", "--mc-cases", "4",
         "--three-way-cases", "4", "--duration", "10", "--margin-tolerance", "0.004", "0.2"],
        cwd=REPO, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    r = json.loads(done.stdout)
    assert all("error" not in v for v in r.values()), r
    t = r["throughput"]
    assert t["cases"] == 4 and t["errors"] == 0 and t["ratio"] > 0.0
    w = r["three_ways"]
    assert w["scheduler_identical"] and w["differing_cases"] == []
    assert list(w["reruns_identical"].values()) == [True, True, True]
    lost = r["lost_worker"]
    assert lost["killed_after_cases"] is not None, lost
    assert (lost["exit"], lost["cases"], lost["duplicates"], lost["errors"]) == (0, 4, 0, 0)
    assert lost["attempt_folders_left"] == [] and lost["identical_to_local"]
    for key, m in r["margins"].items():  # a bracketed boundary, or a lower bound on it
        lo, hi = sorted((m["nominal"], m["toward"]))
        if m["boundary"] is None:
            assert m["runs"] == 2 and "still passes" in m["note"], (key, m)
        else:
            assert m["runs"] >= 3 and m["uncertainty"] > 0.0 and lo < m["boundary"] < hi
