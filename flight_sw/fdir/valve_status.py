"""Thruster FDIR from valve telemetry (THR_STATUS): stuck-closed and stuck-open valves.

What it does: watches, per thruster, the drive electronics' report sampled at each
THR_STATUS transmission (50 Hz): ``Cmd`` (coil commanded/energised), ``Open`` (thrust
above 10 % of the maximum), ``Current`` (coil current flowing), and declares
- **stuck closed** when ``stuck_closed_samples`` samples show the coil energised and the
  valve closed (``Cmd = 1, Open = 0``) with no sample in between showing it energised and
  open (which resets the count), the last such sample no older than
  ``window_samples`` samples (older evidence is forgotten);
- **stuck open** when ``stuck_open_samples`` samples show the valve open while neither the
  coil is energised (``Cmd = 0``) nor the flight software commanded that thruster in its
  last ``quiet_cycles`` control periods (so a pulse's closing tail, up to ~10 ms after the
  coil switches off, is never taken for a stuck valve); a sample showing the valve closed
  and not commanded resets the count; samples taken while the thruster was commanded do
  not count either way.
Detection and isolation coincide (the evidence names the thruster).

Inputs: :meth:`on_valve_status` per THR_STATUS sample (booleans per thruster; ``Current``
is not used to classify: a coil drawing no current while commanded gives no thrust and is
counted as stuck closed by the ``Cmd``/``Open`` test); :meth:`on_command` the on-times the
flight software sent each cycle. Output: :class:`flight_sw.fdir.base.Verdict`.

Observability (the ICD samples the status at transmission, it does not latch): in
lockstep the sample at t_k shows the pulse commanded at t_{k−1} only if that pulse lasts
beyond t_k, i.e. on-times close to the full 20 ms period (saturated demand, e.g. during a
slew). Short pulses are invisible here and are the rate-residual strategy's business
(:mod:`flight_sw.fdir.rate_residual`). A stuck-open valve is open continuously and is
seen at every sample once the controller stops commanding it.

Assumptions: at most one status sample per control period is needed; the opening delay of
a healthy valve is shorter than the time from command reception to the next sample
(in lockstep ≈ 18.5 ms, valves open in a few ms); ``stuck_closed_samples`` ≥ 2 guards
against a pulse that starts just before a sample (realtime runs).

Sources: valve drive-electronics telemetry as used for thruster FDIR, e.g. Wertz & Larson
(eds.) 1999, "Space Mission Analysis and Design", 3rd ed. (health monitoring by
telemetry limits and persistence); the persistence-counter logic is standard FDIR
practice (ECSS-E-ST-70-11C, on-board monitoring with filters).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dbc import validation as check
from flight_sw.fdir.base import (
    NOTHING,
    FailureKind,
    ThrusterFailure,
    ThrusterFdirStrategy,
    Verdict,
)

_SOURCE = "ValveStatusParams"
MAX_THR_STATUS = 16  # THR_STATUS carries thrusters 0..15
STATUS_CMD = tuple(f"Cmd_T{k:02d}" for k in range(MAX_THR_STATUS))  # its signal names
STATUS_OPEN = tuple(f"Open_T{k:02d}" for k in range(MAX_THR_STATUS))
STATUS_CURRENT = tuple(f"Current_T{k:02d}" for k in range(MAX_THR_STATUS))


def status_flags(signals: Mapping[str, Any], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per thruster (the first ``min(n, 16)``): coil commanded, valve open, coil current, as
    boolean arrays from a decoded THR_STATUS frame (absent signals read as 0)."""
    k_max = min(n, MAX_THR_STATUS)
    cmd = np.array([bool(signals.get(STATUS_CMD[k], 0)) for k in range(k_max)])
    opened = np.array([bool(signals.get(STATUS_OPEN[k], 0)) for k in range(k_max)])
    current = np.array([bool(signals.get(STATUS_CURRENT[k], 0)) for k in range(k_max)])
    return cmd, opened, current


