"""A run folder's telemetry.csv for the plot and report tests: an attitude error decaying
as exp(-t) sampled every 10 ms, every other column 0."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bench.results.telemetry import telemetry_columns

TELEMETRY_DT_S = 0.01


def write_telemetry(folder: Path, n_thrusters: int, n_rows: int) -> None:
    """``folder/telemetry.csv`` with ``n_rows`` rows of a ``n_thrusters`` vehicle."""
    cols = telemetry_columns(n_thrusters)
    data = np.zeros((n_rows, len(cols)))
    data[:, 0] = np.arange(n_rows) * TELEMETRY_DT_S
    data[:, cols.index("att_err_deg")] = np.exp(-data[:, 0])
    with open(folder / "telemetry.csv", "w", encoding="utf-8") as f:
        f.write(",".join(cols) + "\n")
        f.writelines(",".join(map(repr, row.tolist())) + "\n" for row in data)
