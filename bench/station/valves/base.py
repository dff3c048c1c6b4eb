"""The interface the thruster set needs from one valve model (on-off ``Valve``, ``ThrottledValve``).

Times are integer nanoseconds of simulation time; thrust in newtons. See
``bench.station.valves.valve`` for the semantics of each method (the throttled model follows
the same contract with its own physics).
"""

from __future__ import annotations

from typing import Protocol

from bench.station.valves.params import FaultParams, ValveParams


class ValveModel(Protocol):
    """One thruster valve as the thruster set and the bench node use it."""

    params: ValveParams
    openings: int
    dropped_pulses: int
    idle_from_ns: int

    def thrust_N(self, t_ns: int) -> float:
        """Physical thrust [N] at ``t_ns``."""
        ...

    def stage_thrusts_N(self, t_ns: int, dt_ns: int) -> tuple[float, float, float]:
        """Thrust samples for the RK4 stages of [t, t + dt] [N]: both models give the step's
        mean thrust three times, so the integrated impulse is exact."""
        ...

    def command(self, t_ns: int, on_time_ns: int) -> None:
        """An on-time command received at ``t_ns``."""
        ...

    def set_fault(self, kind: str | None, t_ns: int | None = None, **params: object) -> None:
        """Inject (or clear all, ``None``) a fault at ``t_ns``."""
        ...

    def clear_fault(self, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` at ``t_ns``."""
        ...

    @property
    def faults_active(self) -> dict[str, FaultParams]:
        """Active faults: kind → recorded parameters."""
        ...

    def status(self, t_ns: int) -> tuple[bool, bool, bool]:
        """(coil energised, open, current) at ``t_ns``."""
        ...
