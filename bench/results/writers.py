"""Run-folder writers of the results room: CSV tables and summary.json, flushed as they go.

* :class:`TelemetryWriter` — a CSV file with a fixed column list (``telemetry.csv``,
  ``chains.csv``, ``valve_pulses.csv``, ``frames.csv``; gzip-compressed when the name ends
  in ``.gz``, bench.results.record): one row of numbers per call, 10 significant digits
  unless the caller asks for fewer (telemetry: 7), flushed on demand so a crash loses at
  most what the caller has not flushed. Deferred writing (``deferred=True``, the lockstep
  bench) keeps rows as values and formats them in :meth:`TelemetryWriter.write_pending`,
  so the text formatting happens while the flight software computes its cycle; the
  file's content is the same.
* :func:`write_summary` — strict JSON (NaN and infinities as null), written atomically.

No clock is read here.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import IO, Any

from bench.results.record import open_writer
from dbc.records import write_record

NUMBER_FORMAT = "%.10g"  # 10 significant digits: 1 us at 1e4 s (the timing tables)
# per control cycle: IMU sample sent, last command frame received, first command frame that
# fires a valve received, that valve opening (nan: no valve fired)
CHAIN_COLUMNS = ["cycle", "imu_counter", "t_imu_tx_s", "t_cmd_rx_s", "t_fire_cmd_rx_s",
                 "t_valve_open_s"]
PULSE_COLUMNS = ["t_on_s", "t_off_s", "thruster"]


class TelemetryWriter:
    """``telemetry.csv`` with a fixed column list, flushed on demand."""

    def __init__(self, path: Path, columns: list[str], deferred: bool = False,
                 formats: list[str] | None = None) -> None:
        """``deferred``: keep rows until :meth:`write_pending` (see the module docstring);
        ``formats``: one printf format per column (default: 10 significant digits each)."""
        if formats is not None and len(formats) != len(columns):
            raise ValueError(f"{path.name}: {len(formats)} formats for {len(columns)} columns")
        self.path = path
        self.deferred = deferred
        self._pending: list[list[float | int]] = []
        self._file: IO[str] = open_writer(path)
        csv.writer(self._file).writerow(columns)
        self.columns = columns
        self._fmt = ",".join(formats or [NUMBER_FORMAT] * len(columns)) + "\n"

    def row(self, values: list[float | int]) -> None:
        """Append one row of numbers (same order as the columns), in the writer's format."""
        if self.deferred:
            self._pending.append(values)
        else:
            self._file.write(self._fmt % tuple(values))

    def write_pending(self) -> None:
        """Format the rows deferred writing kept into the file; not flushed."""
        if self._pending:
            fmt = self._fmt
            self._file.write("".join([fmt % tuple(v) for v in self._pending]))
            self._pending.clear()

    def flush(self) -> None:
        """Flush to disk."""
        self.write_pending()
        self._file.flush()

    def close(self) -> None:
        """Close the file."""
        self.write_pending()
        self._file.close()


def write_summary(path: Path, summary: dict[str, Any]) -> None:
    """Write ``summary`` as strict JSON (NaN and infinities as null), atomically."""
    write_record(path, summary)
