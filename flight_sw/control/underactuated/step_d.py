"""Step D: plan the de-spin so the spin stops on the target angle with x and y at the target.

What it does: in single spin, with the stopping velocity and position already set (Steps
B and C), the axis-III torque alone moves the body in x–y (the force turns with the body,
eq. 9) and is planned in sequences of the exponential de-spin of :mod:`.despin`:
- **velocity sequences** (seq. 1 of §3.5): a half turn started on the spin angle that
  points the change where it is needed, sized by η (``|Δv| = 2λη``); used to stop the
  drift and to set a transfer velocity toward the aim point, then again to stop there;
  each is planned from the closed forms (start angle, duration, position change) and
  re-planned from the measured state after it;
- **coast** (T_III = 0) between sequences;
- **the final turn** (seq. 3): from ψ_f + 2π with zero velocity, a whole-turn exponential
  de-spin that stops exactly on ψ_f; its x–y displacement ``Δr_f(ψ_f)`` is a constant of
  the vehicle (:func:`.despin.final_turn_offset_m`), so the velocity sequences aim at
  ``−Δr_f``. η is recomputed each cycle from the angle left (``η = −ω_III/(ψ − ψ_f)``),
  which closes the loop on the stop angle; the last sliver of spin is taken out in one
  control period.
The paper's second sequence (a whole-turn partial de-spin that moves the body without
changing its velocity) is replaced by the transfer-and-stop pair, which reaches any
distance for a bounded spin cost; if the plan cannot be done before ψ_f + 2π the stop
moves one turn later (the supervisor is told: that turn count also sets z, Step C).

Inputs per cycle: ψ (unwrapped) [rad], ω_III [rad/s], x–y position [m] and velocity
[m/s] in R. Output: the axis-III torque to add to Step A's hold [N m] (≥ 0).
Source: seed 004 §3.5 (eqs. 39–53) and §3.6 (why the plan needs small x–y errors).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.control.underactuated.despin import (
    TWO_PI,
    Despin,
    final_turn_offset_m,
    half_turn_for,
    max_half_turn_dv,
)
from flight_sw.control.underactuated.geometry import ThreeThrusters
from flight_sw.control.underactuated.invariants import SPIN_FLOOR_RAD_S

_SOURCE = "[flight_sw.pose] step D"
MIN_SPEED_TOLS = 2.0  # the least transfer speed, in velocity tolerances


class Phase(enum.Enum):
    """What Step D is doing."""

    COAST = "coast"
    VELOCITY = "velocity sequence"
    FINAL = "final turn"
    DONE = "done"


@dataclass(frozen=True)
class StepDParams:
    """Tolerances [m, m/s], transfer lead [s] and its least length in spin periods,
    speed limit [m/s], spin kept per sequence, end of the final turn [rad]."""

    position_tol_m: float = 0.005
    velocity_tol_m_s: float = 5e-5
    transfer_lead_s: float = 40.0
    lead_turns: float = 1.5
    max_transfer_speed_m_s: float = 0.02
    keep_spin_fraction: float = 0.5
    final_angle_tol_rad: float = 1e-3

    def __post_init__(self) -> None:
        for key in ("position_tol_m", "velocity_tol_m_s", "transfer_lead_s",
                    "lead_turns", "max_transfer_speed_m_s", "final_angle_tol_rad"):
            check.positive(_SOURCE, key, getattr(self, key))
        if not 0.0 < self.keep_spin_fraction < 1.0:
            raise ConfigError(_SOURCE, "keep_spin_fraction", self.keep_spin_fraction,
                              "a fraction in (0, 1)")


def next_angle_below(psi_rad: float, angle_mod_rad: float) -> float:
    """The largest angle ≤ ψ equal to ``angle_mod_rad`` mod 2π (a negative spin reaches it next)."""
    return psi_rad - ((psi_rad - angle_mod_rad) % TWO_PI)


class StepD:
    """The de-spin planner (module docstring). ``psi_f_rad`` is the planned stop angle."""

    def __init__(self, thrusters: ThreeThrusters, params: StepDParams, period_s: float) -> None:
        self.thr = thrusters
        self.p = params
        self.period_s = period_s
        self.lam = thrusters.lateral_m_per_rad_s
        self.alpha = thrusters.alpha_rad
        self.j3 = float(thrusters.inertia_diag_kgm2[2])
        self.phase = Phase.COAST
        self.psi_f_rad = 0.0
        self.transfer = True
        self.sequence: Despin | None = None
        self.sequences = 0
        self.postponed_turns = 0

    def start(self, psi_f_rad: float, transfer: bool = True) -> None:
        """Begin planning toward a stop on ``psi_f_rad`` (unwrapped); ``transfer=False``
        only stops the x–y drift where the body is (no move toward the aim point)."""
        self.psi_f_rad = psi_f_rad
        self.transfer = transfer
        self.phase = Phase.COAST
        self.sequence = None

    def settled(self, r_xy: np.ndarray, v_xy: np.ndarray) -> bool:
        """At the aim point and at rest in x–y, within the tolerances: ready for the final
        turn."""
        return (float(np.linalg.norm(v_xy)) <= self.p.velocity_tol_m_s
                and float(np.linalg.norm(self.aim_m() - np.asarray(r_xy)))
                <= self.p.position_tol_m)

    def aim_m(self) -> np.ndarray:
        """Where the final turn must start so that it ends at the origin [m]."""
        # the offset turns with ψ_f mod 2π; the remainder keeps the closed form's angles
        # small when ψ_f is far ahead (the supervisor's transfer)
        return -final_turn_offset_m(math.remainder(self.psi_f_rad, TWO_PI), self.lam,
                                    self.alpha)

    def lead_s(self, w3: float) -> float:
        """The transfer's lead time: ``transfer_lead_s``, or ``lead_turns`` spin periods if
        longer (a sequence waits up to a turn for its start angle and lasts half a turn:
        a lead shorter than that overshoots and rings as the spin slows) [s]."""
        return max(self.p.transfer_lead_s, self.p.lead_turns * TWO_PI
                   / max(abs(w3), SPIN_FLOOR_RAD_S))

    def _transfer_velocity(self, r_from: np.ndarray, w3: float) -> np.ndarray:
        """The x–y velocity that closes the gap to the aim point in the transfer lead time
        (at most the transfer speed; zero once inside the position tolerance) [m/s]."""
        err = self.aim_m() - r_from
        if not self.transfer or float(np.linalg.norm(err)) <= self.p.position_tol_m:
            return np.zeros(2)
        v_des = err / self.lead_s(w3)
        speed = float(np.linalg.norm(v_des))
        # no slower than a few velocity tolerances (a slower demand is inside the
        # tolerance: no sequence would ever close the last millimetres)
        least = MIN_SPEED_TOLS * self.p.velocity_tol_m_s
        if speed < least:
            v_des *= least / speed
        elif speed > self.p.max_transfer_speed_m_s:
            v_des *= self.p.max_transfer_speed_m_s / speed
        return v_des

    def _plan(self, psi: float, w3: float, r: np.ndarray, v: np.ndarray) -> Despin | None:
        """The next velocity sequence, or None if the drift already fits the plan."""
        v_des = self._transfer_velocity(r, w3)
        if float(np.linalg.norm(v_des - v)) <= self.p.velocity_tol_m_s:
            return None
        limit = max_half_turn_dv(w3, self.lam, self.p.keep_spin_fraction)
        seq = None
        for _ in range(3):  # aim from where the sequence will start and end
            dv = v_des - v
            size = float(np.linalg.norm(dv))
            if seq is not None and size <= self.p.velocity_tol_m_s:
                break  # aimed from its end, no change is asked: keep the last plan
            if size > limit:
                dv *= limit / size
            seq = half_turn_for(dv, w3, self.lam, self.alpha)
            psi_a = next_angle_below(psi, seq.psi_a_rad)
            seq = Despin(psi_a, w3, seq.omega_b_rad_s, seq.eta_per_s)
            wait_s = (psi - psi_a) / abs(w3)
            v_des = self._transfer_velocity(
                r + v * wait_s + seq.delta_r(v, self.lam, self.alpha), w3)
        return seq

    def _postpone(self) -> float:
        """Stop one turn later; returns the final turn's new start angle [rad]."""
        self.psi_f_rad -= TWO_PI
        self.postponed_turns += 1
        self.sequence = None
        return self.psi_f_rad + TWO_PI

    def torque_III_Nm(self, psi: float, w3: float, r_xy: np.ndarray, v_xy: np.ndarray) -> float:
        """The axis-III torque to add this cycle [N m] (≥ 0)."""
        if self.phase is Phase.DONE:
            return 0.0
        if self.phase is Phase.FINAL:
            left = psi - self.psi_f_rad
            if left <= self.p.final_angle_tol_rad or w3 >= 0.0:
                self.phase = Phase.DONE
                return max(0.0, -self.j3 * w3 / self.period_s)  # the last sliver
            # T = −η J ω with η = −ω/(ψ − ψ_f), taken at mid-period: the torque is held
            # over the period, and the exponential de-spin's mid-period torque is
            # η J |ω| e^(−η h/2) ≈ J ω² / (ψ − ψ_f + |ω| h/2). Taken at the period's start
            # (forward Euler) the turn ended ~λ |ω| h / 2 off (3.7 mm at 0.3 rad/s, h 20 ms).
            return self.j3 * w3 * w3 / (left - 0.5 * w3 * self.period_s)
        start_final = self.psi_f_rad + TWO_PI
        if self.phase is Phase.VELOCITY and self.sequence is not None:
            if psi > self.sequence.psi_b_rad:
                return -self.sequence.eta_per_s * self.j3 * w3
            self.phase, self.sequence = Phase.COAST, None
        # the final turn starts where ψ passes ψ_f + 2π, inside this period: its first
        # torque is scaled by the part of the period after the crossing (the same
        # impulse; a turn started δ late ends about λ δ off, 8 mm per mrad at λ = 2 m)
        step = abs(w3) * self.period_s
        while psi < start_final - step:  # passed while Step D was not running: too late
            start_final = self._postpone()
        if psi - step < start_final:
            if self.settled(r_xy, v_xy):
                self.phase = Phase.FINAL
                after = min(1.0, (start_final - (psi - step)) / step) if step > 0.0 else 1.0
                return after * self.j3 * w3 * w3 / TWO_PI
            start_final = self._postpone()  # not ready: stop one turn later
        if self.sequence is None:
            self.sequence = self._plan(psi, w3, np.asarray(r_xy), np.asarray(v_xy))
            while self.sequence is not None and self.sequence.psi_b_rad < start_final:
                start_final = self._postpone()  # it ends after the final turn's start
        if self.sequence is not None and psi <= self.sequence.psi_a_rad:
            self.phase = Phase.VELOCITY
            self.sequences += 1
            seq = self.sequence
            # start now, from the measured spin (the plan used the spin at planning time)
            self.sequence = Despin(psi, w3, w3 + (seq.omega_b_rad_s - seq.omega_a_rad_s),
                                   seq.eta_per_s)
            return -seq.eta_per_s * self.j3 * w3
        return 0.0
