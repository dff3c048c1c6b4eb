"""Small versions of the resource and shared-machine benchmarks (slow): the scripts behind
issue 19's figures run and their verdicts hold on a few short runs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
BENCHMARKS = REPO / "benchmarks"
TIMEOUT_S = 900.0  # a hang guard
RSS_GROWTH_BUDGET_MB = 20.0  # issue 19: bench and flight software grow less than this
PEAK_BUDGET_MB = 300.0  # issue 19: no end-of-run peak above this
SHORT_S = 30.0
FROM_S = 5.0
EXIT_BAD_INPUT = 2
# issue 19: within 1 s; the interpreter's start-up (a second or two on a loaded 2-core CI
# machine) comes on top, so the test allows more than the benchmark's figure
SECOND_SENDER_LIMIT_S = 5.0

pytestmark = pytest.mark.slow


def _script(*args: str) -> dict[str, Any]:
    done = subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True, text=True,
                          timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout)
    assert isinstance(result, dict)
    return result


def test_run_resources_measures_each_process_and_the_folder() -> None:
    """A short run: RSS per process, growth within budget, peak within budget, folder figures."""
    r = _script(str(BENCHMARKS / "run_resources.py"), "--durations", str(SHORT_S), "--from-s",
                str(FROM_S))
    (run,) = r["runs"]
    assert run["exit_code"] in (0, 1)
    for role in ("bench", "flight_sw"):
        assert run["rss_mb"][role]["growth"] is not None, role
        assert run["rss_mb"][role]["growth"] < RSS_GROWTH_BUDGET_MB, role
    assert 0 < run["peak_rss_mb_any_process"] < PEAK_BUDGET_MB
    assert run["folder"]["kb_per_sim_s"] > 0
    assert "telemetry.csv.gz" in run["folder"]["kb_per_sim_s_by_file"]  # standard record


def test_sigterm_at_random_moments_leaves_valid_summaries_and_nothing_behind() -> None:
    """Two lockstep and two realtime runs stopped by SIGTERM: all valid, all clean."""
    r = _script(str(BENCHMARKS / "shared_machine.py"), "signals", "--runs", "2")
    assert r["runs"] == 4 and r["valid_and_clean"] == 4, r["per_run"]


def test_parallel_runs_without_bus_equal_the_run_alone() -> None:
    """Two quickstarts at once, no --bus: two channels, both pass, both equal the run alone."""
    r = _script(str(BENCHMARKS / "shared_machine.py"), "parallel", "--runs", "2")
    assert r["distinct_channels"] == 2 and r["all_equal_alone"] and r["all_passed"], r


def test_a_second_bench_on_a_named_bus_is_told_within_a_second() -> None:
    """Once: the second run is refused, the first names a second sender, both summaries say
    so, the first's console within SECOND_SENDER_LIMIT_S of the second's start."""
    r = _script(str(BENCHMARKS / "shared_machine.py"), "second", "--repeats", "1")
    (row,) = r["per_run"]
    assert row["second_exit_code"] == EXIT_BAD_INPUT and row["second_summary_ended"] == "refused"
    assert row["second_heard"] and row["first_summary_compromised"]
    assert row["first_console_after_s"] is not None
    assert row["first_console_after_s"] < SECOND_SENDER_LIMIT_S
