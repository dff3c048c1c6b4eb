"""Step B: set the stopping velocity with planned disturbances and Step A's return.

What it does: in single spin the stopping velocity ``V_s = v_z − κ ω_III`` (eq. 21) does
not change (eq. 22); only leaving the manifold does. Step B repeats a sequence until V_s
is within ``velocity_tol_m_s`` of its target (0 for seed 004's Step B; Step C sets other
targets):
- **settle**: Step A's pointing law holds the body until it is in single spin again
  (tilt and transverse rates below the tolerances: Step A's exit condition), then V_s
  is measured;
- **kick**: the disturbance of :mod:`.disturbance` that changes V_s by what is missing
  (clipped per kick) is played open loop, thrusts as planned, for its one turn.
The plan is first order, so each sequence leaves a remainder that the next one takes;
what a sequence achieved over what it planned (the gain, kept from one sequence to the
next) scales the next request, which takes out most of the systematic part (the second
order terms keep their sign for a given spin); V_s converges without overshoot when each
change is sized to what is left (the paper's repeated sequences, §3.3). Every kick costs
spin (condition (ii)); the count of kicks and the spin spent are kept for the supervisor.

Inputs per cycle: time [s], ``q_BR``, ``omega_BN_B`` [rad/s], the spin angle ψ [rad], the
z velocity in the target frame [m/s]. Output: the torque demand in body axes [N m].
Source: seed 004 §3.3 (eqs. 21–27).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np

from dbc import validation as check
from flight_sw.control.underactuated.disturbance import DisturbanceParams, Kick, plan_kick
from flight_sw.control.underactuated.geometry import ThreeThrusters
from flight_sw.control.underactuated.invariants import stopping_velocity_m_s
from flight_sw.control.underactuated.step_a import StepA, in_single_spin

_SOURCE = "[flight_sw.pose] step B"
GAIN_MIN_DV_M_S = 2e-3  # kicks smaller than this do not update the gain (noise)
GAIN_MAX = 2.0  # the gain stays within [1/GAIN_MAX, GAIN_MAX]


class Phase(enum.Enum):
    """What Step B is doing."""

    SETTLE = "settle"
    KICK = "kick"
    DONE = "done"


@dataclass(frozen=True)
class StepBParams:
    """Tolerance on V_s [m/s]; single-spin tolerances [rad, rad/s]; the kick's design."""

    velocity_tol_m_s: float = 5e-5
    settle_tilt_rad: float = 2e-3
    settle_rate_rad_s: float = 2e-4
    disturbance: DisturbanceParams = field(default_factory=DisturbanceParams)

    def __post_init__(self) -> None:
        for key in ("velocity_tol_m_s", "settle_tilt_rad", "settle_rate_rad_s"):
            check.positive(_SOURCE, key, getattr(self, key))


class StepB:
    """Step B's sequences (module docstring)."""

    def __init__(self, thrusters: ThreeThrusters, hold: StepA, params: StepBParams,
                 period_s: float) -> None:
        self.thr = thrusters
        self.hold = hold
        self.p = params
        self.period_s = period_s
        self.phase = Phase.DONE
        self.target_m_s = 0.0
        self.tol_m_s = params.velocity_tol_m_s
        #: measured over planned change of V_s of the last sequence (kick and settle)
        self.gain = 1.0
        self._v_before = float("nan")
        self.kick: Kick | None = None
        self._kick_t0_s = 0.0
        self.kicks = 0
        self.spin_spent_rad_s = 0.0
        #: V_s measured at the last settle [m/s] (nan before the first)
        self.v_stop_m_s = float("nan")

    def start(self, target_m_s: float = 0.0, tol_m_s: float | None = None) -> None:
        """Begin driving V_s to ``target_m_s`` within ``tol_m_s`` (default: the
        parameters' tolerance) [m/s]."""
        self.target_m_s = check.number(_SOURCE, "target_m_s", target_m_s)
        self.tol_m_s = (self.p.velocity_tol_m_s if tol_m_s is None
                        else check.positive(_SOURCE, "tol_m_s", tol_m_s))
        self.phase = Phase.SETTLE
        self.kick = None

    def torque_B_Nm(self, t_s: float, q_BR: np.ndarray, omega_BN_B: np.ndarray,
                    psi_rad: float, v_z_m_s: float) -> np.ndarray:
        """The torque demand this cycle [N m]."""
        if self.phase is Phase.KICK and self.kick is not None:
            since = t_s - self._kick_t0_s
            if since < self.kick.duration_s:
                return self.thr.torque_B @ self.kick.thrusts_at(since)
            self.phase = Phase.SETTLE  # the kick is kept: its plan meets the measurement
        if self.phase is Phase.SETTLE and in_single_spin(
                q_BR, omega_BN_B, self.p.settle_tilt_rad, self.p.settle_rate_rad_s):
            w3 = float(omega_BN_B[2])
            self.v_stop_m_s = stopping_velocity_m_s(v_z_m_s, w3,
                                                    self.thr.kappa_m_s_per_rad_s)
            if self.kick is not None and abs(self.kick.dv_stop_m_s) >= GAIN_MIN_DV_M_S:
                ratio = (self.v_stop_m_s - self._v_before) / (self.gain
                                                              * self.kick.dv_stop_m_s)
                self.gain = min(GAIN_MAX, max(1.0 / GAIN_MAX, ratio * self.gain))
            missing = self.target_m_s - self.v_stop_m_s
            if abs(missing) <= self.tol_m_s:
                self.phase, self.kick = Phase.DONE, None
            else:
                self._v_before = self.v_stop_m_s
                self.kick = plan_kick(self.thr, self.p.disturbance, self.period_s, w3,
                                      psi_rad, missing / self.gain)
                self.phase, self._kick_t0_s = Phase.KICK, t_s
                self.kicks += 1
                self.spin_spent_rad_s += self.kick.domega_III_rad_s
                return self.thr.torque_B @ self.kick.thrusts_at(0.0)
        return self.hold.track(omega_BN_B, self.hold.pointing_rate(q_BR))
