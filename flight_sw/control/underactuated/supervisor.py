"""Seed 004's switching controller: Steps A to D in turn, from rest to rest at the target.

What it does (seed 004 §3.1, Figure 3, with the x–y transfer made a step of its own):
1. **Step A** until single spin (axis III along the target z, transverse rates ~0);
2. **stop drift**: one of Step D's half-turn velocity sequences takes out the x–y velocity
   Step A left (``drift_tol_m_s``);
3. **transfer, with Step C alongside**: Step D's velocity sequences take x–y to the aim
   point at rest (their stop angle set far ahead, never reached) while Step C moves the
   stopping position Z = z − κ(ψ − ψ_f) to 0 within ``z_tol_m`` and ends with the
   stopping velocity V_s ~ 0. The two do not disturb each other: the axis-III torque
   leaves V_s and Z as they are (eqs. 21–22) and Step C's kicks leave the x–y velocity
   unchanged to first order; Step D waits during a kick (and re-plans a sequence whose
   start angle the kick passed), Step C during a velocity sequence. The stop angle ψ_f
   (a whole turn of the target angle ψ_t = 0) is chosen at the transfer's start: the
   earliest, at least the transfer's expected turns plus ``stop_reserve_turns`` ahead,
   whose Z can reach 0 before that stop less the reserve, riding the stopping velocity
   Step A left when it carries Z there in time (no kick to go), else at Step C's largest
   speed (:func:`.step_c.choose_stop_turn`). With κ = 0.285 m the body moves 2πκ = 1.8 m
   in z a turn while it spins, so Z must move tens of metres: done alongside the
   transfer's hundreds of seconds, not after them. If Step C is still moving Z
   ``final_reserve_turns`` before the stop, or finds no time left for a round with Z
   outside its tolerance, a later stop is picked (Step C's own reserve kept);
4. **Step D** waits at the aim point and stops the spin on ψ_f with its final turn. If
   Step D has to stop a turn later (ψ_f − 2π), Z changed by 2πκ: a coarse Step C
   (``coarse_z_tol_m``) toward the earliest turn from that one it can reach with its own
   reserve, Step D's re-trim and a fine Step C follow (a fallback: no case takes it).
Every switch is kept with its time (:attr:`Supervisor.switches`) for the run's summary.
From rest at seed 004's three cases it ends at rest on the target on the test plant
(docs/reproductions.md).

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
    stopping_velocity_m_s,
    unwrap,
)
from flight_sw.control.underactuated.step_a import StepA, StepAParams, in_single_spin
from flight_sw.control.underactuated.step_b import Phase as PhaseB
from flight_sw.control.underactuated.step_b import StepB, StepBParams
from flight_sw.control.underactuated.step_c import Phase as PhaseC
from flight_sw.control.underactuated.step_c import StepC, StepCParams, choose_stop_turn
from flight_sw.control.underactuated.step_d import Phase as PhaseD
from flight_sw.control.underactuated.step_d import StepD, StepDParams

_SOURCE = "[flight_sw.pose] underactuated"
FAR_TURNS = 10_000  # the transfer's stop angle: never reached
MAX_RESERVE_TURNS = 200.0  # a reserve beyond this is a configuration error
LATER_STOP_EXTRA_TURNS = 2.0  # a later stop: Step C's reserve plus these turns ahead


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
    """Each step's parameters; single-spin tolerances [rad, rad/s]; turns kept after the
    transfer's expected end before the stop, and the turns before the stop at which a
    Step C still moving Z picks a later one; Z tolerances [m] (coarse: after a later stop
    was picked; fine: alongside the transfer); the drift left by Step A [m/s]."""

    step_a: StepAParams = field(default_factory=StepAParams)
    step_b: StepBParams = field(default_factory=StepBParams)
    step_c: StepCParams = field(default_factory=StepCParams)
    step_d: StepDParams = field(default_factory=StepDParams)
    single_spin_tilt_rad: float = math.radians(0.05)
    single_spin_rate_rad_s: float = 1e-4
    stop_reserve_turns: float = 20.0
    final_reserve_turns: float = 2.0
    coarse_z_tol_m: float = 0.3
    z_tol_m: float = 0.0075
    drift_tol_m_s: float = 2e-3

    def __post_init__(self) -> None:
        check.positive(_SOURCE, "single_spin_tilt_rad", self.single_spin_tilt_rad)
        check.positive(_SOURCE, "single_spin_rate_rad_s", self.single_spin_rate_rad_s)
        check.positive(_SOURCE, "drift_tol_m_s", self.drift_tol_m_s)
        check.positive(_SOURCE, "coarse_z_tol_m", self.coarse_z_tol_m)
        check.positive(_SOURCE, "z_tol_m", self.z_tol_m)
        check.number(_SOURCE, "stop_reserve_turns", self.stop_reserve_turns, 2.0,
                     MAX_RESERVE_TURNS)
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
        self.fine = False  # Step C's tolerance is z_tol_m (else coarse_z_tol_m)
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

    def _transfer_turns(self, w3: float, r_xy: np.ndarray) -> float:
        """The turns the x–y transfer is expected to take: the distance to the aim point
        at the transfer speed, plus a lead time at each end [turns]."""
        dp = self.step_d.p
        dist_m = float(np.linalg.norm(self.step_d.aim_m() - r_xy))
        time_s = dist_m / dp.max_transfer_speed_m_s + 2.0 * self.step_d.lead_s(w3)
        return abs(w3) * time_s / TWO_PI

    def _start_c(self, t_s: float, z_m: float, w3: float, v_stop_m_s: float,
                 first_turn: int, mode: Mode, reserve_turns: float | None = None) -> None:
        """Step C toward the stop turn :func:`.step_c.choose_stop_turn` picks from
        ``first_turn`` on, ``reserve_turns`` kept (default ``stop_reserve_turns``: the
        transfer's start; a later stop keeps Step C's own reserve)."""
        reserve = self.p.stop_reserve_turns if reserve_turns is None else reserve_turns
        n, move_s = choose_stop_turn(self.psi_rad, z_m, w3, v_stop_m_s,
                                     self.thr.kappa_m_s_per_rad_s, first_turn, reserve,
                                     self.p.step_c.max_speed_m_s)
        # alongside the transfer Step C goes to its own (fine) tolerance: the transfer
        # re-trims x–y after each of its rounds
        fine = mode is Mode.TRANSFER
        self.step_c.start(TWO_PI * n, reserve, self.p.z_tol_m if fine else self.p.coarse_z_tol_m,
                          move_s)
        self.fine = fine
        if mode is not self.mode:
            self._switch(t_s, mode)

    def _replan_if_late(self, t_s: float, z_m: float, w3: float, v_z: float) -> None:
        """A later stop if Step C is still moving Z ``final_reserve_turns`` before it, or
        found no time left for a round with Z outside its tolerance (``out_of_turns``):
        the first turn that leaves Step C its reserve and the final turn."""
        c = self.step_c
        z_off = abs(c.z_stop_m(z_m, self.psi_rad)) > c.tol_m
        late = (c.phase in (PhaseC.CHECK, PhaseC.COAST) and z_off
                and self.psi_rad - c.psi_f_rad < self.p.final_reserve_turns * TWO_PI)
        if late or (c.phase is PhaseC.DONE and c.out_of_turns and z_off):
            reserve = c.p.reserve_turns
            self._start_c(t_s, z_m, w3, self._v_stop(v_z, w3), planned_stop_turn(
                self.psi_rad, 0.0, (reserve + LATER_STOP_EXTRA_TURNS) * TWO_PI), self.mode,
                reserve)

    def _v_stop(self, v_z_m_s: float, w3: float) -> float:
        return stopping_velocity_m_s(v_z_m_s, w3, self.thr.kappa_m_s_per_rad_s)

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
                turns = self._transfer_turns(w3, r_R_m[:2]) + self.p.stop_reserve_turns
                self._start_c(t_s, float(r_R_m[2]), w3, self._v_stop(float(v_R_m_s[2]), w3),
                              planned_stop_turn(psi, 0.0, turns * TWO_PI), Mode.TRANSFER)
            else:
                t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
        if self.mode is Mode.TRANSFER:
            # Step C moves Z while Step D moves x–y (module docstring): Step D waits
            # during a kick, Step C during a velocity sequence
            self._replan_if_late(t_s, float(r_R_m[2]), w3, float(v_R_m_s[2]))
            if (self.step_c.phase is not PhaseC.DONE
                    and self.step_d.phase is not PhaseD.VELOCITY):
                torque = self.step_c.torque_B_Nm(t_s, q_BR, omega_BN_B, psi, float(r_R_m[2]),
                                                 float(v_R_m_s[2]))
                if self.step_b.phase is PhaseB.KICK:  # (Step C going or stopping)
                    return torque  # a kick: Step D waits
            seq = self.step_d.sequence
            if (self.step_d.phase is PhaseD.COAST and seq is not None
                    and psi < seq.psi_a_rad - abs(w3) * self.period_s):
                self.step_d.start(self._far(psi))  # a kick passed its start angle: re-plan
            if not (self.step_d.phase is PhaseD.COAST
                    and self.step_d.settled(r_R_m[:2], v_R_m_s[:2])):
                t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
            if self.step_c.phase is not PhaseC.DONE:
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR))  # Z still moving
            self.step_d.start(self.step_c.psi_f_rad)
            self._switch(t_s, Mode.D)
        if self.mode is Mode.C:
            self._replan_if_late(t_s, float(r_R_m[2]), w3, float(v_R_m_s[2]))
            torque = self.step_c.torque_B_Nm(t_s, q_BR, omega_BN_B, psi, float(r_R_m[2]),
                                             float(v_R_m_s[2]))
            if self.step_c.phase is not PhaseC.DONE:
                return torque
            self.step_d.start(self.step_c.psi_f_rad)
            self._switch(t_s, Mode.D)
        if self.mode is Mode.D:
            psi_f = self.step_d.psi_f_rad
            waiting = (self.step_d.phase is PhaseD.COAST
                       and self.step_d.settled(r_R_m[:2], v_R_m_s[:2]))
            if not self.fine and waiting:
                # after a coarse Step C, at the aim point: a fine round (small kicks)
                self.step_c.start(psi_f, self.step_c.p.reserve_turns, self.p.z_tol_m)
                self.fine = True
                self._switch(t_s, Mode.C)
                return self.step_c.torque_B_Nm(t_s, q_BR, omega_BN_B, psi, float(r_R_m[2]),
                                               float(v_R_m_s[2]))
            t3 = self.step_d.torque_III_Nm(psi, w3, r_R_m[:2], v_R_m_s[:2])
            if self.step_d.psi_f_rad != psi_f:  # a turn later: Z moved by 2πκ
                self._start_c(t_s, float(r_R_m[2]), w3, self._v_stop(float(v_R_m_s[2]), w3),
                              round(self.step_d.psi_f_rad / TWO_PI), Mode.C,
                              self.step_c.p.reserve_turns)
                return hold.track(omega_BN_B, hold.pointing_rate(q_BR))
            if self.step_d.phase is PhaseD.DONE:
                self._switch(t_s, Mode.DONE)
                return np.array([0.0, 0.0, t3])  # the last sliver of spin
            return hold.track(omega_BN_B, hold.pointing_rate(q_BR), t3)
        return np.zeros(3)
