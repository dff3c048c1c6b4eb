"""The invariants of single spin (seed 004 §3.3–3.4): spin angle, stopping velocity and
stopping position.

Single spin: ω_I = ω_II = 0 with body axis III along the target z (Step A's manifold).
With the axis-III torque alone, ``J_III ω̇_III = T_III`` and ``m v̇_z = P_33 T_III``
(eqs. 18–19), so ``v_z − κ ω_III`` with ``κ = P_33 J_III / m`` does not change: it is the
z velocity left when the spin stops, eq. (21) (:func:`stopping_velocity_m_s`).
Integrating once more, ``Z = z − κ (ψ − ψ_t)`` changes at the rate of that velocity
(zero after Step B): the z position at which a spin that stops at the angle ψ_t (mod 2π)
ends is ``Z + 2π κ n`` for the number n of whole turns left (eqs. 28–32). The paper's
remainder form (eq. 35) keeps the integer out of the feedback; here the supervisor
plans the turn on which the spin stops and :func:`stopping_position_error_m` measures Z
against that turn's target (:func:`planned_stop_turn`).

Inputs: ``q_BR`` the body attitude relative to the target frame R (scalar first),
positions [m] and velocities [m/s] in R, ``omega_III_rad_s`` [rad/s], ``kappa_m`` [m]
(:attr:`ThreeThrusters.kappa_m_s_per_rad_s`). Angles in rad, unwrapped by the caller
where turns count.
Source: seed 004 eqs. (18)–(22) and (28)–(35).
"""

from __future__ import annotations

import math

import numpy as np

from flight_sw.quaternion import to_dcm

TWO_PI = 2.0 * math.pi
SPIN_FLOOR_RAD_S = 1e-9  # |ω_III| below this is taken as this in times to an angle


def target_z_in_B(q_BR: np.ndarray) -> np.ndarray:
    """The target z axis of R expressed in body axes (the third column of C_BR)."""
    return to_dcm(q_BR)[:, 2].copy()


def spin_angle_rad(q_BR: np.ndarray) -> float:
    """ψ: the heading of body axis I about z_R, in (−π, π] (exact in single spin)."""
    c = to_dcm(q_BR)  # rows: body axes in R
    return math.atan2(float(c[0, 1]), float(c[0, 0]))


def unwrap(previous_rad: float, wrapped_rad: float) -> float:
    """The continuous angle nearest ``previous_rad`` equal to ``wrapped_rad`` mod 2π."""
    return previous_rad + math.remainder(wrapped_rad - previous_rad, TWO_PI)


def stopping_velocity_m_s(v_z_m_s: float, omega_III_rad_s: float, kappa_m: float) -> float:
    """Eq. (21): the z velocity when the single spin stops, ``v_z − κ ω_III`` [m/s]."""
    return v_z_m_s - kappa_m * omega_III_rad_s


def stopping_position_m(z_m: float, psi_rad: float, psi_target_rad: float,
                        kappa_m: float) -> float:
    """Z = z − κ (ψ − ψ_t): the z position at which a spin stopping at ψ_t ends [m]
    (ψ unwrapped; valid with zero stopping velocity, eqs. 28–32)."""
    return z_m - kappa_m * (psi_rad - psi_target_rad)


def planned_stop_turn(psi_rad: float, psi_target_rad: float, margin_rad: float) -> int:
    """The last whole turn n with ψ_t + 2πn at least ``margin_rad`` below ψ (a negative
    spin decreases ψ): the earliest stop a plan needing ``margin_rad`` of rotation can make."""
    return math.floor((psi_rad - psi_target_rad - margin_rad) / TWO_PI)


def stopping_position_error_m(z_stop_m: float, stop_turn: int, kappa_m: float) -> float:
    """The final z if the spin stops on turn ``stop_turn``: ``Z + 2π κ n`` [m]."""
    return z_stop_m + TWO_PI * kappa_m * stop_turn


def remainder_error_m(z_stop_m: float, kappa_m: float) -> float:
    """The paper's remainder form (eq. 35): Z modulo 2π|κ|, in (−π|κ|, π|κ|] [m]."""
    period = TWO_PI * abs(kappa_m)
    return math.remainder(z_stop_m, period) if period > 0.0 else z_stop_m
