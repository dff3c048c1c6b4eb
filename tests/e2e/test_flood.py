"""100 000 malformed frames at full bus rate against both processes during a realtime run."""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
from pathlib import Path

import pytest

from tests.e2e.conftest import QUICKSTART, REPO, unique_bus

pytestmark = pytest.mark.slow

FLOOD_FRAMES = 100_000
FLOOD_RATE_HZ = 7400.0  # a 1 Mbit/s bus's capacity for 8-byte frames
RUN_S = "40"  # the flood takes 13.5 s at full rate; margin for a loaded machine
DEADLINE_S = 120.0


def test_flood_is_counted_by_cause_and_nothing_crashes(tmp_path: Path, runtime_dir: Path) -> None:
    """Every malformed frame is counted under its cause by its receiver; the run still converges."""
    bus = unique_bus()
    out = tmp_path / "run"
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    run = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bench.cli",
            "run",
            str(QUICKSTART),
            "--bus",
            bus,
            "--mode",
            "realtime",
            "--duration",
            RUN_S,
            "--out",
            str(out),
        ],
        cwd=REPO,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert run.stderr is not None
        sel = selectors.DefaultSelector()
        sel.register(run.stderr, selectors.EVENT_READ)
        while True:
            assert sel.select(timeout=DEADLINE_S), "no progress from the run"
            line = run.stderr.readline()
            assert line, "run ended early"
            if line.startswith("progress") and float(line.split()[1]) > 0.0:
                break
        flood = subprocess.run(
            [
                sys.executable,
                "-m",
                "bench.flood",
                "--bus",
                bus,
                "--frames",
                str(FLOOD_FRAMES),
                "--rate-hz",
                str(FLOOD_RATE_HZ),
            ],
            cwd=REPO,
            env=env,
            capture_output=True,
            text=True,
            timeout=DEADLINE_S,
            check=True,
        )
        run.communicate(timeout=DEADLINE_S)
    finally:
        if run.poll() is None:
            run.kill()
            run.communicate()
    sent = json.loads(flood.stdout)["sent"]
    s = json.loads((out / "summary.json").read_text())
    assert "error" not in s, s.get("error")
    assert s["fsw"]["exit_code"] == 0
    frames, other = s["frames"], s["rejected_other"]
    for side, own in (("BENCH", "FSW_ATT_EST"), ("FSW", "IMU_ACCEL")):
        assert other[side].get("unknown_id", 0) == sent["ALL"]["unknown_id"], side
        assert other[side].get("error_frame", 0) == sent["ALL"]["error_frame"], side
        for cause in ("crc", "dlc", "remote_frame"):
            assert frames[own]["rejected"].get(cause, 0) == sent[side][cause], (side, cause)
    assert s["fsw"]["exit_code"] == 0 and s["fsw"]["mode"] in ("NOMINAL", "BOOT", "SAFE")


LOCKSTEP_FLOOD_RATE_HZ = 3000.0  # below the bus capacity
LOCKSTEP_FLOOD_FRAMES = 6000


def test_flood_does_not_change_lockstep_control(tmp_path: Path, runtime_dir: Path) -> None:
    """In lockstep, garbage on the bus leaves the control result exactly as without it."""
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    results = []
    for flooded in (False, True):
        bus, out = unique_bus(), tmp_path / f"run{int(flooded)}"
        run = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "bench.cli",
                "run",
                str(QUICKSTART),
                "--bus",
                bus,
                "--out",
                str(out),
            ],
            cwd=REPO,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            assert run.stderr is not None
            line = run.stderr.readline()  # first progress line: the run is going
            assert line.startswith("progress"), line
            if flooded:
                subprocess.run(
                    [
                        sys.executable,
                        "-m",
                        "bench.flood",
                        "--bus",
                        bus,
                        "--frames",
                        str(LOCKSTEP_FLOOD_FRAMES),
                        "--rate-hz",
                        str(LOCKSTEP_FLOOD_RATE_HZ),
                    ],
                    cwd=REPO,
                    env=env,
                    capture_output=True,
                    timeout=DEADLINE_S,
                    check=True,
                )
            run.communicate(timeout=DEADLINE_S)
        finally:
            if run.poll() is None:
                run.kill()
                run.communicate()
        results.append(json.loads((out / "summary.json").read_text()))
    ref, got = results
    assert sum(got["rejected_other"]["FSW"].values()) > 0  # the flood did arrive
    for key in ("settling_time_s", "steady_state_attitude_error_deg", "propellant_kg"):
        assert got[key] == ref[key], key
