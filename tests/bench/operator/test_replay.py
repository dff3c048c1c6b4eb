"""Replay: a recorded lockstep trace cut into cycles as the bench kept them."""

from __future__ import annotations

from pathlib import Path

import can
import pytest

from bench.operator.replay import split_cycles
from bench.wire.trace import TraceRecorder
from dbc.database import load_database
from dbc.errors import ConfigError

PERIOD_NS = 20_000_000


def _msg(db: object, name: str) -> can.Message:
    spec = db.get_message_by_name(name)  # type: ignore[attr-defined]
    return can.Message(arbitration_id=spec.frame_id, data=bytes(spec.length),
                       is_extended_id=False)


def test_frames_are_grouped_per_cycle_by_sender(tmp_path: Path) -> None:
    """Before SYNC(0): the bench's samples (the boot heartbeat is left out); then per SYNC,
    the flight software's answers and the bench's frames that followed, in trace order."""
    db = load_database()
    rec = TraceRecorder(tmp_path, 0.0)
    rec.frame(_msg(db, "FSW_STATUS"), 0, tx=False)  # boot heartbeat
    rec.frame(_msg(db, "IMU_RATE"), 0, tx=True)
    for k in range(2):
        t = k * PERIOD_NS
        rec.frame(_msg(db, "SYNC"), t, tx=True)
        rec.frame(_msg(db, "THR_CMD_0"), t + 2_000_000, tx=False)
        rec.frame(_msg(db, "FSW_STATUS"), t + 2_100_000, tx=False)
        rec.frame(_msg(db, "IMU_RATE"), t + 10_000_000, tx=True)
        rec.error_frame(t + 11_000_000)
    rec.close()
    before, cycles = split_cycles(tmp_path, db)
    names = {m.frame_id: m.name for m in db.messages}
    assert [names[m.arbitration_id] for m in before] == ["IMU_RATE"]
    assert len(cycles) == 2
    for c in cycles:
        assert [names[m.arbitration_id] for m in c.answers] == ["THR_CMD_0", "FSW_STATUS"]
        assert [names[m.arbitration_id] for m in c.after] == ["IMU_RATE"]


def test_a_trace_without_sync_is_refused(tmp_path: Path) -> None:
    """A realtime run (no SYNC): not replayable in steps; ConfigError naming SYNC."""
    db = load_database()
    rec = TraceRecorder(tmp_path, 0.0)
    rec.frame(_msg(db, "IMU_RATE"), 0, tx=True)
    rec.close()
    with pytest.raises(ConfigError, match="SYNC"):
        split_cycles(tmp_path, db)
