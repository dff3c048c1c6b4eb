"""A small version of the lockstep speed benchmark (slow): issue 23's figures are produced,
one run of the quickstart, and they are consistent with each other."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "benchmarks" / "lockstep_speed.py"
TIMEOUT_S = 600.0  # a hang guard

pytestmark = pytest.mark.slow


def test_lockstep_speed_reports_the_factor_the_cycle_split_and_the_command() -> None:
    """RTF, cycle split (wait within the cycle), command overhead and its parts, as JSON."""
    done = subprocess.run([sys.executable, str(SCRIPT), "--runs", "1", "--scenarios",
                           "quickstart"], cwd=REPO, capture_output=True, text=True,
                          timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    r = json.loads(done.stdout)
    q = r["scenarios"]["quickstart"]
    assert q["runs"] == 1 and q["passed"] == [True]
    assert q["realtime_factor_median"] > 1.0
    assert 0.0 < q["waiting_for_fsw_us"]["p50"] <= q["cycle_wall_us"]["p50"]
    assert q["bench_own_us_p50"] > 0.0 and q["fsw_cycle_us"]["p50"] > 0.0
    assert set(q["split_us_p50"]) == {"before_sync", "meanwhile", "waiting_for_fsw",
                                      "after_commands"}
    assert all(v > 0.0 for v in q["split_us_p50"].values())
    assert r["bytecode"] == "cached"
    c = r["command"]
    for key in ("plots", "no_plots", "plots_prestart_off"):
        assert c[key]["command_s_median"] > c[key]["loop_s_median"] > 0.0, key
    parts = c["parts_alone_s"]
    assert parts["command_start"] > 0.0 and parts["fsw_start_up"] > 0.0
    assert math.isfinite(parts["plots"]) and math.isfinite(c["prestart_gain_s"])


def test_unknown_scenario_is_refused_by_name() -> None:
    """--scenarios with a name that has no file: exit 2 naming it."""
    done = subprocess.run([sys.executable, str(SCRIPT), "--scenarios", "nope"], cwd=REPO,
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 2 and "scenarios/nope.toml" in done.stderr


def test_baseline_runs_take_turns_and_give_paired_ratios() -> None:
    """--baseline: the other install's figures and the paired ratios per scenario (here the
    same install against itself: each ratio a positive finite number)."""
    done = subprocess.run([sys.executable, str(SCRIPT), "--runs", "1", "--scenarios",
                           "quickstart", "--no-command", "--baseline", sys.executable],
                          cwd=REPO, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr[-3000:]
    r = json.loads(done.stdout)
    b = r["baseline"]
    assert b["python"] == sys.executable and b["scenarios"]["quickstart"]["runs"] == 1
    ratios = b["ratios"]["quickstart"]
    assert set(ratios) == {"realtime_factor", "fsw_cycle_p50", "fsw_cycle_p99"}
    assert all(math.isfinite(v) and v > 0.0 for v in ratios.values())
    assert "command" not in r


def test_a_baseline_without_the_project_is_refused_by_name(tmp_path: Path) -> None:
    """--baseline naming an interpreter that cannot import thruster-hil: exit 2, named."""
    venv = tmp_path / "bare"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True,
                   timeout=TIMEOUT_S)
    bare = str(venv / "bin" / "python")
    done = subprocess.run([sys.executable, str(SCRIPT), "--scenarios", "quickstart",
                           "--baseline", bare], cwd=REPO, capture_output=True, text=True,
                          timeout=TIMEOUT_S)
    assert done.returncode == 2
    assert f"--baseline {bare}" in done.stderr and "no thruster-hil installed" in done.stderr
