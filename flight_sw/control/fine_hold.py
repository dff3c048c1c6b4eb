"""Fine hold: a 6-DoF law that hands over to low-gain PD laws near the target, with hysteresis.

What it does: wraps a coupled 6-DoF law (the *coarse* law, e.g. the seed-000 NFTSM of
:mod:`flight_sw.control.nftsm_dq`) and, once the vehicle is near its reference, replaces
it by a *fine* pair: an attitude law (torque) and a translation law (force), normally the
PD laws of :mod:`flight_sw.control.quaternion_pd` and :mod:`flight_sw.control.position_pd`
with a low bandwidth. It switches to fine when every error is inside its *enter*
threshold (position ‖r − r_ref‖, speed ‖v − v_ref‖, attitude angle of ``q_RN* ⊗ q_BN``,
rate ‖ω_BN − ω_RN‖) and back to coarse only when the position or the attitude error
leaves its larger *leave* threshold: the gap is the hysteresis, so sensor noise at a
threshold does not toggle the laws.

Why (seed 000 on on-off valves, docs/reproductions.md): a sliding-mode law's reaching term
``α3 sig(S)^p2`` has an unbounded gain at ``S = 0`` and its switching term ``K tanh(S/w)``
a gain ``K/w`` (400 N per unit of S with the paper's values), so near the target the
navigation noise (5 mm, 0.5 mm/s) becomes force commands of about 1–3 N, and the
modulators fire on noise: 367 valve pulses per second in the hold and two thirds of the
run's propellant spent after convergence. The design rule of the fine pair: its force
(torque) response to the sensor noise must stay inside the modulator's dead zone,
``K_p σ_r + K_d σ_v < n (U_on/K_m) F_max`` with ``n`` the thrusters the allocation spreads
it over, while its stiffness holds the band: a demand below that dead zone fires nothing,
so the position rests up to ``n (U_on/K_m) F_max / K_p`` off the target. With m = 100 kg,
ω_n = 0.4 rad/s, ζ = 0.7 (K_p = 16 N/m, K_d = 56 N s/m) and four 5 N thrusters per axis:
noise 0.11 N against 4 × 0.05 N, and a resting offset up to 12.5 mm (16 mm measured).
The thrusters then fire only to cancel the disturbance, near the minimum impulse bit.
Measured on seed 000
(``scenarios/formation_keeping_nftsm.toml``, on-off valves, the thresholds of
:class:`FineHoldParams`' defaults, fine laws at ω_n 2 rad/s (attitude) and 0.4 rad/s
(position), ζ 0.7): after settling, 9.9 valve pulses/s (about 6/s once the hand-over
transient is over; 367/s without the fine hold) and 2 % of the run's propellant (67 %
without), the run's propellant 0.39 kg instead of 1.18 kg; steady-state errors 16 mm and
0.026° (4.4 mm and 0.008° with the chattering law), inside the 0.1 m and 0.5° bands.

Inputs/outputs: those of :class:`flight_sw.control.base.PoseController` (force [N] and
torque [N m] in body axes); thresholds in m, m/s, deg, deg/s (:class:`FineHoldParams`).
:attr:`FineHold.in_fine_hold` tells which law acted last and :attr:`FineHold.switches`
counts the hand-overs (both into the flight software's statistics).

Assumptions: a reference that is still or slow (the fine laws have no feed-forward); the
laws are stateless or reset together (:meth:`FineHold.reset`).

Sources: the boundary-layer/fine-pointing hand-over of sliding-mode and bang-bang attitude
control with on-off thrusters, Wie 2008, "Space Vehicle Dynamics and Control", 2nd ed.,
ch. 7 (thruster-based fine pointing, dead zones matched to noise and minimum impulse);
Slotine & Li 1991, "Applied Nonlinear Control", sec. 7.2 (chattering and boundary layers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw import quaternion as qt
from flight_sw.allocation.dense import norm
from flight_sw.control.base import AttitudeController, PoseController, TranslationController

_SOURCE = "FineHoldParams"


@dataclass(frozen=True)
class FineHoldParams:
    """Hand-over thresholds (enter below all four; leave above either leave threshold).

    Attributes:
        enter_position_m, leave_position_m: position error [m] (0 < enter < leave).
        enter_attitude_deg, leave_attitude_deg: attitude error angle [deg] (0 < enter < leave).
        enter_speed_m_s: velocity error [m/s] below which the fine laws may take over (> 0).
        enter_rate_deg_s: rate error [deg/s] below which the fine laws may take over (> 0).
    """

    enter_position_m: float = 0.25
    leave_position_m: float = 0.5
    enter_attitude_deg: float = 0.5
    leave_attitude_deg: float = 2.0
    enter_speed_m_s: float = 0.05
    enter_rate_deg_s: float = 0.3

    def __post_init__(self) -> None:
        for key in ("enter_position_m", "leave_position_m", "enter_attitude_deg",
                    "leave_attitude_deg", "enter_speed_m_s", "enter_rate_deg_s"):
            check.positive(_SOURCE, key, getattr(self, key))
        for enter, leave in (("enter_position_m", "leave_position_m"),
                             ("enter_attitude_deg", "leave_attitude_deg")):
            if getattr(self, enter) >= getattr(self, leave):
                raise ConfigError(_SOURCE, leave, getattr(self, leave),
                                  f"above {enter} = {getattr(self, enter)} (the hysteresis)")


class FineHold:
    """A :class:`PoseController`: the coarse law far from the target, the fine pair near it."""

    def __init__(self, coarse: PoseController, attitude: AttitudeController,
                 translation: TranslationController, params: FineHoldParams) -> None:
        self.coarse = coarse
        self.attitude = attitude
        self.translation = translation
        self.params = params
        self.in_fine_hold = False
        self.switches = 0

    def reset(self) -> None:
        """Back to the coarse law (a restart), and reset the laws that keep state."""
        self.in_fine_hold = False
        for law in (self.coarse, self.attitude, self.translation):
            reset = getattr(law, "reset", None)
            if callable(reset):
                reset()

    def _fine_now(self, q_BN: np.ndarray, omega_BN_B: np.ndarray, r_N_m: np.ndarray,
                  v_N_m_s: np.ndarray, q_RN: np.ndarray, omega_RN_B: np.ndarray,
                  r_ref_N_m: np.ndarray, v_ref_N_m_s: np.ndarray) -> bool:
        p = self.params
        pos = norm((r_N_m - r_ref_N_m).tolist())
        att_deg = math.degrees(qt.rotation_angle_rad(qt.error_quaternion(q_RN, q_BN)))
        if self.in_fine_hold:
            return pos <= p.leave_position_m and att_deg <= p.leave_attitude_deg
        speed = norm((v_N_m_s - v_ref_N_m_s).tolist())
        rate_deg_s = math.degrees(norm((omega_BN_B - omega_RN_B).tolist()))
        return (pos < p.enter_position_m and att_deg < p.enter_attitude_deg
                and speed < p.enter_speed_m_s and rate_deg_s < p.enter_rate_deg_s)

    def wrench_B(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """The demanded wrench [force_B_N; torque_B_Nm] of the law in charge (module docstring)."""
        fine = self._fine_now(q_BN, omega_BN_B, r_N_m, v_N_m_s, q_RN, omega_RN_B,
                              r_ref_N_m, v_ref_N_m_s)
        if fine != self.in_fine_hold:
            self.in_fine_hold = fine
            self.switches += 1
        if not fine:
            return self.coarse.wrench_B(t_ns, q_BN, omega_BN_B, r_N_m, v_N_m_s, q_RN,
                                        omega_RN_B, r_ref_N_m, v_ref_N_m_s)
        force = self.translation.force_B_N(t_ns, q_BN, r_N_m, v_N_m_s, r_ref_N_m, v_ref_N_m_s)
        torque = self.attitude.torque_B_Nm(t_ns, q_BN, omega_BN_B, q_RN, omega_RN_B)
        return np.concatenate((force, torque))
