"""100 000 malformed frames at full bus rate against both processes during a realtime run."""

from __future__ import annotations

import json
from pathlib import Path

import can
import pytest

from bench.results.record import run_file
from dbc.database import load_database
from tests.e2e.conftest import QUICKSTART, flood, running, unique_bus

pytestmark = pytest.mark.slow

FLOOD_FRAMES = 100_000
FLOOD_RATE_HZ = 7400.0  # a 1 Mbit/s bus's capacity for 8-byte frames
RUN_S = "40"  # the flood takes 13.5 s at full rate; margin for a loaded machine
LOCKSTEP_FLOOD_RATE_HZ = 3000.0  # below the bus capacity
LOCKSTEP_FLOOD_FRAMES = 6000


def test_flood_is_counted_by_cause_and_nothing_crashes(tmp_path: Path, runtime_dir: Path) -> None:
    """Every malformed frame is counted under its cause by its receiver, and is in the bench's
    CAN trace (as a logger records what it hears); nothing crashes."""
    bus, out = unique_bus(), tmp_path / "run"
    args = ["run", str(QUICKSTART), "--bus", bus, "--mode", "realtime", "--duration", RUN_S]
    with running(args, out, runtime_dir):
        sent = flood(bus, runtime_dir, FLOOD_FRAMES, FLOOD_RATE_HZ)["sent"]
    s = json.loads((out / "summary.json").read_text())
    assert "error" not in s, s.get("error")
    assert s["fsw"]["exit_code"] == 0
    frames, other = s["frames"], s["rejected_other"]
    for side, own in (("BENCH", "FSW_ATT_EST"), ("FSW", "IMU_ACCEL")):
        assert other[side].get("unknown_id", 0) == sent["ALL"]["unknown_id"], side
        assert other[side].get("error_frame", 0) == sent["ALL"]["error_frame"], side
        for cause in ("crc", "dlc", "remote_frame"):
            assert frames[own]["rejected"].get(cause, 0) == sent[side][cause], (side, cause)
    known = {m.frame_id for m in load_database().messages}
    heard = list(can.LogReader(str(run_file(out, "trace.asc"))))
    assert sum(m.is_error_frame for m in heard) == sent["ALL"]["error_frame"]
    unknown = sum(not m.is_error_frame and m.arbitration_id not in known for m in heard)
    assert unknown == sent["ALL"]["unknown_id"]


def test_flood_does_not_change_lockstep_control(tmp_path: Path, runtime_dir: Path) -> None:
    """In lockstep, garbage on the bus leaves the control result exactly as without it."""
    results = []
    for flooded in (False, True):
        bus, out = unique_bus(), tmp_path / f"run{int(flooded)}"
        with running(["run", str(QUICKSTART), "--bus", bus], out, runtime_dir):
            if flooded:
                flood(bus, runtime_dir, LOCKSTEP_FLOOD_FRAMES, LOCKSTEP_FLOOD_RATE_HZ)
        results.append(json.loads((out / "summary.json").read_text()))
    ref, got = results
    assert sum(got["rejected_other"]["FSW"].values()) > 0  # the flood did arrive
    for key in ("settling_time_s", "steady_state_attitude_error_deg", "propellant_kg"):
        assert got[key] == ref[key], key
