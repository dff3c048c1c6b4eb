"""The attitude estimator interface: gyro samples and star-tracker quaternions in, estimate out.

What it does: defines :class:`AttitudeEstimator` (the one interface every estimation
strategy implements) and :class:`AttitudeEstimate` (its immutable output).

Inputs: ``propagate(t_ns, omega_meas_B)``: one gyro sample, the measured body rate of B
relative to N in body axes [rad/s], raw (bias included), taken at time ``t_ns`` [integer ns
of the flight software's time base]; ``update_star_tracker(t_ns, q_meas_BN)``: one
star-tracker attitude sample (scalar-first, maps N to B) taken at ``t_ns``.
Output: ``estimate()`` -> :class:`AttitudeEstimate` at the filter's current time.

Assumptions: samples arrive in time order per sensor (an out-of-order sample is the
strategy's to ignore; see its docstring); time is only what the caller passes, never a clock.

Source: interface only; the quaternion and frame conventions are those of
:mod:`flight_sw.quaternion`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True, slots=True)
class AttitudeEstimate:
    """One attitude estimate (arrays are read-only copies).

    Attributes:
        t_ns: the time the estimate refers to [ns]; ``None`` before any sample.
        q_BN: attitude, scalar-first, maps N to B (identity before initialisation).
        omega_BN_B: bias-corrected body rate of the newest gyro sample, body axes [rad/s].
        gyro_bias_B_rad_s: estimated gyro bias, body axes [rad/s].
        covariance_diag: diagonal of the error covariance, strategy-defined order (for the
            MEKF: attitude error [rad²] ×3, then gyro bias [(rad/s)²] ×3).
        initialised: False until the attitude has been set from a measurement.
    """

    t_ns: int | None
    q_BN: np.ndarray
    omega_BN_B: np.ndarray
    gyro_bias_B_rad_s: np.ndarray
    covariance_diag: np.ndarray
    initialised: bool


class AttitudeEstimator(Protocol):
    """An attitude estimator driven by gyro samples and star-tracker quaternions."""

    def propagate(self, t_ns: int, omega_meas_B: np.ndarray) -> None:
        """Take one gyro sample (raw body rate [rad/s] at ``t_ns``) and propagate to ``t_ns``."""
        ...

    def update_star_tracker(self, t_ns: int, q_meas_BN: np.ndarray) -> None:
        """Take one star-tracker quaternion ``q_meas_BN`` measured at ``t_ns``."""
        ...

    def estimate(self) -> AttitudeEstimate:
        """The current estimate."""
        ...


class InertiaIdentifier(Protocol):
    """Identifies the inertia from body rates and the torque applied (e.g. RLS, seed 001 §2).

    Called once per control cycle with the estimated body rate [rad/s] and the torque
    [N m] applied over the period that just ended; returns the current 3×3 estimate
    [kg m²] (body axes, about the centre of mass), or None while not yet excited enough
    or while the estimate is the inertia of no body (a principal moment above the sum of
    the other two).
    """

    @property
    def n_updates(self) -> int:
        """Estimation steps taken so far."""
        ...

    @property
    def n_unphysical(self) -> int:
        """Calls of ``update`` (cycles) whose estimate was withheld as no body's inertia."""
        ...

    def update(
        self, t_ns: int, omega_BN_B: np.ndarray, torque_B_Nm: np.ndarray
    ) -> np.ndarray | None:
        """Take one sample; the current inertia estimate or None."""
        ...
