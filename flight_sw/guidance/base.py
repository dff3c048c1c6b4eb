"""The attitude guidance interface: time in, reference attitude, rate and acceleration out.

What it does: defines :class:`AttitudeGuidance`, the one interface every guidance
(reference-trajectory) strategy implements, and :class:`AttitudeReference`, its immutable
output.

Inputs: ``reference(t_ns)``: the time [integer ns] on the caller's time base (the flight
computer passes the time since its time base; each strategy documents its own origin).
Output: :class:`AttitudeReference`: ``q_RN`` the reference attitude (scalar-first, maps
inertial N to the reference frame R), ``omega_RN_R`` the rate of R relative to N in R axes
[rad/s], ``domega_RN_R`` its time derivative in R axes [rad/s²] (the derivative of
``ω_RN`` is the same taken in N or in R, since ``ω_RN × ω_RN = 0``).

Assumptions: strategies are pure functions of time (no state, no clock reads); a caller
that wants the rates in body axes maps them with ``C_BR = C(q_BN) C(q_RN)ᵀ``.

Source: interface only; conventions as in :mod:`flight_sw.quaternion`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError

QUATERNION_SIZE = 4
VECTOR_SIZE = 3

_SOURCE = "AttitudeReference"


def _frozen(name: str, value: object, size: int) -> np.ndarray:
    """``value`` as a read-only float array of ``size`` finite numbers (ConfigError else).

    The array test runs first (every cycle builds a reference); the validator only words
    the error.
    """
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.zeros(0)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        check.vector(_SOURCE, name, value, size)  # raises, naming the field
        raise ConfigError(_SOURCE, name, value, f"{size} finite numbers")  # e.g. a bool
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class AttitudeReference:
    """One reference sample (arrays are read-only float copies).

    Attributes:
        q_RN: reference attitude, scalar-first, maps N to R (unit norm).
        omega_RN_R: rate of R relative to N, R axes [rad/s].
        domega_RN_R: angular acceleration of R relative to N, R axes [rad/s²].
    """

    q_RN: np.ndarray
    omega_RN_R: np.ndarray
    domega_RN_R: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "q_RN", _frozen("q_RN", self.q_RN, QUATERNION_SIZE))
        object.__setattr__(self, "omega_RN_R", _frozen("omega_RN_R", self.omega_RN_R, VECTOR_SIZE))
        object.__setattr__(
            self, "domega_RN_R", _frozen("domega_RN_R", self.domega_RN_R, VECTOR_SIZE)
        )


class AttitudeGuidance(Protocol):
    """A reference attitude trajectory."""

    def reference(self, t_ns: int) -> AttitudeReference:
        """The reference at time ``t_ns`` [ns]."""
        ...
