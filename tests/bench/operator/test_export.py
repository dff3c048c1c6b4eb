"""Decoded export: every DBC signal a channel, values as cantools decodes the trace's frames."""

from __future__ import annotations

import csv
from pathlib import Path

import can
import pytest

from bench.operator.export import decode_trace, write_csv, write_mf4, write_parquet
from bench.wire.trace import TraceRecorder
from dbc.database import load_database

START_WALL_S = 1_780_000_000.0
PERIOD_NS = 10_000_000
N_SAMPLES = 5
UNKNOWN_ID = 0x7FF


def _trace(run_dir: Path) -> list[dict[str, float]]:
    """A trace of IMU_RATE frames (known values), an unknown ID and an error frame."""
    db = load_database()
    imu = db.get_message_by_name("IMU_RATE")
    rec = TraceRecorder(run_dir, START_WALL_S)
    sent = []
    for k in range(N_SAMPLES):
        values = {s.name: 0 for s in imu.signals}
        values.update({"RateX": 0.01 * k, "RateY": -0.02, "AliveCounter": k})
        rec.frame(can.Message(arbitration_id=imu.frame_id, data=imu.encode(values),
                              is_extended_id=False), k * PERIOD_NS, tx=True)
        sent.append(imu.decode(imu.encode(values), decode_choices=False))
    rec.frame(can.Message(arbitration_id=UNKNOWN_ID, data=b"\x00", is_extended_id=False),
              N_SAMPLES * PERIOD_NS, tx=False)
    rec.error_frame(N_SAMPLES * PERIOD_NS + 1)
    rec.close()
    return sent


def test_frames_decode_to_the_dbc_values_and_the_rest_is_counted(tmp_path: Path) -> None:
    """IMU_RATE's signals equal cantools' decoding of the frames; the unknown ID and the
    error frame are skipped, each counted by reason."""
    sent = _trace(tmp_path)
    decoded = decode_trace(tmp_path, load_database())
    s = decoded.series["IMU_RATE"]
    assert decoded.frames == N_SAMPLES and list(s.t_s) == [k * 0.01 for k in range(N_SAMPLES)]
    assert list(s.values["RateX"]) == [v["RateX"] for v in sent]
    assert decoded.skipped == {"ID not in the DBC": 1, "error or remote frame": 1}


def test_csv_has_a_column_per_signal_with_its_unit(tmp_path: Path) -> None:
    """One CSV per message that occurs; headed t_s, direction, SIGNAL [unit]."""
    sent = _trace(tmp_path)
    db = load_database()
    (path,) = write_csv(decode_trace(tmp_path, db), db, tmp_path / "signals")
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    imu = db.get_message_by_name("IMU_RATE")
    assert path.name == "IMU_RATE.csv" and len(rows) == N_SAMPLES + 1
    assert rows[0][:2] == ["t_s", "direction"] and "RateX [rad/s]" in rows[0]
    assert len(rows[0]) == 2 + len(imu.signals)
    col = rows[0].index("RateX [rad/s]")
    assert [r[col] for r in rows[1:]] == [format(v["RateX"], ".15g") for v in sent]
    counter = rows[0].index("AliveCounter")
    assert [r[counter] for r in rows[1:]] == [str(k) for k in range(N_SAMPLES)]  # integers
    assert {r[1] for r in rows[1:]} == {"Tx"}


def test_mf4_has_one_channel_per_dbc_signal(tmp_path: Path) -> None:
    """The MDF file opens with asammdf; a channel MESSAGE.SIGNAL for every DBC signal
    (empty for messages the run never carried), with its unit and the decoded values."""
    asammdf = pytest.importorskip("asammdf")
    sent = _trace(tmp_path)
    db = load_database()
    path = write_mf4(decode_trace(tmp_path, db), db, tmp_path / "signals.mf4")
    with asammdf.MDF(path) as mdf:
        names = {n for n in mdf.channels_db if "." in n}
        assert names == {f"{m.name}.{s.name}" for m in db.messages for s in m.signals}
        rate = mdf.get("IMU_RATE.RateX")
        assert rate.unit == "rad/s" and list(rate.samples) == [v["RateX"] for v in sent]
        assert list(rate.timestamps) == [k * 0.01 for k in range(N_SAMPLES)]


def test_parquet_has_a_typed_column_per_signal_with_its_unit(tmp_path: Path) -> None:
    """One Parquet file per message that occurs: t_s, direction, a column per signal (int64
    for integer signals), the DBC's unit in the field metadata, the values decoded."""
    import pyarrow.parquet as pq

    sent = _trace(tmp_path)
    db = load_database()
    (path,) = write_parquet(decode_trace(tmp_path, db), db, tmp_path / "pq")
    table = pq.read_table(path)
    imu = db.get_message_by_name("IMU_RATE")
    assert path.name == "IMU_RATE.parquet" and table.num_rows == N_SAMPLES
    assert table.column_names == ["t_s", "direction", *(s.name for s in imu.signals)]
    assert table.schema.field("RateX").metadata == {b"unit": b"rad/s"}
    assert table.column("RateX").to_pylist() == [v["RateX"] for v in sent]
    assert str(table.schema.field("AliveCounter").type) == "int64"
    assert table.column("AliveCounter").to_pylist() == list(range(N_SAMPLES))
    assert table.schema.metadata[b"message"] == b"IMU_RATE"


def test_a_trace_with_no_frame_of_the_dbc_is_refused(tmp_path: Path) -> None:
    """A folder whose trace decodes to nothing (not a run's trace): ConfigError, by name."""
    from dbc.errors import ConfigError

    (tmp_path / "trace.asc").write_text("garbage\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="none decoded"):
        decode_trace(tmp_path, load_database())
