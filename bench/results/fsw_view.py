"""The bench's view of the flight software, from the frames it sends: mode, estimate, FDIR.

In: decoded FSW_STATUS, FSW_ATT_EST and FSW_FDIR signals with the bench's time of receipt
[ns], and the true attitude at that time. Out: the flight software's mode and counters
(telemetry, summary.json ``deadline_misses.fsw_overruns``), its attitude estimate and the
estimate's error against the truth [deg] (telemetry), its latest FDIR report
(summary.json ``fdir``), its restarts, its mode changes (summary.json ``fsw_mode_changes``:
the first :data:`MAX_MODE_CHANGES` with their time, all counted), and events
(``fsw_isolated``, ``fsw_restart``, ``fsw_restart_refused``, ``fsw_mode``) as
``(t_ns, name, fields)``.

Restarts: an FSW_STATUS in BOOT mode after one that was not is a restart only when the
flight software had gone quiet first: no frame of it taken for at least
``RESTART_QUIET_NS`` of wall-clock time (a process that dies and boots again is silent
far longer). A BOOT status in the middle of a live stream is a replayed or forged frame:
refused, counted (``restarts_refused``) and not taken, so it cannot reset anything.
"""

from __future__ import annotations

import math
from typing import Any

from dbc.icd import Icd
from dbc.quaternion import unpack_quaternion

RAD_DEG = 180.0 / math.pi
RESTART_QUIET_NS = 200_000_000
MAX_MODE_CHANGES = 20  # mode changes kept for summary.json (a flapping mode is counted)
NS_PER_S = 1e9
Event = tuple[int, str, dict[str, Any]]


def quat_error_deg(q: tuple[float, ...] | list[float], r: tuple[float, ...]) -> float:
    """Rotation angle between attitudes q and r [deg] (scalar-first quaternions)."""
    d = abs(q[0] * r[0] + q[1] * r[1] + q[2] * r[2] + q[3] * r[3])
    return 2.0 * math.acos(min(1.0, d)) * RAD_DEG


class FswView:
    """What the bench knows of the flight software (see the module docstring)."""

    def __init__(self, icd: Icd) -> None:
        self.icd = icd
        self._boot = icd.modes["BOOT"]
        self._no_thruster = icd.no_failed_thruster
        self._mode_names = {v: k for k, v in icd.modes.items()}
        self.status: dict[str, float] = {}
        self.q_est: tuple[float, float, float, float] | None = None
        self.q_valid = False
        self.est_err_deg = float("nan")
        self.fdir: dict[str, Any] = {}
        self.restarts = 0
        self.restarts_refused = 0
        self.mode_changes: list[dict[str, Any]] = []
        self.mode_change_count = 0

    @property
    def mode(self) -> int:
        """FSW_STATUS.Mode of the last status taken (-1 before any)."""
        return int(self.status.get("Mode", -1))

    @property
    def overruns(self) -> int:
        """FSW_STATUS.Overruns of the last status taken."""
        return int(self.status.get("Overruns", 0))

    def restart_allowed(self, signals: dict[str, float], quiet_ns: int | None) -> bool | None:
        """For an FSW_STATUS after ``quiet_ns`` of wall-clock silence of the flight software
        (None: never heard): None if it is no restart, else whether it is taken as one."""
        if int(signals["Mode"]) != self._boot or self.status.get("Mode", self._boot) == self._boot:
            return None
        return quiet_ns is None or quiet_ns >= RESTART_QUIET_NS

    def on_status(self, signals: dict[str, float], t_ns: int, events: list[Event]) -> None:
        """Take an FSW_STATUS (a restart already accepted by :meth:`restart_allowed`)."""
        mode, previous = int(signals["Mode"]), self.status.get("Mode")
        if mode == self._boot and previous is not None and previous != self._boot:
            # the flight software booted again: its counters restart, its state is new
            self.restarts += 1
            events.append((t_ns, "fsw_restart", {"count": self.restarts}))
        elif previous is not None and mode != int(previous):
            flags = int(signals["FdirFlags"])
            change: dict[str, Any] = {
                "mode": self._mode_names.get(mode, str(mode)),
                "previous": self._mode_names.get(int(previous), str(previous)),
                "fdir_flags": [n for n, bit in self.icd.fdir_flags.items() if flags & bit]}
            events.append((t_ns, "fsw_mode", change))
            self.mode_change_count += 1
            if len(self.mode_changes) < MAX_MODE_CHANGES:
                self.mode_changes.append({"t_s": t_ns / NS_PER_S, **change})
        self.status = signals

    def refuse_restart(self, t_ns: int, events: list[Event]) -> None:
        """A BOOT status while the flight software was live: not taken (module docstring)."""
        self.restarts_refused += 1
        events.append((t_ns, "fsw_restart_refused", {
            "why": "FSW_STATUS in BOOT mode while the flight software was answering: "
                   "a replayed or forged frame", "count": self.restarts_refused}))

    def on_estimate(self, signals: dict[str, float], q_true: tuple[float, ...]) -> None:
        """Take an FSW_ATT_EST; its error against ``q_true`` (the truth at its cycle)."""
        self.q_est = unpack_quaternion(signals)
        self.est_err_deg = quat_error_deg(q_true, self.q_est)
        self.q_valid = bool(signals["Valid"])

    def on_fdir(self, signals: dict[str, float], t_ns: int, events: list[Event]) -> None:
        """Keep the latest FDIR report; its first isolation is an event."""
        failed = int(signals["FailedThruster"])
        kinds = self.icd.failure_kinds
        report = {
            "available_mask": int(signals["AvailableMask"]),
            "failed_thruster": None if failed == self._no_thruster else failed,
            "failure_kind": kinds.get(int(signals["FailureKind"]), "other"),
            "detection_time_s": float(signals["DetectionTime"]) or None,
            "isolation_delay_s": float(signals["IsolationDelay"]),
            "sensor_flags": int(signals["SensorFlags"]),
        }
        if report["failed_thruster"] is not None and self.fdir.get("failed_thruster") is None:
            events.append((t_ns, "fsw_isolated", report))
        self.fdir = report

    def estimate_row(self) -> list[float]:
        """Telemetry columns fsw_q0..3, fsw_est_err_deg, fsw_mode (NaN where unknown)."""
        q = self.q_est if (self.q_est and self.q_valid) else None
        nan = float("nan")
        return [*(q if q else (nan, nan, nan, nan)), self.est_err_deg if q else nan,
                float(self.mode)]
