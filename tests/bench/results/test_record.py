"""Record levels: compressed run-folder files round-trip, are deterministic, and a writer
that dies leaves every flushed line readable; readers find either form by its plain name."""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path
from typing import TextIO

import can
import pytest

from bench.results.record import (
    GZ_SUFFIX,
    RECORD_FULL,
    RECORD_LEAN,
    RECORD_STANDARD,
    check_record,
    file_name,
    is_whole,
    open_writer,
    read_lines,
    run_file,
    seal,
    trace_file,
    writes_tables,
)
from bench.results.writers import TelemetryWriter
from bench.wire.trace import TraceRecorder
from dbc.errors import ConfigError

ROWS = 5000
FLUSH_EVERY_ROWS = 50  # as a bench flushes: every few cycles
START_WALL_S = 1_780_000_000.0
FRAMES = 300
FRAME_PERIOD_NS = 1_000_000


def _rows(n: int) -> list[str]:
    return [f"{k * 0.01:.10g},{0.5 + 1e-7 * k * k:.10g},{k % 7}\n" for k in range(n)]


def _write(path: Path, lines: list[str], close: bool = True) -> TextIO:
    """Write ``lines`` flushing as a bench does; the writer (hold it while it must stay
    unclosed: collected, it closes and writes the trailer)."""
    w = open_writer(path)
    for k, line in enumerate(lines):
        w.write(line)
        if k % FLUSH_EVERY_ROWS == FLUSH_EVERY_ROWS - 1:
            w.flush()
    w.flush()
    if close:
        w.close()
    return w


def test_compressed_file_round_trips_and_is_gzip(tmp_path: Path) -> None:
    """What open_writer wrote to a .gz is what read_lines and gzip itself read back."""
    lines = _rows(ROWS)
    path = tmp_path / "t.csv.gz"
    _write(path, lines)
    assert list(read_lines(path)) == lines
    assert gzip.decompress(path.read_bytes()).decode() == "".join(lines)
    assert path.stat().st_size < len("".join(lines))  # the figure: benchmarks/run_resources.py


def test_plain_file_is_plain_text(tmp_path: Path) -> None:
    """A name without .gz is written as plain UTF-8 text."""
    lines = _rows(10)
    _write(tmp_path / "t.csv", lines)
    assert (tmp_path / "t.csv").read_text(encoding="utf-8") == "".join(lines)


def test_same_rows_give_the_same_bytes(tmp_path: Path) -> None:
    """No time in the gzip header: two writes of the same rows are byte-identical."""
    lines = _rows(ROWS)
    _write(tmp_path / "a.csv.gz", lines)
    _write(tmp_path / "b.csv.gz", lines)
    assert (tmp_path / "a.csv.gz").read_bytes() == (tmp_path / "b.csv.gz").read_bytes()


def test_a_writer_that_died_leaves_every_flushed_line(tmp_path: Path) -> None:
    """The file as a killed writer leaves it (flushed, never closed) reads back whole."""
    lines = _rows(ROWS)
    path = tmp_path / "t.csv.gz"
    writer = _write(path, lines, close=False)
    shutil.copy(path, tmp_path / "killed.csv.gz")  # no gzip trailer
    writer.close()
    assert not is_whole(tmp_path / "killed.csv.gz")
    assert list(read_lines(tmp_path / "killed.csv.gz")) == lines


