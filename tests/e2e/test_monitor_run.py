"""The monitor against real traffic (slow: real processes): a recorded run's trace played
onto a bus with python-can's player; what the monitor counts is what the run recorded."""

from __future__ import annotations

import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import can
import pytest

from dbc.database import load_database
from tests.e2e.conftest import QUICKSTART, REPO, run_cli, unique_bus

pytestmark = pytest.mark.slow

SHORT_S = "4"
MONITOR_S = "8"  # long enough for the player at full speed
TIMEOUT_S = 120.0  # a hang guard


def test_monitor_counts_a_played_trace_as_the_run_summary(tmp_path: Path,
                                                          runtime_dir: Path) -> None:
    """Per message, the monitor's count of a played trace equals the frames the run's
    summary says the bench received or sent."""
    run = run_cli(["run", str(QUICKSTART), "--bus", unique_bus(), "--duration", SHORT_S,
                   "--no-plots"], tmp_path / "run", runtime_dir)
    assert run.returncode in (0, 1), run.stderr
    bus = unique_bus()
    channel = bus.split(":", 1)[1]
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir))
    mon = subprocess.Popen([sys.executable, "-m", "bench.operator.entry", "monitor", "--bus", bus,
                            "--duration", MONITOR_S], cwd=REPO, env=env, text=True,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert mon.stderr is not None
        assert "listening on" in mon.stderr.readline()  # the reader is on the bus
        subprocess.run([sys.executable, "-m", "can.player", "-i", "hilbus", "-c", channel,
                        "--ignore-timestamps", str(run.out / "trace.asc.gz")], cwd=REPO,
                       env=env, check=True, capture_output=True, timeout=TIMEOUT_S)
        out, err = mon.communicate(timeout=TIMEOUT_S)
    finally:
        mon.kill()
    assert mon.returncode == 0, err
    names = {m.frame_id: m.name for m in load_database().messages}
    recorded = Counter(names[m.arbitration_id] for m in can.LogReader(run.out / "trace.asc.gz")
                       if not m.is_error_frame and m.arbitration_id in names)
    shown = {}
    for line in out.splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 2 and cells[1] in recorded:
            shown[cells[1]] = int(cells[2])
    assert shown == dict(recorded)
    for name, n in recorded.items():
        row = run.summary["frames"][name]
        assert n == (row["received"] if name.startswith(("THR_CMD", "FSW_")) else row["sent"])


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
def test_run_monitor_shows_the_run_it_watches(mode: str, tmp_path: Path,
                                              runtime_dir: Path) -> None:
    """run --monitor (headless: no terminal), lockstep and realtime: the monitor's last
    picture comes before the verdict, counts every frame the bench sent as the summary does,
    and at least every frame of the flight software's that the bench received; watching
    drops nothing (realtime overruns a member that reads late)."""
    run = run_cli(["run", str(QUICKSTART), "--mode", mode, "--duration", SHORT_S,
                   "--no-plots", "--monitor"], tmp_path / "run", runtime_dir)
    assert run.returncode in (0, 1), run.stderr
    assert not [line for line in run.summary["abnormal"] if "dropped" in line]
    assert run.stdout.index("thrusters (C commanded") < run.stdout.index("verdict:")
    shown = {}
    for line in run.stdout.splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 2 and cells[1] in run.summary["frames"]:
            shown[cells[1]] = int(cells[2])
    assert shown, run.stdout
    for name, row in run.summary["frames"].items():
        if row["sender"] == "BENCH" and row["sent"]:
            assert shown.get(name) == row["sent"], name
        elif row["received"]:
            assert shown.get(name, 0) >= row["received"], name
