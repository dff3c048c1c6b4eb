"""Step C: set the stopping position with Step B's sequences, for the planned stop angle.

What it does: with the stop angle ψ_f fixed (the supervisor's choice of turn), the z at
which the spin will stop is ``Z = z − κ (ψ − ψ_f)`` (eqs. 28–32 with ψ_t = ψ_f: the
paper's target turn folded into the angle), and in single spin ``Ż = V_s`` (the stopping
velocity, eq. 21). So Z is moved by giving V_s a value for a while: Step C repeats
- **go**: Step B sets ``V_s = u``, ``u = −Z / move_time_s`` limited to ``max_speed_m_s``;
- **coast**: Step A's hold while Z moves at u; the kick that will take u out is planned
  once (:func:`.disturbance.plan_kick`: its shape does not depend on the spin angle), and
  it starts when Z plus the shift that kick itself makes (:meth:`Kick.z_stop_shift_m`)
  reaches 0;
- **stop**: Step B sets ``V_s = 0``;
until |Z| ≤ ``position_tol_m`` (each round takes what the last one left; seed 004 §3.4
repeats its sequences the same way, with the remainder form of eq. 35 keeping the
target continuous, which fixing ψ_f does here).

Inputs per cycle: time [s], ``q_BR``, ``omega_BN_B`` [rad/s], ψ (unwrapped) [rad], z and
v_z in the target frame [m, m/s]. Output: the torque demand in body axes [N m].
Source: seed 004 §3.4 (eqs. 28–38).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.control.underactuated.disturbance import plan_kick
from flight_sw.control.underactuated.invariants import stopping_position_m
from flight_sw.control.underactuated.step_b import Phase as PhaseB
from flight_sw.control.underactuated.step_b import StepB

_SOURCE = "[flight_sw.pose] step C"


class Phase(enum.Enum):
    """What Step C is doing."""

    CHECK = "check"
    GO = "go"
    COAST = "coast"
    STOP = "stop"
    DONE = "done"


@dataclass(frozen=True)
class StepCParams:
    """Tolerance on Z [m], time to move it [s], largest stopping velocity used [m/s]."""

    position_tol_m: float = 0.005
    move_time_s: float = 120.0
    max_speed_m_s: float = 0.02

    def __post_init__(self) -> None:
        for key in ("position_tol_m", "move_time_s", "max_speed_m_s"):
            check.positive(_SOURCE, key, getattr(self, key))


class StepC:
    """Step C's rounds (module docstring)."""

    def __init__(self, step_b: StepB, params: StepCParams, period_s: float) -> None:
        self.b = step_b
        self.thr = step_b.thr
        self.p = params
        self.period_s = period_s
        self.phase = Phase.DONE
        self.psi_f_rad = 0.0
        self.rounds = 0
        self._shift_m = 0.0
        self._sign = 0.0

    def start(self, psi_f_rad: float) -> None:
        """Begin moving Z to 0 for a spin that stops at ``psi_f_rad`` (unwrapped)."""
        self.psi_f_rad = check.number(_SOURCE, "psi_f_rad", psi_f_rad)
        self.phase = Phase.CHECK

    def z_stop_m(self, z_m: float, psi_rad: float) -> float:
        """Z for the planned stop angle [m]."""
        return stopping_position_m(z_m, psi_rad, self.psi_f_rad, self.thr.kappa_m_s_per_rad_s)

    def torque_B_Nm(self, t_s: float, q_BR: np.ndarray, omega_BN_B: np.ndarray,
                    psi_rad: float, z_m: float, v_z_m_s: float) -> np.ndarray:
        """The torque demand this cycle [N m]."""
        z_stop = self.z_stop_m(z_m, psi_rad)
        if self.phase is Phase.CHECK:
            if abs(z_stop) <= self.p.position_tol_m:
                self.phase = Phase.DONE
            else:
                u = -z_stop / self.p.move_time_s
                self.b.start(max(-self.p.max_speed_m_s, min(self.p.max_speed_m_s, u)))
                self.phase, self._sign = Phase.GO, math.copysign(1.0, z_stop)
                self.rounds += 1
        if self.phase is Phase.GO:
            torque = self.b.torque_B_Nm(t_s, q_BR, omega_BN_B, psi_rad, v_z_m_s)
            if self.b.phase is not PhaseB.DONE:
                return torque
            v_stop = self.b.v_stop_m_s
            stop = plan_kick(self.thr, self.b.p.disturbance, self.period_s,
                             float(omega_BN_B[2]), psi_rad, -v_stop)
            self._shift_m = stop.z_stop_shift_m(v_stop)
            self.phase = Phase.COAST
        if self.phase is Phase.COAST:
            if self._sign * (z_stop + self._shift_m) <= self.p.position_tol_m:
                self.b.start(0.0)
                self.phase = Phase.STOP
            else:
                return self.b.hold.track(omega_BN_B, self.b.hold.pointing_rate(q_BR))
        if self.phase is Phase.STOP:
            torque = self.b.torque_B_Nm(t_s, q_BR, omega_BN_B, psi_rad, v_z_m_s)
            if self.b.phase is not PhaseB.DONE:
                return torque
            self.phase = Phase.CHECK
        return self.b.hold.track(omega_BN_B, self.b.hold.pointing_rate(q_BR))
