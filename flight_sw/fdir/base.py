"""The thruster-FDIR strategy interface: observations in, detection and isolation out.

What it does: defines :class:`ThrusterFdirStrategy`, the small interface every thruster
fault detection and isolation strategy implements (one strategy per file:
:mod:`flight_sw.fdir.valve_status`, :mod:`flight_sw.fdir.rate_residual`), with hooks that
do nothing by default so a strategy overrides only the observations it uses, and the
immutable results :class:`ThrusterFailure` and :class:`Verdict`.

Inputs (hooks, each with its time ``t_ns`` [integer ns of the flight software's time
base]): ``on_command`` the valve on-times [s] the flight software commanded for the
control period starting at ``t_ns`` (what it sent, per thruster); ``on_gyro`` one gyro
sample (measured ω_BN_B [rad/s], body axes, raw); ``on_accel`` one accelerometer sample
(specific force [m/s²], body axes); ``on_valve_status`` one THR_STATUS sample (per
thruster: coil commanded, valve open, coil current; booleans).
Output: ``evaluate(t_ns)`` once per control cycle -> :class:`Verdict`: whether an anomaly
is detected now (threshold and persistence passed) and, once isolated, the failure.
``set_failures`` tells a strategy which failures are known (after the allocator was
reconfigured), so it models them instead of detecting them again; ``reset`` forgets
everything (bench restart).

Assumptions: single thruster failures of two kinds (FSW_FDIR.FailureKind): stuck closed
(no thrust whatever the command) and stuck open (full thrust whatever the command).

Source: interface only; the strategies cite theirs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np


class FailureKind(IntEnum):
    """FSW_FDIR.FailureKind values (the DBC's VAL_ table)."""

    NONE = 0
    STUCK_CLOSED = 1
    STUCK_OPEN = 2
    OTHER = 3


@dataclass(frozen=True)
class ThrusterFailure:
    """One isolated thruster failure.

    Attributes:
        thruster: thruster index (0-based, as in THR_CMD/THR_STATUS).
        kind: stuck closed or stuck open.
        t_detect_ns: when the anomaly was first detected [ns].
        t_isolate_ns: when this thruster was isolated [ns] (≥ ``t_detect_ns``).
        source: the strategy that isolated it (its ``name``).
    """

    thruster: int
    kind: FailureKind
    t_detect_ns: int
    t_isolate_ns: int
    source: str


@dataclass(frozen=True)
class Verdict:
    """One evaluation of a strategy.

    Attributes:
        detected: an anomaly is detected now (its test passed threshold and persistence).
        t_detect_ns: when the current detection was first declared (None if not detected).
        failure: the failure isolated by this evaluation, else None.
    """

    detected: bool = False
    t_detect_ns: int | None = None
    failure: ThrusterFailure | None = None


NOTHING = Verdict()


class ThrusterFdirStrategy:
    """Base of the thruster FDIR strategies: every hook is a no-op, nothing is detected."""

    name = "none"

    def on_command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """The on-times [s] commanded for the period starting at ``t_ns`` (one per thruster)."""

    def on_gyro(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """One gyro sample [rad/s, body axes] taken at ``t_ns``."""

    def on_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """One accelerometer sample [m/s², body axes] taken at ``t_ns``."""

    def on_valve_status(
        self, t_ns: int, cmd: np.ndarray, opened: np.ndarray, current: np.ndarray
    ) -> None:
        """One THR_STATUS sample: per thruster coil commanded, valve open, coil current."""

    def evaluate(self, t_ns: int) -> Verdict:
        """Detection and isolation at ``t_ns`` (once per control cycle)."""
        return NOTHING

    def set_failures(self, t_ns: int, failures: Sequence[ThrusterFailure]) -> None:
        """The failures known (isolated and reconfigured) at ``t_ns``."""

    def reset(self) -> None:
        """Forget every observation and known failure."""
