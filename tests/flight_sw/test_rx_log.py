"""The flight software's receive log: rows as the bench's timing analysis reads them."""

from __future__ import annotations

from pathlib import Path

import can

from bench.operator.analysis.reception import RX_LOG_COLUMNS, receive_log
from bench.operator.analysis.tables import read_csv_columns
from flight_sw.rx_log import NO_COUNTER, ReceiveLog
from flight_sw.rx_log import RX_LOG_COLUMNS as FSW_COLUMNS

WALL_S = 1_764_633_600.123456


def test_rows_round_trip_through_the_bench_reader(tmp_path: Path) -> None:
    """Timestamp (to the microsecond), ID and alive counter survive write and read."""
    path = tmp_path / "fsw_rx.csv"
    log = ReceiveLog(path)
    log.row(can.Message(timestamp=WALL_S, arbitration_id=0x40, data=[0xAB, 0x37, 0, 0]))
    log.row(can.Message(timestamp=WALL_S + 0.010001, arbitration_id=0x7FF, data=[1]))
    log.flush()
    cols = read_csv_columns(path, RX_LOG_COLUMNS)
    log.close()
    assert FSW_COLUMNS == RX_LOG_COLUMNS
    rows = receive_log(cols, WALL_S)
    assert rows.can_id.tolist() == [0x40, 0x7FF]
    assert rows.counter.tolist() == [0x37 & 0x0F, NO_COUNTER]
    assert abs(rows.t_rx_s[0]) < 1e-6 and abs(rows.t_rx_s[1] - 0.010001) < 1e-6
