"""Ideal continuous-thrust ("throttled") valve: the on-time fraction becomes a constant thrust.

What it does
    The reference actuator the papers simulate (seed 000 §V, seed 001 §5, seed 003's
    "ideal" comparisons): no delays, no rise or tail, no minimum on-time. A command
    received at t with on-time τ for a control period P gives the constant thrust

        F = min(τ, P)/P · Fmax   on [t, t + P)

    and 0 afterwards unless a newer command replaces it (a command always replaces the
    one in progress from its arrival on). The impulse of one command is therefore
    exactly τ·Fmax (for τ ≤ P).

RK4 sampling (why the impulse is exact)
    The thrust is piecewise constant with jumps at arbitrary nanoseconds. Sampling a jump
    at the RK4 stage times would miscount its step; ``stage_thrusts_N(t, dt)`` instead
    returns the *mean* thrust over [t, t + dt] for all three stages, so Simpson's rule
    (the impulse booking of the thruster set and the velocity increment of RK4 for a
    constant attitude) integrates the thrust exactly. ``thrust_N`` is the instantaneous
    value (telemetry).

Faults: ``stuck_closed`` (0 N), ``stuck_open`` (Fmax), ``degraded`` (factor × thrust)
and ``leak`` (+ constant thrust) as in ``bench.station.valves.valve``; ``delayed`` and
``intermittent`` describe valve-opening physics this model does not have and raise
``ConfigError``.

Inputs: ``ValveParams`` (only ``max_thrust_N`` and ``isp_s`` matter here), the control
period ``period_ns`` [ns]. Times are integer nanoseconds of simulation time.
"""

from __future__ import annotations

import bisect

import numpy as np

from bench.station.valves.params import (
    FAULT_DEGRADED,
    FAULT_DELAYED,
    FAULT_INTERMITTENT,
    FAULT_KINDS,
    FAULT_LEAK,
    FAULT_STUCK_CLOSED,
    FAULT_STUCK_OPEN,
    HISTORY_NS,
    NEVER_NS,
    NOMINAL_THRUST_FACTOR,
    FaultParams,
    ValveParams,
    check_fault_params,
)
from dbc import validation as check
from dbc.errors import ConfigError

UNSUPPORTED_FAULTS = frozenset({FAULT_DELAYED, FAULT_INTERMITTENT})
"""Valve faults of opening physics the ideal model does not have."""


