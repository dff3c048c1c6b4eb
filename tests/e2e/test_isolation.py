"""Runs on a shared machine: without --bus each run has a channel of its own, so parallel runs
equal runs alone; a second bench on a named bus is refused and both runs say so."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bench.operator.cli import EXIT_BAD_INPUT
from tests.e2e.conftest import QUICKSTART, REPO, RUN_TIMEOUT_S, running, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

PARALLEL_RUNS = 4
DURATION = "6"
START_PERCENT = 5.0


def _start(out: Path, runtime_dir: Path, extra: list[str]) -> subprocess.Popen[str]:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    return subprocess.Popen(
        [sys.executable, "-m", "bench.operator.entry", "run", str(QUICKSTART), "--duration",
         DURATION, "--seed", "3", "--out", str(out), *extra],
        cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_parallel_runs_without_bus_equal_a_run_alone(tmp_path: Path, runtime_dir: Path) -> None:
    """Several runs at once, no --bus: each names its own channel, and every one's telemetry
    equals the same run alone."""
    alone = _start(tmp_path / "alone", runtime_dir, [])
    alone.communicate(timeout=RUN_TIMEOUT_S)
    assert alone.returncode in (0, 1)  # a short run: its expectations may fail
    procs = [_start(tmp_path / f"p{i}", runtime_dir, []) for i in range(PARALLEL_RUNS)]
    channels = set()
    for p in procs:
        _, err = p.communicate(timeout=RUN_TIMEOUT_S)
        assert p.returncode == alone.returncode, err
        line = next(ln for ln in err.splitlines() if ln.startswith("thruster-hil: bus hilbus:"))
        channels.add(line.split()[2])
    assert len(channels) == PARALLEL_RUNS  # a channel each
    ref = run_text(tmp_path / "alone", "telemetry.csv").encode()
    for i in range(PARALLEL_RUNS):
        assert run_text(tmp_path / f"p{i}", "telemetry.csv").encode() == ref, i


def test_second_bench_on_a_named_bus_is_refused_and_reported_by_both(
    tmp_path: Path, runtime_dir: Path
) -> None:
    """A second run on the bus of a running one: refused (exit 2, naming what it heard);
    the running one reports a second sender on its console and in its summary."""
    bus = unique_bus()
    first = ["run", str(QUICKSTART), "--bus", bus, "--mode", "realtime", "--duration", "8"]
    with running(first, tmp_path / "first", runtime_dir, START_PERCENT) as p1:
        p2 = _start(tmp_path / "second", runtime_dir, ["--bus", bus])
        _, err2 = p2.communicate(timeout=RUN_TIMEOUT_S)
        _, err1 = p1.communicate(timeout=RUN_TIMEOUT_S)
    assert p2.returncode == EXIT_BAD_INPUT, err2
    assert "--bus" in err2 and "heard" in err2
    s2 = json.loads((tmp_path / "second" / "summary.json").read_text(encoding="utf-8"))
    assert s2["ended"] == "refused" and s2["verdict"].startswith("REFUSED")
    assert s2["second_sender_heard"] and "heard" in s2["abnormal"][0]
    s1 = json.loads((tmp_path / "first" / "summary.json").read_text(encoding="utf-8"))
    assert s1["compromised"] is not None and "BENCH_STATUS" in s1["compromised"]["messages"]
    assert "second sender" in err1
