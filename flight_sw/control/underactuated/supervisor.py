"""Seed 004's switching controller: Steps A to D in turn, from any state to rest (in progress).

What it does (seed 004 §3.1, Figure 3, with the x–y transfer made a step of its own):
1. **Step A** until single spin (axis III along the target z, transverse rates ~0);
2. **stop drift**: one of Step D's half-turn velocity sequences takes out the x–y velocity
   Step A left (``drift_tol_m_s``);
3. **transfer**: Step D's velocity sequences take x–y to the aim point at rest (their stop
   angle set far ahead, never reached);
4. **Step C**, coarse: picks the stop angle ψ_f (a whole turn of the target angle ψ_t = 0,
   at least ``stop_margin_turns`` ahead: the earliest whose stopping position
   Z = z − κ(ψ − ψ_f) it can move to 0 at its largest speed before that stop less
   ``stop_reserve_turns``) and moves Z within ``coarse_z_tol_m``, ending with the stopping
   velocity V_s ~ 0 (Step C sets V_s with Step B); if it is still at it
   ``final_reserve_turns`` before the stop, it picks a later stop;
5. **Step D** re-trims x–y; at the aim point at rest, a last, fine **Step C** (small kicks);
   then Step D stops the spin on ψ_f. If Step D has to stop a turn later (ψ_f − 2π), Z
   changed by 2πκ: back to a coarse Step C for that angle.
Every switch is kept with its time (:attr:`Supervisor.switches`) for the run's summary.
Legs 1–4 work on the test plant; leg 5 does not converge yet (docs/reproductions.md).

Inputs per cycle: time [s], ``q_BR`` (body relative to the target frame), ``omega_BN_B``
[rad/s], position and velocity in the target frame [m, m/s]. Output: the torque demand
in body axes [N m] (the three thrusts ≥ 0: each step's torque is one the thrusters make).
Source: seed 004 §3 (Steps A–D, eqs. 12–54).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np

from dbc import validation as check
from flight_sw.control.underactuated.geometry import ThreeThrusters
from flight_sw.control.underactuated.invariants import (
    TWO_PI,
    planned_stop_turn,
    spin_angle_rad,
    unwrap,
)
from flight_sw.control.underactuated.step_a import StepA, StepAParams, in_single_spin
from flight_sw.control.underactuated.step_b import StepB, StepBParams
from flight_sw.control.underactuated.step_c import Phase as PhaseC
from flight_sw.control.underactuated.step_c import StepC, StepCParams
from flight_sw.control.underactuated.step_d import Phase as PhaseD
from flight_sw.control.underactuated.step_d import StepD, StepDParams

_SOURCE = "[flight_sw.pose] underactuated"
FAR_TURNS = 10_000  # the transfer's stop angle: never reached
MAX_EXTRA_TURNS = 200  # Step C's search for a stop turn it can reach


class Mode(enum.Enum):
    """Which step runs."""

    A = "step A"
    STOP_DRIFT = "stop drift"
    TRANSFER = "transfer"
    C = "step C"
    D = "step D"
    DONE = "done"


@dataclass(frozen=True)
class SupervisorParams:
    """Each step's parameters; single-spin tolerances [rad, rad/s]; turns kept between
    Step C's start and the stop."""

    step_a: StepAParams = field(default_factory=StepAParams)
    step_b: StepBParams = field(default_factory=StepBParams)
    step_c: StepCParams = field(default_factory=StepCParams)
    step_d: StepDParams = field(default_factory=StepDParams)
    single_spin_tilt_rad: float = math.radians(0.05)
    single_spin_rate_rad_s: float = 1e-4
    stop_margin_turns: int = 16
    stop_reserve_turns: float = 10.0
    final_reserve_turns: float = 2.0
    coarse_z_tol_m: float = 0.3
    drift_tol_m_s: float = 2e-3

    def __post_init__(self) -> None:
        check.positive(_SOURCE, "single_spin_tilt_rad", self.single_spin_tilt_rad)
        check.positive(_SOURCE, "single_spin_rate_rad_s", self.single_spin_rate_rad_s)
        check.positive(_SOURCE, "drift_tol_m_s", self.drift_tol_m_s)
        check.positive(_SOURCE, "coarse_z_tol_m", self.coarse_z_tol_m)
        check.integer(_SOURCE, "stop_margin_turns", self.stop_margin_turns, lo=3)
        check.number(_SOURCE, "stop_reserve_turns", self.stop_reserve_turns, 2.0,
                     float(self.stop_margin_turns))
        check.number(_SOURCE, "final_reserve_turns", self.final_reserve_turns, 1.0,
                     self.stop_reserve_turns)


