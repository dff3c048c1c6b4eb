"""Quaternion PID attitude control: the quaternion PD law plus a bounded integral term.

What it does: ``τ_B = τ_PD − K_p ∘ x_I`` with ``τ_PD`` the quaternion PD law of
:mod:`flight_sw.control.quaternion_pd` (same gains, same short-way sign and slew-rate
limit) and ``x_I`` the integral of the short-way error vector ``sgn(δq0) δq_vec`` divided
by ``integral_time_s`` (T_i, the classic PID form ``K_p (e + (1/T_i)∫e dt)``).
Why: a constant disturbance torque d leaves the PD law with a steady error ``δq = d/K_p``;
after a thruster fault the allocator's model of the remaining thrusters is never perfect
(pulse-shape losses of the countering thrusters under a stuck-open one amount to a few %
of its wrench), and the integral removes that offset.
Anti-windup (both needed with on-off thrusters and large slews): the error is integrated
only while the error angle is below ``integral_band_rad`` (conditional integration: not
during a slew), and the integral torque ``K_p ∘ x_I`` is clamped per axis to
``max_integral_torque_Nm``.

Inputs/outputs: as :class:`flight_sw.control.base.AttitudeController`; ``t_ns`` is used
(the integral's time step is the difference of consecutive calls' ``t_ns``; the first call
and any step back or longer than ``MAX_STEP_S`` integrate nothing). Torque [N m], body axes.

Assumptions: as the PD law; the disturbance is constant or slow compared with T_i.

Sources: the PD part: Wie & Barba 1985 (JGCD 8(3) 360–365), Wie 2008, "Space Vehicle
Dynamics and Control", 2nd ed., ch. 7 (quaternion feedback, with an integral term for
constant disturbances); PID form and conditional integration / clamping anti-windup:
Åström & Hägglund 2006, "Advanced PID Control", ISA, ch. 3 (integrator windup).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.control.quaternion_pd import QuaternionPd, QuaternionPdParams
from flight_sw.quaternion import error_quaternion, rotation_angle_rad

NS_PER_S = 1_000_000_000
MAX_STEP_S = 1.0  # a longer gap between calls (a restart, a stall) integrates nothing
_SOURCE = "QuaternionPidParams"


@dataclass(frozen=True)
class QuaternionPidParams:
    """The PD gains plus the integral settings.

    Attributes:
        pd: the quaternion PD gains and slew-rate limit.
        integral_time_s: T_i [s] (> 0).
        integral_band_rad: integrate only below this error angle [rad] (> 0).
        max_integral_torque_Nm: per-axis clamp of the integral torque [N m] (> 0).
    """

    pd: QuaternionPdParams
    integral_time_s: float
    integral_band_rad: float
    max_integral_torque_Nm: float

    def __post_init__(self) -> None:
        s = _SOURCE
        check.instance(s, "pd", self.pd, QuaternionPdParams)
        check.positive(s, "integral_time_s", self.integral_time_s, unit="s")
        check.positive(s, "integral_band_rad", self.integral_band_rad, unit="rad")
        check.limit(s, "max_integral_torque_Nm", self.max_integral_torque_Nm, unit="N m")


class QuaternionPid:
    """Quaternion PID controller (implements ``AttitudeController``); keeps its integral."""

    def __init__(self, params: QuaternionPidParams) -> None:
        self._params = params
        self._pd = QuaternionPd(params.pd)
        self._kp = np.array(params.pd.kp_Nm, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            lim = params.max_integral_torque_Nm / self._kp
        self._x_limit = np.where(np.isfinite(lim), lim, np.inf)
        self.x_integral = np.zeros(3)
        self._t_last_ns: int | None = None

    @property
    def params(self) -> QuaternionPidParams:
        """The settings this controller was built with."""
        return self._params

    def reset(self) -> None:
        """Forget the integral."""
        self.x_integral = np.zeros(3)
        self._t_last_ns = None

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """``τ_PD − K_p ∘ x_I`` [N m] (see the module docstring)."""
        p = self._params
        dq = error_quaternion(q_RN, q_BN)
        dt_s = 0.0 if self._t_last_ns is None else (t_ns - self._t_last_ns) / NS_PER_S
        self._t_last_ns = t_ns
        if 0.0 < dt_s <= MAX_STEP_S and rotation_angle_rad(dq) < p.integral_band_rad:
            e = (-1.0 if dq[0] < 0.0 else 1.0) * dq[1:]
            self.x_integral = np.clip(
                self.x_integral + e * dt_s / p.integral_time_s, -self._x_limit, self._x_limit
            )
        tau = self._pd.torque_B_Nm(t_ns, q_BN, omega_BN_B, q_RN, omega_RN_B)
        return tau - self._kp * self.x_integral