@dataclass(frozen=True)
class ValveStatusParams:
    """Persistence settings of the valve-telemetry FDIR (counts of THR_STATUS samples).

    Attributes:
        stuck_closed_samples: energised-but-closed samples that declare stuck closed (≥ 1).
        window_samples: evidence older than this many samples is forgotten (≥ 1).
        stuck_open_samples: open-while-not-commanded samples that declare stuck open (≥ 1).
        quiet_cycles: control periods without any command before an open valve counts (≥ 1).
    """

    stuck_closed_samples: int = 3
    window_samples: int = 50
    stuck_open_samples: int = 3
    quiet_cycles: int = 2

    def __post_init__(self) -> None:
        for key in ("stuck_closed_samples", "window_samples", "stuck_open_samples",
                    "quiet_cycles"):
            check.integer(_SOURCE, key, getattr(self, key), 1)


class ValveStatusFdir(ThrusterFdirStrategy):
    """Stuck-closed / stuck-open detection from THR_STATUS (see the module docstring)."""

    name = "valve_status"

    def __init__(self, n_thrusters: int, params: ValveStatusParams) -> None:
        check.integer("ValveStatusFdir", "n_thrusters", n_thrusters, 1)
        self.params = params
        self.n = n_thrusters
        self.reset()

    def reset(self) -> None:
        """Forget every observation and known failure."""
        n = self.n
        self._sample = 0
        self._closed_count = np.zeros(n, dtype=int)
        self._closed_last = np.full(n, -(10**9), dtype=int)
        self._open_count = np.zeros(n, dtype=int)
        self._recent_cmd: deque[np.ndarray] = deque(maxlen=self.params.quiet_cycles)
        self._known = np.zeros(n, dtype=bool)

    def on_command(self, t_ns: int, on_time_s: np.ndarray) -> None:
        """Remember which thrusters were commanded in the last ``quiet_cycles`` periods."""
        self._recent_cmd.append(np.asarray(on_time_s, dtype=float)[: self.n] > 0.0)

    def on_valve_status(
        self, t_ns: int, cmd: np.ndarray, opened: np.ndarray, current: np.ndarray
    ) -> None:
        """Update the per-thruster evidence counters with one THR_STATUS sample."""
        p = self.params
        cmd = np.asarray(cmd, dtype=bool)[: self.n]
        opened = np.asarray(opened, dtype=bool)[: self.n]
        self._sample += 1
        k = self._sample
        stale = k - self._closed_last > p.window_samples
        self._closed_count[stale] = 0
        closed_evidence = cmd & ~opened
        healthy_open = cmd & opened
        self._closed_count[healthy_open] = 0
        self._closed_count[closed_evidence] += 1
        self._closed_last[closed_evidence] = k
        commanded_lately = np.zeros(self.n, dtype=bool)
        for c in self._recent_cmd:
            commanded_lately |= c
        quiet = ~cmd & ~commanded_lately
        if len(self._recent_cmd) < p.quiet_cycles:
            quiet[:] = False  # not enough command history to tell a tail from a stuck valve
        self._open_count[quiet & opened] += 1
        self._open_count[quiet & ~opened] = 0

    def evaluate(self, t_ns: int) -> Verdict:
        """Declare the first thruster whose evidence reached its count (index order)."""
        p = self.params
        closed = (self._closed_count >= p.stuck_closed_samples) & ~self._known
        opened = (self._open_count >= p.stuck_open_samples) & ~self._known
        for k in range(self.n):
            if opened[k] or closed[k]:
                kind = FailureKind.STUCK_OPEN if opened[k] else FailureKind.STUCK_CLOSED
                failure = ThrusterFailure(k, kind, t_ns, t_ns, self.name)
                return Verdict(True, t_ns, failure)
        return NOTHING

    def set_failures(self, t_ns: int, failures: Sequence[ThrusterFailure]) -> None:
        """Stop watching the thrusters already isolated."""
        for f in failures:
            if 0 <= f.thruster < self.n:
                self._known[f.thruster] = True
                self._closed_count[f.thruster] = 0
                self._open_count[f.thruster] = 0
