"""CSV writers of the run folder: per-column number formats, and telemetry's precision."""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.results.telemetry import TIME_FORMAT, VALUE_FORMAT
from bench.results.writers import TelemetryWriter

LONGEST_RUN_S = 1e6  # bench.scenario's largest duration
TELEMETRY_STEP_S = 0.01
VALUE_REL_TOL = 5e-7  # half a unit in the 7th significant digit


def _write(path: Path, formats: list[str] | None, rows: list[list[float | int]]) -> list[str]:
    w = TelemetryWriter(path, ["t_s", "x"], deferred=False, formats=formats)
    for r in rows:
        w.row(r)
    w.close()
    return path.read_text().splitlines()


def test_default_format_keeps_ten_digits(tmp_path: Path) -> None:
    """Without formats every column has 10 significant digits (the timing tables)."""
    lines = _write(tmp_path / "t.csv", None, [[1234.567891234, 0.1234567891234]])
    assert lines == ["t_s,x", "1234.567891,0.1234567891"]


def test_telemetry_formats_keep_time_exact_and_values_to_seven_digits(tmp_path: Path) -> None:
    """Telemetry's t_s reads back to the 10 ms row at the longest run; values to 7 digits."""
    t_last_s = LONGEST_RUN_S - TELEMETRY_STEP_S
    value = 0.123456789
    lines = _write(tmp_path / "t.csv", [TIME_FORMAT, VALUE_FORMAT], [[t_last_s, value]])
    t_text, x_text = lines[1].split(",")
    assert float(t_text) == t_last_s
    assert float(x_text) != value and float(x_text) == pytest.approx(value, rel=VALUE_REL_TOL)


def test_a_format_per_column_or_nothing(tmp_path: Path) -> None:
    """A format list of the wrong length is refused, naming the file and both counts."""
    with pytest.raises(ValueError, match=r"t\.csv: 1 formats for 2 columns"):
        TelemetryWriter(tmp_path / "t.csv", ["t_s", "x"], formats=["%.3g"])
