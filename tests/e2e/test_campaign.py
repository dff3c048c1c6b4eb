"""The 16-thruster single-failure campaign: every stuck-closed and stuck-open thruster, lockstep."""

from __future__ import annotations

import csv
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import REPO, RUN_TIMEOUT_S

pytestmark = pytest.mark.slow

SCENARIO = REPO / "scenarios" / "fdir_16thr.toml"
FAULT_T_S = 6.0  # during the slew (it starts at 5 s)
DETECT_MAX_S = {"stuck_closed": 2.0, "stuck_open": 1.0}  # the limits
N_THRUSTERS = 16
JOBS = 2


def test_every_single_thruster_failure_is_detected_isolated_and_survived(tmp_path: Path) -> None:
    """32 runs: detected in time, the right thruster and kind isolated, expectations met."""
    out = tmp_path / "campaign"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "bench.operator.entry",
            "campaign",
            str(SCENARIO),
            "--out",
            str(out),
            "--fault-time",
            str(FAULT_T_S),
            "--jobs",
            str(JOBS),
        ],
        cwd=REPO,
        env=dict(os.environ),
        capture_output=True,
        text=True,
        timeout=4 * RUN_TIMEOUT_S,
    )
    with open(out / "campaign.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * N_THRUSTERS
    for r in rows:
        case = (r["kind"], r["thruster"])
        assert r["detected"] == "True", case
        assert float(r["detection_time_s"]) <= DETECT_MAX_S[r["kind"]], case
        assert r["isolation_correct"] == "True", case
        assert r["expectations_met"] == "True", case
    assert (out / "campaign.png").stat().st_size > 0
    # campaign.html links each case's report.html, relative to the campaign folder
    links = re.findall(r"href='([^']+)'", (out / "campaign.html").read_text(encoding="utf-8"))
    assert len(links) == len(rows) and all((out / h).is_file() for h in links)
    assert p.returncode == 0, p.stdout[-2000:]
    # redirected (not a terminal): one line per run as it finished, numbered, then the verdict
    progress = [ln for ln in p.stdout.splitlines() if ln.startswith("[")]
    assert [ln.split("]")[0] for ln in progress] == [
        f"[{i}/{2 * N_THRUSTERS}" for i in range(1, 2 * N_THRUSTERS + 1)]
    assert p.stdout.splitlines()[-1].startswith(f"campaign: {2 * N_THRUSTERS}/{2 * N_THRUSTERS}")
