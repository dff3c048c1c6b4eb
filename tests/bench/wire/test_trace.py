"""The CAN trace: dated when the run started, frame times in run time, readable by python-can;
deferred writing (lockstep) gives the same files."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

import can

from bench.results.record import RECORD_STANDARD
from bench.results.writers import TelemetryWriter
from bench.wire.trace import BLF_NAME, TraceRecorder

START_WALL_S = 1_780_000_000.25  # a wall-clock instant in 2026
T_FRAME_NS = 500_000_000
FRAME_ID = 0x123
ASC_RESOLUTION_S = 1e-6  # the ASC trace's timestamps have 6 decimals


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


def _record_a_run(run_dir: Path, deferred: bool) -> TraceRecorder:
    """The same calls a bench makes (frames both ways, an error frame, events, telemetry)."""
    run_dir.mkdir()
    rec = TraceRecorder(run_dir, START_WALL_S, deferred)
    tel = TelemetryWriter(run_dir / "telemetry.csv", ["t_s", "x"], deferred)
    for k in range(3):
        t_ns = k * T_FRAME_NS
        rec.frame(can.Message(arbitration_id=FRAME_ID, data=bytes([k, 2]), is_extended_id=False),
                  t_ns, tx=True, t_ready_ns=t_ns - 1000, t_start_ns=t_ns - 500, bits=60)
        rec.event(t_ns + 1, "valve_watchdog", action="all valves closed")  # also in the trace
        rec.error_frame(t_ns + 2)
        rec.frame(can.Message(arbitration_id=FRAME_ID + 1, data=b"\x07", is_extended_id=False),
                  t_ns + 3, tx=False, bits=50)
        tel.row([t_ns / 1e9, 0.1 * k])
        if k == 1:
            rec.flush()
            tel.flush()
    rec.close()
    tel.close()
    return rec


def test_deferred_writing_gives_the_same_files(tmp_path: Path) -> None:
    """Deferred writing (lockstep) writes exactly what immediate writing does, in trace order."""
    now = _record_a_run(tmp_path / "now", deferred=False)
    later = _record_a_run(tmp_path / "later", deferred=True)
    assert now.frames_written == later.frames_written == 9
    for name in ("trace.asc", "frames.csv", "events.jsonl", "telemetry.csv"):
        now_text, later_text = ((tmp_path / d / name).read_text().splitlines()
                                for d in ("now", "later"))
        if name == "trace.asc":  # python-can dates the file when it opens it (metadata)
            now_text, later_text = now_text[1:], later_text[1:]
            assert now_text[0].startswith("base hex")
        assert now_text == later_text, name
    assert len(list(can.LogReader(tmp_path / "later" / "trace.asc"))) == 9


def test_deferred_rows_wait_for_write_pending_and_events_do_not(tmp_path: Path) -> None:
    """Deferred: frames and rows reach the files at write_pending; events.jsonl at once."""
    rec = TraceRecorder(tmp_path, START_WALL_S, deferred=True)
    rec.frame(can.Message(arbitration_id=FRAME_ID, data=b"\x01", is_extended_id=False),
              T_FRAME_NS, tx=True)
    rec.event(T_FRAME_NS, "fault_injected", kind="stuck_open")
    rec._writer.file.flush()
    assert "fault_injected" in (tmp_path / "events.jsonl").read_text()
    assert list(can.LogReader(tmp_path / "trace.asc")) == []
    rec.flush()
    assert len(list(can.LogReader(tmp_path / "trace.asc"))) == 1
    rec.close()


def test_blf_holds_the_frames_of_the_asc_trace(tmp_path: Path) -> None:
    """--record full: trace.blf reads back with python-can as the ASC trace's frames (ID,
    data, direction, error frames; times to the ASC's microsecond, exact in the BLF), and
    deferred writing gives the same BLF bytes (no wall clock in it)."""
    rec = _record_a_run(tmp_path / "now", deferred=False)
    _record_a_run(tmp_path / "later", deferred=True)
    asc = list(can.LogReader(tmp_path / "now" / "trace.asc"))
    blf = list(can.LogReader(tmp_path / "now" / BLF_NAME))
    assert len(blf) == len(asc) == rec.frames_written
    for a, b in zip(asc, blf, strict=True):
        assert (a.arbitration_id, bytes(a.data), a.is_rx, a.is_error_frame) == (
            b.arbitration_id, bytes(b.data), b.is_rx, b.is_error_frame)
        assert abs(a.timestamp - b.timestamp) <= ASC_RESOLUTION_S
    assert [round(m.timestamp * 1e9) for m in blf if not m.is_error_frame][:2] == [0, 3]
    assert (tmp_path / "now" / BLF_NAME).read_bytes() == (tmp_path / "later" / BLF_NAME
                                                          ).read_bytes()


def test_standard_record_writes_blf_beside_the_compressed_asc(tmp_path: Path) -> None:
    """The default level writes trace.asc.gz and trace.blf, and they hold the same frames."""
    rec = TraceRecorder(tmp_path, START_WALL_S, record=RECORD_STANDARD)
    rec.frame(can.Message(arbitration_id=FRAME_ID, data=b"\x01", is_extended_id=False),
              T_FRAME_NS, tx=True)
    rec.close()
    asc = list(can.LogReader(tmp_path / "trace.asc.gz"))
    blf = list(can.LogReader(tmp_path / BLF_NAME))
    assert not (tmp_path / "trace.asc").exists()
    assert [(m.arbitration_id, bytes(m.data)) for m in asc] == [(FRAME_ID, b"\x01")]
    assert [(m.arbitration_id, bytes(m.data)) for m in blf] == [(FRAME_ID, b"\x01")]
