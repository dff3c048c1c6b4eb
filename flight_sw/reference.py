"""The manoeuvre the flight computer follows: a timed step, or a moving reference.

What it does: :class:`Timeline` is the scenario's manoeuvre (hold the attitude at start,
point at ``q_target_BN`` from ``t_start_ns`` on; hold a position in 6 DoF) on the
flight software's time base; :class:`References` turns it, or a moving reference
(:class:`flight_sw.guidance.base.AttitudeGuidance`), into what the control laws take each
cycle: the reference attitude ``q_RN``, its rate and angular acceleration in body axes
[rad/s, rad/s²] (``C_BR = C_BN C_NR`` applied to the guidance's R-axes values: the
feed-forward of the reference motion), and the position to hold [m, frame N] (the
configured target, else the first navigation fix).

Inputs: times [ns of the flight software's time base, ``time_base_ns`` = the flight
software's time of the bench's time 0], the estimated attitude ``q_BN``, navigation
positions [m]. Assumptions: unit quaternions. Source: project convention (the scenario's
``[manoeuvre]``, ``docs/scenarios.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flight_sw import vec3
from flight_sw.guidance.base import AttitudeGuidance
from flight_sw.quaternion import dcm


def _dcm(q: np.ndarray) -> vec3.Mat3:
    q0, q1, q2, q3 = np.asarray(q, dtype=float).tolist()
    return dcm(q0, q1, q2, q3)


def _to_body(c_BN: vec3.Mat3, c_RN: vec3.Mat3, x_R: np.ndarray) -> np.ndarray:
    """``C_BN C_RNᵀ x_R``: a reference-frame vector in body axes."""
    return np.array(vec3.mat_vec(c_BN, *vec3.mat_t_vec(c_RN, *vec3.vec3(x_R))))


@dataclass
class Timeline:
    """The manoeuvre: hold until ``t_start_ns``, then point at ``q_target_BN``.

    Times are relative to ``time_base_ns`` (the flight-software time of the bench's time 0:
    0 in lockstep, where the flight software runs on the bench's time). ``r_target_N_m``:
    the position to hold in 6 DoF (None: the first navigation fix).
    """

    q_target_BN: np.ndarray
    t_start_ns: int
    r_target_N_m: np.ndarray | None = None
    time_base_ns: int = 0


class References:
    """The reference of each cycle from a :class:`Timeline` or a guidance (module docstring).

    Keeps the attitude held before the step and the position held without a target; both
    are taken at their first use and forgotten by :meth:`clear` (a bench restart).
    """

    def __init__(self, timeline: Timeline, guidance: AttitudeGuidance | None) -> None:
        self.timeline = timeline
        self.guidance = guidance
        self._q_hold_BN: np.ndarray | None = None
        self._r_hold_N_m: np.ndarray | None = None

    def clear(self) -> None:
        """Forget the held attitude and position."""
        self._q_hold_BN = self._r_hold_N_m = None

    def attitude(
        self, t_ns: int, q_BN: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Reference attitude, rate and acceleration (the last two in body axes)."""
        tl = self.timeline
        if self.guidance is not None:
            ref = self.guidance.reference(t_ns - tl.time_base_ns)
            q_RN = np.asarray(ref.q_RN, dtype=float)
            # body axes: x_B = C_BN C_RNᵀ x_R (feed-forward of the reference motion), on
            # floats (numpy's 3×3 products go through the CPU's BLAS kernel)
            c_BN, c_RN = _dcm(q_BN), _dcm(q_RN)
            return (q_RN, _to_body(c_BN, c_RN, ref.omega_RN_R),
                    _to_body(c_BN, c_RN, ref.domega_RN_R))
        if t_ns - tl.time_base_ns >= tl.t_start_ns:
            return tl.q_target_BN, np.zeros(3), None
        if self._q_hold_BN is None:
            self._q_hold_BN = np.array(q_BN, dtype=float)
        return self._q_hold_BN, np.zeros(3), None

    def position(self, r_N_m: np.ndarray) -> np.ndarray:
        """The position to hold: the configured target, else the first navigation fix."""
        if self.timeline.r_target_N_m is not None:
            return self.timeline.r_target_N_m
        if self._r_hold_N_m is None:
            self._r_hold_N_m = r_N_m.copy()
        return self._r_hold_N_m
