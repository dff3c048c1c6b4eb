"""The CAN trace: dated when the run started, frame times in run time, readable by python-can."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

import can

from bench.recorder import TraceRecorder

START_WALL_S = 1_780_000_000.25  # a wall-clock instant in 2026
T_FRAME_NS = 500_000_000
FRAME_ID = 0x123


def test_trigger_block_is_dated_at_the_run_start_and_frames_keep_run_time(tmp_path: Path) -> None:
    """Begin Triggerblock carries START_WALL_S's date (not 1970); the frame reads back at 0.5 s."""
    rec = TraceRecorder(tmp_path, START_WALL_S)
    rec.frame(can.Message(arbitration_id=FRAME_ID, data=b"\x01\x02", is_extended_id=False),
              T_FRAME_NS, tx=True)
    rec.close()
    text = (tmp_path / "trace.asc").read_text()
    (block,) = [ln for ln in text.splitlines() if ln.startswith("Begin Triggerblock")]
    start = datetime.fromtimestamp(START_WALL_S)
    assert start.strftime("%b %d") in block and block.endswith(str(start.year))
    assert "1970" not in block
    (msg,) = list(can.LogReader(tmp_path / "trace.asc"))
    assert msg.arbitration_id == FRAME_ID and msg.timestamp == T_FRAME_NS / 1e9
