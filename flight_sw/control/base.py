"""The attitude controller interface: estimated and reference attitude/rate in, body torque out.

What it does: defines :class:`AttitudeController`, the one interface every attitude
control strategy implements.

Inputs: ``t_ns`` [integer ns, the caller's time base; strategies without memory ignore
it]; ``q_BN`` the (estimated) attitude, scalar-first, maps inertial N to body B;
``omega_BN_B`` the (estimated) body rate of B relative to N in body axes [rad/s];
``q_RN`` the reference attitude (maps N to the reference frame R); ``omega_RN_B`` the
reference rate of R relative to N expressed in body axes [rad/s] (zero for regulation or
a slew to a fixed attitude).
Output: the demanded control torque about the centre of mass in body axes [N m], shape (3,).

Assumptions: unit quaternions; the caller expresses the reference rate in body axes
(``omega_RN_B = C(q_BR) omega_RN_R``); actuator limits are the allocator's business.

Source: interface only; conventions as in :mod:`flight_sw.quaternion`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class AttitudeController(Protocol):
    """An attitude control law producing a body torque demand."""

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
    ) -> np.ndarray:
        """The demanded torque in body axes [N m], shape (3,)."""
        ...
