"""Warm starts, end to end: a run the campaign's zygote forks (supervisor, bench and flight
software all forked from imported modules), and a command whose flight software starts in
its prestart (bench.operator.fsw_prestart), are the cold command's run, byte for byte."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

from bench.campaign.zygote import Zygote
from bench.operator.fsw_prestart import PRESTART_ENV
from tests.e2e.conftest import QUICKSTART, processes_with, run_cli, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

DURATION_S = "20"  # long enough to see its flight software running
WALL_CLOCK_KEYS = ("bus", "wall_time_s", "realtime_factor", "lockstep_wall_us", "fsw")
# the flight software's own figures that differ between two runs of one scenario: its
# clock's cycle times, how it started, the pid its overrun drops are keyed by
FSW_RUN_KEYS = ("cycle_time_us", "start", "bus_overrun_drops_by_pid")
TIMEOUT_S = 120.0
VERDICT_EXITS = (0, 1)  # passed, failed: the run completed
POLL_S = 0.01


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_warm_run_equals_the_cold_command(tmp_path: Path, runtime_dir: Path) -> None:
    """The same quickstart run cold (the command) and warm (zygote, its flight software seen
    forked from it): the same exit code, the same
    trace (ASC records and BLF bytes), telemetry and summary figures; the flight software
    ran and wrote its statistics in both."""
    args = ["run", str(QUICKSTART), "--duration", DURATION_S, "--no-plots", "--seed", "3"]
    cold = run_cli([*args, "--bus", unique_bus()], tmp_path / "cold", runtime_dir)
    assert cold.returncode in VERDICT_EXITS, cold.stderr
    warm_out = tmp_path / "warm"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    result: dict[str, int] = {}
    with Zygote() as z:
        t = threading.Thread(target=lambda: result.setdefault("code", z.run(
            [*args, "--bus", unique_bus(), "--out", str(warm_out)], env,
            tmp_path / "warm.err", TIMEOUT_S)))
        t.start()
        # warm indeed: the flight software is a fork of the zygote, not `python -m flight_sw`
        cmdline = b""
        while not cmdline and t.is_alive():
            time.sleep(POLL_S)  # the run's flight software, seen from outside while it runs
            with contextlib.suppress(OSError, ValueError):  # not started yet, or ended
                pid = int((warm_out / "fsw.pid").read_text())
                cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
        t.join(TIMEOUT_S)
        assert b"bench.campaign.zygote" in cmdline, cmdline
    assert result.get("code") == cold.returncode, (tmp_path / "warm.err").read_text()
    assert _digest(warm_out / "trace.blf") == _digest(cold.out / "trace.blf")
    for name in ("trace.asc", "telemetry.csv", "frames.csv", "valve_pulses.csv"):
        cold_text, warm_text = run_text(cold.out, name), run_text(warm_out, name)
        if name == "trace.asc":  # its first lines carry the wall-clock date
            cold_text, warm_text = (t.split("Start of measurement", 1)[1]
                                    for t in (cold_text, warm_text))
        assert warm_text == cold_text, name
    s_warm = json.loads((warm_out / "summary.json").read_text(encoding="utf-8"))
    s_cold = cold.summary
    assert {k: v for k, v in s_warm.items() if k not in WALL_CLOCK_KEYS} == {
        k: v for k, v in s_cold.items() if k not in WALL_CLOCK_KEYS}
    for s in (s_warm, s_cold):
        assert s["fsw"]["exit_code"] == 0 and s["fsw"]["sent"], s["fsw"]
    assert (s_warm["fsw"]["start"], s_cold["fsw"]["start"]) == ("forked", "prestart")


def test_a_prestarted_run_equals_the_cold_command(tmp_path: Path, runtime_dir: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """The console script's run with its flight software in the prestart, and with the
    prestart turned off (THRUSTER_HIL_PRESTART=0): the same exit code, trace, telemetry
    and summary figures; summary.json says how each flight software started."""
    args = ["run", str(QUICKSTART), "--duration", DURATION_S, "--no-plots", "--seed", "3"]
    pre = run_cli([*args, "--bus", unique_bus()], tmp_path / "pre", runtime_dir)
    monkeypatch.setenv(PRESTART_ENV, "0")
    cold = run_cli([*args, "--bus", unique_bus()], tmp_path / "cold", runtime_dir)
    assert pre.returncode == cold.returncode and pre.returncode in VERDICT_EXITS, pre.stderr
    assert _digest(pre.out / "trace.blf") == _digest(cold.out / "trace.blf")
    for name in ("telemetry.csv", "frames.csv", "valve_pulses.csv"):
        assert run_text(pre.out, name) == run_text(cold.out, name), name
    assert {k: v for k, v in pre.summary.items() if k not in WALL_CLOCK_KEYS} == {
        k: v for k, v in cold.summary.items() if k not in WALL_CLOCK_KEYS}
    assert (pre.summary["fsw"]["start"], cold.summary["fsw"]["start"]) == ("prestart",
                                                                           "command")
    assert {k: v for k, v in pre.summary["fsw"].items() if k not in FSW_RUN_KEYS} == {
        k: v for k, v in cold.summary["fsw"].items() if k not in FSW_RUN_KEYS}
    for s in (pre.summary, cold.summary):
        assert s["fsw"]["exit_code"] == 0 and s["fsw"]["sent"], s["fsw"]


def test_a_refused_run_leaves_no_prestart_behind(tmp_path: Path, runtime_dir: Path) -> None:
    """A run refused before its bench (a bad --duration) exits 2 at once: its prestart,
    maybe still importing, ended with it (no process of the command is left)."""
    mark = f"THIL_TEST_MARK_{uuid.uuid4().hex}"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir), THIL_TEST_MARK=mark)
    done = subprocess.run([sys.executable, "-m", "bench.operator.entry", "run",
                           str(QUICKSTART), "--duration", "-1", "--bus", unique_bus(),
                           "--out", str(tmp_path / "out")], env=env, capture_output=True,
                          text=True, timeout=TIMEOUT_S)
    assert done.returncode == 2 and "--duration" in done.stderr, done.stderr
    assert processes_with(mark) == []