class Supervisor:
    """Seed 004's switching controller (module docstring)."""

    def __init__(self, thrusters: ThreeThrusters, params: SupervisorParams,
                 period_s: float) -> None:
        self.thr = thrusters
        self.p = params
        self.period_s = period_s
        self.step_a = StepA(thrusters, params.step_a)
        self.step_b = StepB(thrusters, self.step_a, params.step_b, period_s)
        self.step_c = StepC(self.step_b, params.step_c, period_s)
        self.step_d = StepD(thrusters, params.step_d, period_s)
        self.mode = Mode.A
        self.fine = False  # Step C's last, fine round (after the x–y transfer)
        self.psi_rad = 0.0
        #: (time [s], mode entered) for every switch
        self.switches: list[tuple[float, str]] = [(0.0, Mode.A.value)]

    def _switch(self, t_s: float, mode: Mode) -> None:
        self.mode = mode
        self.switches.append((t_s, mode.value))

    @staticmethod
    def _far(psi_rad: float) -> float:
        """A stop angle so far ahead that it is never reached (the transfer's)."""
        return TWO_PI * planned_stop_turn(psi_rad, 0.0, FAR_TURNS * TWO_PI)

    def _start_c(self, t_s: float, z_m: float, w3: float, first_turn: int) -> None:
        """Step C for the earliest stop turn, from ``first_turn`` on, whose stopping position
        it can move to 0 at its largest speed in the time left before that turn's final
        turn (less the reserve); the later the stop, the farther Z is (2πκ a turn) but the
        longer the time, so a speed above κ|ω_III| always finds one."""
        kappa, w = self.thr.kappa_m_s_per_rad_s, max(abs(w3), 1e-9)
        n = first_turn
        for n in range(first_turn, first_turn - MAX_EXTRA_TURNS, -1):
            psi_f = TWO_PI * n
            left_s = (self.psi_rad - psi_f - self.p.stop_reserve_turns * TWO_PI) / w
            z_stop = z_m - kappa * (self.psi_rad - psi_f)
            if left_s > 0.0 and abs(z_stop) <= self.p.step_c.max_speed_m_s * left_s:
                break
        self.step_c.start(TWO_PI * n, self.p.stop_reserve_turns, self.p.coarse_z_tol_m)
        self.fine = False
        self._switch(t_s, Mode.C)

    def torque_B_Nm(self, t_s: float, q_BR: np.ndarray, omega_BN_B: np.ndarray,
                    r_R_m: np.ndarray, v_R_m_s: np.ndarray) -> np.ndarray:
        """The torque demand this cycle [N m]."""
        self.psi_rad = unwrap(self.psi_rad, spin_angle_rad(q_BR))
        psi, w3 = self.psi_rad, float(omega_BN_B[2])
        hold = self.step_a
        if self.mode is Mode.A:
            if not hold.spinning_up and in_single_spin(q_BR, omega_BN_B,
                                                       self.p.single_spin_tilt_rad,
                                                       self.p.single_spin_rate_rad_s):
                self.step_d.start(self._far(psi), transfer=False)
                self._switch(t_s, Mode.STOP_DRIFT)
            else:
                return hold.torque_B_Nm(q_BR, omega_BN_B)
        if self.mode is Mode.STOP_DRIFT:
            if (self.step_d.phase is PhaseD.COAST
                    and float(np.linalg.norm(v_R_m_s[:2])) <= self.p.drift_tol_m_s):
                self.step_d.start(self._far(psi))
                self._switch(t_s, Mode.TRANSFER)
            else:
                t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
        if self.mode is Mode.TRANSFER:
            if (self.step_d.phase is PhaseD.COAST
                    and self.step_d.settled(r_R_m[:2], v_R_m_s[:2])):
                self._start_c(t_s, float(r_R_m[2]), w3, planned_stop_turn(
                    psi, 0.0, self.p.stop_margin_turns * TWO_PI))
            else:
                t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
        if self.mode is Mode.C:
            if (self.step_c.phase in (PhaseC.CHECK, PhaseC.COAST)
                    and psi - self.step_c.psi_f_rad < self.p.final_reserve_turns * TWO_PI):
                self._start_c(t_s, float(r_R_m[2]), w3, planned_stop_turn(
                    psi, 0.0, self.p.stop_margin_turns * TWO_PI))  # too late: a later stop
            torque = self.step_c.torque_B_Nm(t_s, q_BR, omega_BN_B, psi, float(r_R_m[2]),
                                             float(v_R_m_s[2]))
            if self.step_c.phase is not PhaseC.DONE:
                return torque
            self.step_d.start(self.step_c.psi_f_rad)
            self._switch(t_s, Mode.D)
        if self.mode is Mode.D:
            psi_f = self.step_d.psi_f_rad
            if (not self.fine and self.step_d.phase is PhaseD.COAST
                    and self.step_d.settled(r_R_m[:2], v_R_m_s[:2])):
                # at the aim point: the last, fine round of Step C (small kicks)
                self.step_c.start(psi_f, self.step_c.p.reserve_turns)
                self.fine = True
                self._switch(t_s, Mode.C)
                return self.step_c.torque_B_Nm(t_s, q_BR, omega_BN_B, psi, float(r_R_m[2]),
                                               float(v_R_m_s[2]))
            t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
            if self.step_d.psi_f_rad != psi_f:  # a turn later: Z moved by 2πκ
                self._start_c(t_s, float(r_R_m[2]), w3,
                              round(self.step_d.psi_f_rad / TWO_PI))
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR))
            if self.step_d.phase is PhaseD.DONE:
                self._switch(t_s, Mode.DONE)
                return np.array([0.0, 0.0, t3])  # the last sliver of spin
            return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
        return np.zeros(3)
