"""The timing files of a run folder as column arrays: ``frames.csv``, ``chains.csv``.

What
----
``FrameTable`` (one row per frame on the trace), ``ChainTable`` (one row per control
cycle) and :func:`read_csv_columns`, the tolerant CSV reader behind both (a run folder
whose writer died mid-line still reads).

Inputs
------
``frames.csv`` (``t_ready_s, t_start_s, t_rx_s, id, dlc, bits, tx, counter``, written by
:mod:`bench.wire.trace`), ``chains.csv`` (``cycle, imu_counter, t_imu_tx_s, t_cmd_rx_s,
t_fire_cmd_rx_s, t_valve_open_s``, written by :mod:`bench.results.writers`; run folders
written before ``t_fire_cmd_rx_s`` existed read it as ``t_cmd_rx_s``). Times in seconds,
``nan`` where unknown; ``counter`` is -1 (:data:`NO_COUNTER`) for a frame too short to
carry an alive counter.

Outputs
-------
Numpy arrays per column. A frame's *seen* time (``FrameTable.seen_s``) is ``t_rx`` where
known, else ``t_ready`` (a realtime bench frame whose reception the flight software did
not log in ``fsw_rx.csv``; the virtual buses deliver within tens of microseconds of
sending).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bench.results.record import read_lines
from bench.results.writers import CHAIN_COLUMNS
from dbc.errors import ConfigError, RunError

NO_COUNTER = -1  # recorder's counter for frames too short to carry one
FIRE_COLUMN = "t_fire_cmd_rx_s"  # chains.csv: the first firing command frame received


@dataclass(frozen=True, eq=False)
class FrameTable:
    """The columns of ``frames.csv`` as arrays (times in s; ``nan`` where unknown)."""

    t_ready_s: np.ndarray
    t_start_s: np.ndarray
    t_rx_s: np.ndarray
    can_id: np.ndarray
    dlc: np.ndarray
    bits: np.ndarray
    tx: np.ndarray
    counter: np.ndarray

    def __post_init__(self) -> None:
        n = {len(v) for v in vars(self).values()}
        if len(n) > 1:
            raise ConfigError("FrameTable", "columns", sorted(n), "columns of equal length")

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any]) -> FrameTable:
        """From a mapping of the ``frames.csv`` column names to sequences."""

        def f(k: str) -> np.ndarray:
            return np.asarray(cols[k], dtype=float)

        def i(k: str) -> np.ndarray:
            return np.asarray(cols[k], dtype=float).astype(np.int64)

        return cls(
            f("t_ready_s"),
            f("t_start_s"),
            f("t_rx_s"),
            i("id"),
            i("dlc"),
            i("bits"),
            i("tx"),
            i("counter"),
        )

    def __len__(self) -> int:
        return len(self.can_id)

    @property
    def seen_s(self) -> np.ndarray:
        """``t_rx`` where known, else ``t_ready``."""
        return np.where(np.isfinite(self.t_rx_s), self.t_rx_s, self.t_ready_s)

    def select(self, mask: np.ndarray) -> FrameTable:
        """The rows where ``mask`` is true (or at the given indices), in that order."""
        return FrameTable(**{k: v[mask] for k, v in vars(self).items()})


@dataclass(frozen=True, eq=False)
class ChainTable:
    """The columns of ``chains.csv`` as arrays (times in s; ``nan`` where none)."""

    cycle: np.ndarray
    imu_counter: np.ndarray
    t_imu_tx_s: np.ndarray
    t_cmd_rx_s: np.ndarray
    t_fire_cmd_rx_s: np.ndarray
    t_valve_open_s: np.ndarray

    @classmethod
    def from_columns(cls, cols: Mapping[str, Any]) -> ChainTable:
        """From a mapping of the ``chains.csv`` column names to sequences.

        Without ``t_fire_cmd_rx_s`` (older run folders) the last command frame stands in.
        """
        if FIRE_COLUMN not in cols:
            cols = {**cols, FIRE_COLUMN: cols["t_cmd_rx_s"]}
        return cls(*(np.asarray(cols[k], dtype=float) for k in CHAIN_COLUMNS))

    @classmethod
    def read(cls, path: Path) -> ChainTable:
        """``chains.csv`` of a run folder (also one written before ``t_fire_cmd_rx_s``)."""
        head = next(csv.reader(read_lines(path)), [])
        cols = [c for c in CHAIN_COLUMNS if c != FIRE_COLUMN or c in head]
        return cls.from_columns(read_csv_columns(path, cols))

    def __len__(self) -> int:
        return len(self.cycle)


def read_csv_columns(path: Path, columns: Sequence[str]) -> dict[str, np.ndarray]:
    """Numeric ``columns`` of a run-folder CSV file as float arrays.

    A row with the wrong number of fields or a non-numeric field (the last line of a file
    whose writer died mid-line) is dropped. Raises :class:`RunError` if the file or a
    column is missing.
    """
    if not path.exists():
        raise RunError(f"{path}: missing (not a run folder?)")
    reader = csv.reader(read_lines(path))
    head = next(reader, None) or []
    missing = [c for c in columns if c not in head]
    if missing:
        raise RunError(f"{path}: no column(s) {', '.join(missing)} (header {head})")
    idx = [head.index(c) for c in columns]
    rows: list[list[float]] = []
    for r in reader:
        if len(r) != len(head):
            continue
        try:
            rows.append([float(r[i]) for i in idx])
        except ValueError:
            continue
    arr = np.array(rows, dtype=float).reshape(-1, len(columns))
    return {c: arr[:, j] for j, c in enumerate(columns)}
