"""Warm starts, end to end: a run the campaign's zygote forks (supervisor, bench and flight
software all forked from imported modules) is the cold command's run, byte for byte."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import threading
import time
from pathlib import Path

import pytest

from bench.campaign.zygote import Zygote
from tests.e2e.conftest import QUICKSTART, run_cli, unique_bus
from tests.run_files import run_text

pytestmark = pytest.mark.slow

DURATION_S = "20"  # long enough to see its flight software running
WALL_CLOCK_KEYS = ("bus", "wall_time_s", "realtime_factor", "lockstep_wall_us", "fsw")
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
