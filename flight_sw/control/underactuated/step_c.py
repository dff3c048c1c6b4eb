"""Step C: set the stopping position with Step B's sequences, for the planned stop angle.

What it does: with the stop angle ψ_f fixed (the supervisor's choice of turn), the z at
which the spin will stop is ``Z = z − κ (ψ − ψ_f)`` (eqs. 28–32 with ψ_t = ψ_f: the
paper's target turn folded into the angle), and in single spin ``Ż = V_s`` (the stopping
velocity, eq. 21). So Z is moved by giving V_s a value for a while: Step C repeats
- **go**: Step B sets ``V_s = u``, ``u = −Z / T`` limited to ``max_speed_m_s``, with T the
  move time or, if shorter, the time left before the stop less ``reserve_turns`` turns;
- **coast**: Step A's hold while Z moves at u; the kicks that will take u out are planned
  once (:func:`.disturbance.plan_kick`: their shape does not depend on the spin angle),
  and the first starts when Z plus the shift they and the settles between them make
  (:meth:`StepC.stop_shift_m`) reaches 0;
- **stop**: Step B sets ``V_s = 0``;
until |Z| ≤ ``position_tol_m`` or no round fits before the stop (``out_of_turns``: Z is
left as it is; each round takes what the last one left; seed 004 §3.4
repeats its sequences the same way, with the remainder form of eq. 35 keeping the
target continuous, which fixing ψ_f does here).

:func:`choose_stop_turn` picks the stop turn for the supervisor: the earliest whose Z
can reach 0 in time, riding the stopping velocity the body already has when that does.

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
from flight_sw.control.underactuated.invariants import (
    SPIN_FLOOR_RAD_S,
    TWO_PI,
    stopping_position_m,
)
from flight_sw.control.underactuated.step_b import Phase as PhaseB
from flight_sw.control.underactuated.step_b import StepB

_SOURCE = "[flight_sw.pose] step C"
MIN_SPEED_TOLS = 4.0  # the least going speed, in Step B's velocity tolerances


def choose_stop_turn(psi_rad: float, z_m: float, omega_III_rad_s: float,
                     v_stop_m_s: float, kappa_m: float, first_turn: int,
                     reserve_turns: float, max_speed_m_s: float,
                     max_extra_turns: int = 200) -> tuple[int, float | None]:
    """The stop turn n (ψ_f = 2πn, from ``first_turn`` on, later turns being lower: a
    negative spin) for Step C: the earliest whose stopping position Z_n = z − κ(ψ − 2πn)
    can reach 0 in the time left before that stop less ``reserve_turns``, carried there by
    the stopping velocity the body already has (no kick to go: returned with its move time
    −Z_n/V_s [s]) or else at ``max_speed_m_s`` (move time None: Step C's own). Z_n falls
    by 2πκ a turn later while the time grows by 2π/|ω_III|, so a speed above κ|ω_III|
    always finds one; past ``max_extra_turns`` the last turn tried is returned (move time
    None: Step C then moves Z at its largest speed and the supervisor's late check
    follows)."""
    w = max(abs(omega_III_rad_s), SPIN_FLOOR_RAD_S)
    n = first_turn
    for n in range(first_turn, first_turn - max_extra_turns, -1):
        left_s = (psi_rad - TWO_PI * n - reserve_turns * TWO_PI) / w
        z_stop = stopping_position_m(z_m, psi_rad, TWO_PI * n, kappa_m)
        if left_s <= 0.0:
            continue
        if (z_stop * v_stop_m_s < 0.0 and abs(v_stop_m_s) <= max_speed_m_s
                and -z_stop / v_stop_m_s <= left_s):
            return n, -z_stop / v_stop_m_s
        if abs(z_stop) <= max_speed_m_s * left_s:
            return n, None
    return n, None


class Phase(enum.Enum):
    """What Step C is doing."""

    CHECK = "check"
    GO = "go"
    COAST = "coast"
    STOP = "stop"
    DONE = "done"


@dataclass(frozen=True)
class StepCParams:
    """Tolerance on Z [m], time to move it [s], largest stopping velocity used [m/s], the
    time Step A's settle takes after a kick [s] (for the stop's shift of Z), the
    tolerance on the going V_s as a fraction of it, the turns a round keeps for its kicks
    and Step D's final turn (the coast is what is left before the stop)."""

    position_tol_m: float = 0.005
    move_time_s: float = 120.0
    max_speed_m_s: float = 0.08
    settle_s: float = 12.0
    go_tol_fraction: float = 0.1
    reserve_turns: float = 4.0

    def __post_init__(self) -> None:
        for key in ("position_tol_m", "move_time_s", "max_speed_m_s", "settle_s",
                    "go_tol_fraction", "reserve_turns"):
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
        self.reserve_turns = params.reserve_turns
        self.tol_m = params.position_tol_m
        self.move_time_s = params.move_time_s
        self.rounds = 0
        #: the last round found no time left before the stop (Z left as it was)
        self.out_of_turns = False
        self._shift_m = 0.0
        self._sign = 0.0

    def start(self, psi_f_rad: float, reserve_turns: float | None = None,
              tol_m: float | None = None, move_time_s: float | None = None) -> None:
        """Begin moving Z to within ``tol_m`` of 0 for a spin that stops at ``psi_f_rad``
        (unwrapped), its first round keeping ``reserve_turns`` before the stop and taking
        ``move_time_s`` (defaults: the parameters')."""
        self.psi_f_rad = check.number(_SOURCE, "psi_f_rad", psi_f_rad)
        self.reserve_turns = (self.p.reserve_turns if reserve_turns is None
                              else check.positive(_SOURCE, "reserve_turns", reserve_turns))
        self.tol_m = (self.p.position_tol_m if tol_m is None
                      else check.positive(_SOURCE, "tol_m", tol_m))
        self.move_time_s = (self.p.move_time_s if move_time_s is None
                            else check.positive(_SOURCE, "move_time_s", move_time_s))
        self.rounds = 0
        self.out_of_turns = False
        self.phase = Phase.CHECK

    def z_stop_m(self, z_m: float, psi_rad: float) -> float:
        """Z for the planned stop angle [m]."""
        return stopping_position_m(z_m, psi_rad, self.psi_f_rad, self.thr.kappa_m_s_per_rad_s)

    def stop_shift_m(self, w3: float, psi_rad: float, v_stop_m_s: float) -> float:
        """How far Z moves while Step B takes ``v_stop_m_s`` out: the kicks it will plan
        (each at most the disturbance's largest change, each shifting Z by its plan) and
        the settles between them (``settle_s`` each) [m]."""
        shift, v = 0.0, v_stop_m_s
        largest = self.b.p.disturbance.max_dv_stop_m_s
        while abs(v) > self.b.p.velocity_tol_m_s:
            kick = plan_kick(self.thr, self.b.p.disturbance, self.period_s, w3, psi_rad, -v)
            shift += kick.z_stop_shift_m(v)
            v += kick.dv_stop_m_s
            shift += v * self.p.settle_s
            if abs(kick.dv_stop_m_s) < largest:
                break  # the last kick takes what is left
        return shift

    def torque_B_Nm(self, t_s: float, q_BR: np.ndarray, omega_BN_B: np.ndarray,
                    psi_rad: float, z_m: float, v_z_m_s: float) -> np.ndarray:
        """The torque demand this cycle [N m]."""
        z_stop = self.z_stop_m(z_m, psi_rad)
        if self.phase is Phase.CHECK:
            if abs(z_stop) <= self.tol_m:
                self.phase = Phase.DONE
            else:
                w = max(abs(float(omega_BN_B[2])), SPIN_FLOOR_RAD_S)
                first = self.rounds == 0
                reserve = self.reserve_turns if first else self.p.reserve_turns
                move_s = self.move_time_s if first else self.p.move_time_s
                coast_s = (psi_rad - self.psi_f_rad - reserve * TWO_PI) / w
                if coast_s < self.p.settle_s:
                    self.phase = Phase.DONE  # no turns left for a round: Z as it is
                    self.out_of_turns = True
                    return self.b.hold.track(omega_BN_B, self.b.hold.pointing_rate(q_BR))
                u = -z_stop / min(move_s, coast_s)
                # at least a few of Step B's tolerances, so that the go is a real change
                u = math.copysign(min(self.p.max_speed_m_s, max(
                    abs(u), MIN_SPEED_TOLS * self.b.p.velocity_tol_m_s)), u)
                # going: a coarse V_s will do (Z is measured, the stop is timed on it)
                self.b.start(u, max(self.b.p.velocity_tol_m_s, self.p.go_tol_fraction * abs(u)))
                self.phase, self._sign = Phase.GO, math.copysign(1.0, z_stop)
                self.rounds += 1
        if self.phase is Phase.GO:
            torque = self.b.torque_B_Nm(t_s, q_BR, omega_BN_B, psi_rad, v_z_m_s)
            if self.b.phase is not PhaseB.DONE:
                return torque
            self._shift_m = self.stop_shift_m(float(omega_BN_B[2]), psi_rad,
                                              self.b.v_stop_m_s)
            self.phase = Phase.COAST
        if self.phase is Phase.COAST:
            if self._sign * (z_stop + self._shift_m) <= self.tol_m:
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
