"""Thruster FDIR manager: runs the detection strategies, keeps the availability mask.

What it does: feeds every observation to each configured strategy
(:mod:`flight_sw.fdir.valve_status`, :mod:`flight_sw.fdir.rate_residual`, ...), evaluates
them once per control cycle and, when one isolates a thruster, records the failure,
removes the thruster from the availability mask and tells every strategy (so they model
it instead of detecting it again). The first strategy in configuration order wins when
two isolate in the same cycle. It reports what FSW_FDIR carries: the mask, the latest
isolated failure, its detection time (the earliest detection by any strategy of the
anomaly that led to it) and isolation delay; and for FSW_STATUS whether a detection is
pending and whether a thruster is isolated. The reconfiguration itself (allocator with
the mask, feed-forward of a stuck-open thruster's wrench) is the flight computer's.

Inputs: observations with their times (see :mod:`flight_sw.fdir.base`); ``update(t_ns)``
once per cycle. Outputs: ``mask`` (n booleans, True = usable), ``stuck_open`` (indices of
isolated stuck-open thrusters), ``failures``, :meth:`report`.

Assumptions: failures are permanent (no un-isolation); times are the flight software's.

Source: the detect/isolate/reconfigure chain of FDIR, e.g. ECSS-E-ST-70-11C (on-board
FDIR) and Wertz & Larson (eds.) 1999, "Space Mission Analysis and Design", 3rd ed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flight_sw.fdir.base import FailureKind, ThrusterFailure, ThrusterFdirStrategy

NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class FdirReport:
    """The thruster-FDIR state FSW_FDIR and FSW_STATUS report.

    Attributes:
        available_mask: bit k set = thruster k usable.
        failed_thruster: latest isolated thruster, None if none.
        failure_kind: its kind.
        detection_time_s: when it (or the pending anomaly) was detected [s]; 0 if none.
        isolation_delay_s: isolation minus detection [s]; 0 if none.
        detected: an anomaly is detected now or a thruster is isolated.
        isolated: at least one thruster is isolated (the allocator runs reconfigured).
    """

    available_mask: int
    failed_thruster: int | None
    failure_kind: FailureKind
    detection_time_s: float
    isolation_delay_s: float
    detected: bool
    isolated: bool


class ThrusterFdir:
    """Runs the thruster FDIR strategies and keeps the availability mask."""

    def __init__(self, n_thrusters: int, strategies: Sequence[ThrusterFdirStrategy]) -> None:
        self.n = n_thrusters
        self.strategies = list(strategies)
        self.time_base_ns = 0  # FSW time of simulation time 0 (reported times are relative)
        self.reset()

    def reset(self) -> None:
        """Forget every failure and observation (bench restart)."""
        self.mask = np.ones(self.n, dtype=bool)
        self.failures: list[ThrusterFailure] = []
        self._pending_ns: int | None = None
        for s in self.strategies:
            s.reset()

    @property
    def stuck_open(self) -> tuple[int, ...]:
        """Indices of the thrusters isolated as stuck open."""
        return tuple(f.thruster for f in self.failures if f.kind == FailureKind.STUCK_OPEN)

    # --- observations ---------------------------------------------------------------

    def on_command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """The on-times [s] commanded for the period starting at ``t_ns``."""
        for s in self.strategies:
            s.on_command(t_ns, on_time_s)

    def on_gyro(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """One gyro sample [rad/s]."""
        for s in self.strategies:
            s.on_gyro(t_ns, omega_meas_B)

    def on_accel(self, t_ns: int, f_meas_B: np.ndarray) -> None:
        """One accelerometer sample [m/s²]."""
        for s in self.strategies:
            s.on_accel(t_ns, f_meas_B)

    def on_valve_status(
        self, t_ns: int, cmd: np.ndarray, opened: np.ndarray, current: np.ndarray
    ) -> None:
        """One THR_STATUS sample."""
        for s in self.strategies:
            s.on_valve_status(t_ns, cmd, opened, current)

    # --- decision -------------------------------------------------------------------

    def update(self, t_ns: int) -> list[ThrusterFailure]:
        """Evaluate every strategy at ``t_ns``; returns the failures isolated now."""
        detected_at: list[int] = []
        new: list[ThrusterFailure] = []
        for s in self.strategies:
            v = s.evaluate(t_ns)
            if v.detected and v.t_detect_ns is not None:
                detected_at.append(v.t_detect_ns)
            f = v.failure
            if f is None or not self.mask[f.thruster] or new:
                continue
            t_detect = min(
                [f.t_detect_ns, *detected_at]
                + ([self._pending_ns] if self._pending_ns is not None else [])
            )
            new.append(ThrusterFailure(f.thruster, f.kind, t_detect, f.t_isolate_ns, f.source))
        if new:
            for f in new:
                self.mask[f.thruster] = False
                self.failures.append(f)
            for s in self.strategies:
                s.set_failures(t_ns, self.failures)
            self._pending_ns = None
        elif detected_at:
            first = min(detected_at)
            self._pending_ns = first if self._pending_ns is None else min(self._pending_ns, first)
        else:
            self._pending_ns = None
        return new

    def _rel_s(self, t_ns: int) -> float:
        return max(0.0, (t_ns - self.time_base_ns) / NS_PER_S)

    def report(self) -> FdirReport:
        """The state for FSW_FDIR / FSW_STATUS."""
        mask = sum(1 << k for k in range(self.n) if self.mask[k])
        isolated = bool(self.failures)
        if self._pending_ns is not None:
            last = self.failures[-1] if self.failures else None
            return FdirReport(
                mask,
                last.thruster if last else None,
                last.kind if last else FailureKind.NONE,
                self._rel_s(self._pending_ns),
                0.0,
                True,
                isolated,
            )
        if not self.failures:
            return FdirReport(mask, None, FailureKind.NONE, 0.0, 0.0, False, False)
        f = self.failures[-1]
        return FdirReport(
            mask,
            f.thruster,
            f.kind,
            self._rel_s(f.t_detect_ns),
            (f.t_isolate_ns - f.t_detect_ns) / NS_PER_S,
            True,
            True,
        )
