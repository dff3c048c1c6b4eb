"""The interface of an environment model: an external wrench as a function of time and attitude.

``EnvironmentModel.wrench_B(t_s, q_BN, mp)`` returns (fx, fy, fz, tx, ty, tz): force [N]
and torque about the centre of mass [N·m] in body axes, at simulation time ``t_s`` [s]
for the attitude ``q_BN`` (scalar first, N = the inertial frame I) and the current mass
properties ``mp``. Pure: no clock, no state. The plant adds it to the thrusters' wrench
at every RK4 stage (``bench.station.dynamics.stepper``).
"""

from __future__ import annotations

from typing import Protocol

from bench.station.dynamics.rigid_body import MassProperties, Quat, Wrench


class EnvironmentModel(Protocol):
    """An external wrench on the vehicle (module docstring)."""

    def wrench_B(self, t_s: float, q_BN: Quat, mp: MassProperties) -> Wrench:
        """Force [N] and torque [N·m] in body axes at ``t_s`` [s]."""
        ...
