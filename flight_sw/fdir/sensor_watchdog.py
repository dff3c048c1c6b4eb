"""Sensor watchdog: declares a sensor lost when its frames stop for N of their periods.

In: the time of each valid frame of a watched message (``t_ns``), and the current time.
Out: which sensors are lost. Periods come from the DBC (``GenMsgCycleTime``); the
threshold is ``LOST_AFTER_PERIODS`` periods (3, as the foundation issue requires).
Pure bookkeeping: time is an argument.
"""

from __future__ import annotations

from dataclasses import dataclass, field

LOST_AFTER_PERIODS = 3


@dataclass
class SensorWatchdog:
    """Tracks the last valid frame time of each watched message."""

    periods_ns: dict[str, int]
    lost_after_periods: int = LOST_AFTER_PERIODS
    last_ns: dict[str, int] = field(default_factory=dict)

    def seen(self, name: str, t_ns: int) -> None:
        """A valid frame of ``name`` arrived at ``t_ns``."""
        if name in self.periods_ns:
            self.last_ns[name] = t_ns

    def start(self, t_ns: int) -> None:
        """Start watching at ``t_ns`` (a sensor never seen counts from here)."""
        for name in self.periods_ns:
            self.last_ns.setdefault(name, t_ns)

    def lost(self, name: str, t_ns: int) -> bool:
        """True if ``name`` has been silent for more than the allowed periods at ``t_ns``."""
        last = self.last_ns.get(name)
        if last is None:
            return False
        return t_ns - last > self.lost_after_periods * self.periods_ns[name]