class ThrottledValve:
    """Ideal continuous-thrust valve (module docstring); the ``ValveModel`` contract."""

    def __init__(
        self, params: ValveParams, period_ns: int, rng: np.random.Generator | None = None
    ) -> None:
        self.params = params
        self.period_ns = check.integer("ThrottledValve", "period_ns", period_ns, lo=1)
        self.openings = 0
        self.dropped_pulses = 0
        self.idle_from_ns = -NEVER_NS
        # physical thrust breakpoints (t_ns, thrust from t_ns on [N]), time order
        self._times: list[int] = [-NEVER_NS]
        self._thrust: list[float] = [0.0]
        self._cmd_level_N = 0.0
        self._cmd_start_ns = -NEVER_NS
        self._cmd_end_ns = -NEVER_NS
        self._last_event_ns = -NEVER_NS
        self._faults: dict[str, dict[str, float]] = {}

    # --- queries --------------------------------------------------------------------
    def thrust_N(self, t_ns: int) -> float:
        """Physical thrust [N] at ``t_ns``."""
        i = bisect.bisect_right(self._times, t_ns) - 1
        return self._thrust[max(i, 0)]

    def mean_thrust_N(self, t0_ns: int, t1_ns: int) -> float:
        """Mean thrust over [t0, t1] [N] (exact integral of the piecewise constant thrust)."""
        times, thrust = self._times, self._thrust
        i = max(bisect.bisect_right(times, t0_ns) - 1, 0)
        acc = 0.0
        t = t0_ns
        while t < t1_ns:
            nxt = times[i + 1] if i + 1 < len(times) else t1_ns
            end = min(nxt, t1_ns)
            acc += thrust[i] * (end - t)
            t = end
            i += 1
        return acc / (t1_ns - t0_ns)

    def stage_thrusts_N(self, t_ns: int, dt_ns: int) -> tuple[float, float, float]:
        """The mean thrust over [t, t + dt], three times (module docstring)."""
        if t_ns >= self.idle_from_ns:
            return (0.0, 0.0, 0.0)
        f = self.mean_thrust_N(t_ns, t_ns + dt_ns)
        return (f, f, f)

    def coil_energised(self, t_ns: int) -> bool:
        """True while a command with a non-zero on-time is in force."""
        return self._cmd_level_N > 0.0 and self._cmd_start_ns <= t_ns < self._cmd_end_ns

    def status(self, t_ns: int) -> tuple[bool, bool, bool]:
        """(commanded, open: thrust > 10 % Fmax, commanded)."""
        coil = self.coil_energised(t_ns)
        return (coil, self.thrust_N(t_ns) > self.params.open_threshold_N, coil)

    @property
    def faults_active(self) -> dict[str, FaultParams]:
        """Active faults: kind → recorded parameters (a copy)."""
        return {k: dict(v) for k, v in self._faults.items()}

    @property
    def fault(self) -> str | None:
        """None without fault, else the active kinds joined by ``+``."""
        return "+".join(self._faults) if self._faults else None

    # --- commands -------------------------------------------------------------------
    def command(self, t_ns: int, on_time_ns: int) -> None:
        """Thrust (min(on, P)/P)·Fmax from ``t_ns`` for one period P (0 = off now)."""
        self._check_time(t_ns)
        if on_time_ns < 0:
            raise ValueError(f"on_time_ns must be >= 0, got {on_time_ns!r}")
        was_on = self.coil_energised(t_ns)
        level = min(on_time_ns, self.period_ns) / self.period_ns * self.params.max_thrust_N
        self._cmd_level_N = level
        self._cmd_start_ns = t_ns
        self._cmd_end_ns = t_ns + self.period_ns if level > 0.0 else t_ns
        if level > 0.0 and not was_on:
            self.openings += 1
        self._replan(t_ns)

    def set_fault(self, kind: str | None, t_ns: int | None = None, **params: object) -> None:
        """Inject fault ``kind`` at ``t_ns`` (module docstring), or clear all (``None``)."""
        source = f"ThrottledValve.set_fault({kind!r})"
        t = self._last_event_ns if t_ns is None else t_ns
        self._check_time(t)
        if kind is None:
            if params:
                key = next(iter(params))
                raise ConfigError(source, key, params[key], "no parameter when clearing (None)")
            self._faults.clear()
        else:
            if kind in UNSUPPORTED_FAULTS:
                raise ConfigError(source, "kind", kind, "a fault the throttled valve models "
                                  f"(not {sorted(UNSUPPORTED_FAULTS)})")
            recorded = check_fault_params(kind, params, source, self.params.max_thrust_N)
            if kind in (FAULT_STUCK_OPEN, FAULT_STUCK_CLOSED):
                self._faults.pop(FAULT_STUCK_OPEN, None)
                self._faults.pop(FAULT_STUCK_CLOSED, None)
            self._faults[kind] = recorded
        self._replan(t)

    def clear_fault(self, kind: str, t_ns: int | None = None) -> None:
        """Clear fault ``kind`` at ``t_ns``; a no-op if inactive."""
        if kind not in FAULT_KINDS:
            raise ConfigError(
                f"ThrottledValve.clear_fault({kind!r})",
                "kind",
                kind,
                f"one of {sorted(FAULT_KINDS)}",
            )
        t = self._last_event_ns if t_ns is None else t_ns
        self._check_time(t)
        self._faults.pop(kind, None)
        self._replan(t)

    # --- internals ------------------------------------------------------------------
    def _check_time(self, t_ns: int) -> None:
        if t_ns < self._last_event_ns:
            raise ValueError(
                f"valve events must be in time order: t_ns={t_ns} < last {self._last_event_ns}"
            )

    def _physical_N(self, commanded_N: float) -> float:
        f = self._faults
        if FAULT_STUCK_CLOSED in f:
            commanded_N = 0.0
        elif FAULT_STUCK_OPEN in f:
            commanded_N = self.params.max_thrust_N
        factor = f[FAULT_DEGRADED]["factor"] if FAULT_DEGRADED in f else NOMINAL_THRUST_FACTOR
        leak = f[FAULT_LEAK]["thrust_N"] if FAULT_LEAK in f else 0.0
        return factor * commanded_N + leak

    def _replan(self, t_ns: int) -> None:
        """Rebuild the thrust breakpoints from ``t_ns`` on (earlier history kept)."""
        keep = bisect.bisect_left(self._times, t_ns)
        lo = max(bisect.bisect_right(self._times, t_ns - HISTORY_NS) - 1, 0)
        times, thrust = self._times[lo:keep], self._thrust[lo:keep]
        on = self._cmd_end_ns > t_ns
        times.append(t_ns)
        thrust.append(self._physical_N(self._cmd_level_N if on else 0.0))
        if on:
            times.append(self._cmd_end_ns)
            thrust.append(self._physical_N(0.0))
        self._times, self._thrust = times, thrust
        self._last_event_ns = t_ns
        self.idle_from_ns = times[-1] if thrust[-1] == 0.0 else NEVER_NS
