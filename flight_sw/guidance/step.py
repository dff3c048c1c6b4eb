"""Step guidance: hold one attitude, then switch to a target attitude at a given time.

What it does: ``q_RN(t) = q_hold_RN`` for ``t < t_start_ns`` and ``q_target_RN`` from
``t_start_ns`` on, with zero reference rate and acceleration throughout: the classic
regulation / rest-to-rest slew reference (the control law does the slewing).

Inputs/outputs: see :mod:`flight_sw.guidance.base`; parameters ``q_hold_RN`` and
``q_target_RN`` (scalar-first, maps N to R; normalised here), ``t_start_ns`` [ns, on the
caller's time base].

Assumptions: the step itself is what the controller sees (no shaping); the caller picks
the hold attitude (e.g. the first estimated attitude).

Source: seed 003, simulation section (the three-axis referenced commands are "abruptly
varied w.r.t. time" from an initial attitude of 0, 0, 0 deg: step commands).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.guidance.base import QUATERNION_SIZE, VECTOR_SIZE, AttitudeReference
from flight_sw.quaternion import normalise

_SOURCE = "StepGuidance"


def _unit_quaternion(name: str, value: object) -> np.ndarray:
    arr = np.array(check.vector(_SOURCE, name, value, QUATERNION_SIZE))
    try:
        return normalise(arr)
    except ValueError:
        raise ConfigError(_SOURCE, name, value, "a non-zero quaternion") from None


@dataclass(frozen=True)
class StepGuidance:
    """Hold ``q_hold_RN`` before ``t_start_ns``, then ``q_target_RN``; zero rates.

    Attributes:
        q_hold_RN: attitude held before the step (scalar-first; normalised).
        q_target_RN: attitude from ``t_start_ns`` on (scalar-first; normalised).
        t_start_ns: time of the step [ns] (caller's time base).
    """

    q_hold_RN: np.ndarray
    q_target_RN: np.ndarray
    t_start_ns: int = 0
    _before: AttitudeReference = field(init=False, repr=False, compare=False)
    _after: AttitudeReference = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check.integer(_SOURCE, "t_start_ns", self.t_start_ns)
        hold = _unit_quaternion("q_hold_RN", self.q_hold_RN)
        target = _unit_quaternion("q_target_RN", self.q_target_RN)
        zero = np.zeros(VECTOR_SIZE)
        hold.setflags(write=False)
        target.setflags(write=False)
        object.__setattr__(self, "q_hold_RN", hold)
        object.__setattr__(self, "q_target_RN", target)
        object.__setattr__(self, "_before", AttitudeReference(hold, zero, zero))
        object.__setattr__(self, "_after", AttitudeReference(target, zero, zero))

    def reference(self, t_ns: int) -> AttitudeReference:
        """The hold attitude before ``t_start_ns``, the target from then on; zero rates."""
        return self._after if t_ns >= self.t_start_ns else self._before