def test_a_file_cut_mid_block_gives_a_prefix(tmp_path: Path) -> None:
    """Cut in the middle (a full disk): a prefix of the rows, no error."""
    lines = _rows(ROWS)
    path = tmp_path / "t.csv.gz"
    _write(path, lines)
    data = path.read_bytes()
    (tmp_path / "cut.csv.gz").write_bytes(data[: len(data) // 2])
    got = list(read_lines(tmp_path / "cut.csv.gz"))
    assert 0 < len(got) < len(lines) and got == lines[: len(got)]


def test_run_file_finds_either_form(tmp_path: Path) -> None:
    """run_file: the plain file, else the .gz one, else the plain name (missing)."""
    assert run_file(tmp_path, "x.csv") == tmp_path / "x.csv"
    (tmp_path / ("x.csv" + GZ_SUFFIX)).write_bytes(b"")
    assert run_file(tmp_path, "x.csv") == tmp_path / "x.csv.gz"
    (tmp_path / "x.csv").write_text("")
    assert run_file(tmp_path, "x.csv") == tmp_path / "x.csv"


def test_levels_name_their_files_and_a_bad_level_is_refused() -> None:
    """standard adds .gz, full keeps the name; any other level is a ConfigError naming it."""
    assert file_name("trace.asc", RECORD_STANDARD) == "trace.asc.gz"
    assert file_name("trace.asc", RECORD_FULL) == "trace.asc"
    assert file_name("telemetry.csv", RECORD_LEAN) == "telemetry.csv.gz"
    assert [writes_tables(r) for r in (RECORD_STANDARD, RECORD_FULL, RECORD_LEAN)] == [
        True, True, False]
    with pytest.raises(ConfigError, match="'fast'"):
        check_record("fast")


@pytest.mark.parametrize("record", [RECORD_STANDARD, RECORD_FULL])
def test_trace_and_tables_of_either_level_read_back(tmp_path: Path, record: str) -> None:
    """A trace and frames table written at either level: python-can reads the trace (.asc or
    .asc.gz), the frame table has a row per frame, the same text at both levels."""
    rec = TraceRecorder(tmp_path, START_WALL_S, deferred=True, record=record)
    for k in range(FRAMES):
        rec.frame(can.Message(arbitration_id=0x100 + k % 3, data=bytes([k % 256, 1]),
                              is_extended_id=False), k * FRAME_PERIOD_NS, tx=k % 2 == 0)
        if k % FLUSH_EVERY_ROWS == 0:
            rec.flush()
    rec.close()
    trace = run_file(tmp_path, "trace.asc")
    assert trace.name == file_name("trace.asc", record)
    msgs = list(can.LogReader(str(trace)))
    assert [m.timestamp for m in msgs] == [k * FRAME_PERIOD_NS / 1e9 for k in range(FRAMES)]
    frames = list(read_lines(run_file(tmp_path, "frames.csv")))
    assert len(frames) == FRAMES + 1  # and the header


def test_a_lean_trace_is_the_blf_alone_with_the_standard_bytes(tmp_path: Path) -> None:
    """At lean, the recorder writes trace.blf (byte for byte the standard level's) and the
    events, no trace.asc and no frames table; trace_file then names the BLF."""
    for record in (RECORD_STANDARD, RECORD_LEAN):
        folder = tmp_path / record
        folder.mkdir()
        rec = TraceRecorder(folder, START_WALL_S, deferred=True, record=record)
        for k in range(FRAMES):
            rec.frame(can.Message(arbitration_id=0x100 + k % 3, data=bytes([k % 256, 1]),
                                  is_extended_id=False), k * FRAME_PERIOD_NS, tx=k % 2 == 0)
        rec.event(FRAMES * FRAME_PERIOD_NS, "fsw_silent", cycle=1)
        rec.close()
    lean, std = tmp_path / RECORD_LEAN, tmp_path / RECORD_STANDARD
    assert (lean / "trace.blf").read_bytes() == (std / "trace.blf").read_bytes()
    assert sorted(p.name for p in lean.iterdir()) == ["events.jsonl", "trace.blf"]
    assert trace_file(lean) == lean / "trace.blf"
    assert trace_file(std) == std / "trace.asc.gz"
    assert len(list(can.LogReader(str(trace_file(lean))))) == FRAMES


def test_the_trace_digest_is_the_frames_not_the_files(tmp_path: Path) -> None:
    """trace_sha256: the same at every record level and any start date; one data byte, one
    ns or the direction of one frame changed, another digest."""

    def digest(record: str, start_s: float, k_changed: int = -1, what: str = "") -> str:
        folder = tmp_path / f"{record}{start_s}{k_changed}{what}"
        folder.mkdir()
        rec = TraceRecorder(folder, start_s, deferred=True, record=record)
        for k in range(FRAMES):
            changed = k == k_changed
            data = bytes([k % 256, 2 if changed and what == "data" else 1])
            t_ns = k * FRAME_PERIOD_NS + (1 if changed and what == "time" else 0)
            tx = (k % 2 == 0) != (changed and what == "tx")
            rec.frame(can.Message(arbitration_id=0x100 + k % 3, data=data,
                                  is_extended_id=False), t_ns, tx=tx)
        rec.close()
        return rec.digest()

    ref = digest(RECORD_STANDARD, START_WALL_S)
    assert digest(RECORD_LEAN, START_WALL_S) == ref == digest(RECORD_FULL, START_WALL_S + 1e5)
    for what in ("data", "time", "tx"):
        assert digest(RECORD_STANDARD, START_WALL_S, FRAMES // 2, what) != ref, what


def test_telemetry_writer_compresses_by_name(tmp_path: Path) -> None:
    """TelemetryWriter on a .gz name writes the same text as on a plain one."""
    for name in ("t.csv", "t.csv.gz"):
        w = TelemetryWriter(tmp_path / name, ["t_s", "x"], deferred=True)
        for k in range(ROWS):
            w.row([k * 0.01, k * 1e-3])
        w.close()
    assert list(read_lines(tmp_path / "t.csv.gz")) == list(read_lines(tmp_path / "t.csv"))


def test_seal_makes_a_killed_writers_file_whole_with_the_same_bytes(tmp_path: Path) -> None:
    """seal: a file without trailer becomes a whole gzip file of the same flushed text."""
    lines = _rows(ROWS)
    path = tmp_path / "t.csv.gz"
    writer = _write(path, lines, close=False)
    killed = tmp_path / "killed.csv.gz"
    shutil.copy(path, killed)
    writer.close()
    assert not is_whole(killed)
    with pytest.raises(EOFError):
        gzip.decompress(killed.read_bytes())
    assert seal(killed)
    assert is_whole(killed)
    assert gzip.decompress(killed.read_bytes()).decode() == "".join(lines)
    assert not seal(killed)  # whole now: left as it is
    assert not list(tmp_path.glob(".sealing-*"))


def test_seal_keeps_the_prefix_of_a_file_cut_mid_block(tmp_path: Path) -> None:
    """seal on a file cut in the middle of a block keeps a whole-line prefix or more."""
    lines = _rows(ROWS)
    path = tmp_path / "t.csv.gz"
    _write(path, lines)
    data = path.read_bytes()
    cut = tmp_path / "cut.csv.gz"
    cut.write_bytes(data[: len(data) // 2])
    assert seal(cut)
    text = gzip.decompress(cut.read_bytes()).decode()
    assert 0 < len(text) < len("".join(lines)) and "".join(lines).startswith(text)


def test_seal_leaves_plain_whole_and_missing_files(tmp_path: Path) -> None:
    """seal does nothing to a plain file, a whole .gz file or a missing one."""
    _write(tmp_path / "t.csv", _rows(10))
    _write(tmp_path / "w.csv.gz", _rows(10))
    before = (tmp_path / "w.csv.gz").read_bytes()
    assert not seal(tmp_path / "t.csv")
    assert not seal(tmp_path / "w.csv.gz") and (tmp_path / "w.csv.gz").read_bytes() == before
    assert not seal(tmp_path / "none.csv.gz")


def test_sealed_trace_reads_to_the_end_with_python_can(tmp_path: Path) -> None:
    """A trace whose recorder died reads whole with can.LogReader once sealed."""
    rec = TraceRecorder(tmp_path, START_WALL_S, deferred=False, record=RECORD_STANDARD)
    for k in range(FRAMES):
        rec.frame(can.Message(arbitration_id=0x100, data=bytes([k % 256]),
                              is_extended_id=False), k * FRAME_PERIOD_NS, tx=True)
    rec.flush()  # no close: the process is killed here
    killed = tmp_path / "killed"
    killed.mkdir()
    shutil.copy(tmp_path / "trace.asc.gz", killed / "trace.asc.gz")
    rec.close()
    assert seal(killed / "trace.asc.gz")
    msgs = list(can.LogReader(str(killed / "trace.asc.gz")))
    assert [m.data[0] for m in msgs] == [k % 256 for k in range(FRAMES)]
