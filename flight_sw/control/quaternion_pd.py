"""Quaternion PD attitude control (quaternion feedback): the baseline law of seed 003.

What it does: the proportional-derivative law on the error quaternion and rate error
    ``δq = q_RN* ⊗ q_BN``  (= q_BR, attitude of body B relative to reference R),
    ``τ_B = −K_p ∘ sgn(δq0) δq_vec − K_d ∘ (ω_BN_B − ω_RN_B)``,
with per-axis gains (``∘`` is the element-wise product). The factor ``sgn(δq0)`` (+1 for
δq0 = 0) picks the short way: ``q`` and ``−q`` give the same torque, and an error beyond
180° is corrected through the smaller complementary rotation.

Inputs/outputs: see :class:`flight_sw.control.base.AttitudeController`; torque in body
axes [N m]; gains ``kp_Nm`` [N m per unit quaternion-vector error] and ``kd_Nms``
[N m s/rad].

Slew-rate limit (optional ``max_rate_rad_s``): each component of the proportional term
is clipped at ``L_i = K_d,i ω_max / K_p,i``, so far from the target the law drives the
rate towards ω_max per axis instead of building up more rate than the thrusters can brake
(Wie & Lu 1995, "Feedback control logic for spacecraft eigenaxis rotations under slew
rate and control constraints", JGCD 18(6) 1372–1379, in its per-axis form).

Bandwidth design (:meth:`QuaternionPdParams.from_bandwidth`): for small errors
``δq_vec ≈ θ/2`` (θ the error rotation vector) and ``θ̇ ≈ ω − ω_ref``; with the
gyroscopic term negligible near the reference, axis i obeys
``J_i θ̈_i = −K_p,i θ_i/2 − K_d,i θ̇_i``, i.e. ``θ̈ + 2ζω_n θ̇ + ω_n² θ = 0`` with
``K_p,i = 2 J_i ω_n²`` and ``K_d,i = 2 ζ ω_n J_i`` (the 2 in K_p because δq_vec ≈ θ/2).

Assumptions: unit input quaternions (not checked, for speed); principal body axes for
the bandwidth design (diagonal inertia); no gyroscopic or feed-forward terms (Wie's law
in its plain regulator form, which also holds for slow reference motion).

Sources: Wie & Barba 1985, "Quaternion feedback for spacecraft large angle maneuvers",
JGCD 8(3) 360–365; Wie, Weiss & Arapostathis 1989, "Quaternion feedback regulator for
spacecraft eigenaxis rotations", JGCD 12(3) 375–380 (the law ``u = −K q_e − C ω`` with the
short-way sign); Wie 2008, "Space Vehicle Dynamics and Control", 2nd ed., ch. 7
(quaternion feedback control); seed 003 (quaternion PD outer loop, Table 1 gains
kp = 72, kd = 200). The seed's own equations were lost in text extraction, hence the
textbook form here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.control.base import error_limit
from flight_sw.quaternion import error_quaternion

N_AXES = 3
# K_p = KP_PER_HALF_ANGLE · J ω_n²: δq_vec ≈ θ/2 for small errors, so K_p carries a factor 2.
KP_PER_HALF_ANGLE = 2.0
# K_d = KD_FACTOR · ζ ω_n J (standard second-order form 2ζω_n).
KD_FACTOR = 2.0

_SOURCE = "QuaternionPdParams"


@dataclass(frozen=True)
class QuaternionPdParams:
    """Per-axis gains of the quaternion PD law.

    Attributes:
        kp_Nm: proportional gains (x, y, z) on δq_vec [N m], each ≥ 0.
        kd_Nms: derivative gains (x, y, z) on the rate error [N m s/rad], each ≥ 0.
    """

    kp_Nm: tuple[float, float, float]
    kd_Nms: tuple[float, float, float]
    max_rate_rad_s: float = math.inf

    def __post_init__(self) -> None:
        s = _SOURCE
        object.__setattr__(self, "kp_Nm", check.triple(s, "kp_Nm", self.kp_Nm, 0.0))
        object.__setattr__(self, "kd_Nms", check.triple(s, "kd_Nms", self.kd_Nms, 0.0))
        check.limit(s, "max_rate_rad_s", self.max_rate_rad_s, unit="rad/s")

    @classmethod
    def from_bandwidth(
        cls,
        inertia_diag_kgm2: Sequence[float],
        natural_frequency_rad_s: float,
        damping_ratio: float,
        max_rate_rad_s: float = math.inf,
    ) -> QuaternionPdParams:
        """Gains giving each linearised axis the natural frequency ω_n and damping ratio ζ.

        ``K_p,i = 2 J_i ω_n²``, ``K_d,i = 2 ζ ω_n J_i`` (see the module docstring).
        """
        s = _SOURCE
        jx, jy, jz = check.triple(s, "inertia_diag_kgm2", inertia_diag_kgm2, 0.0, lo_open=True)
        wn = check.positive(s, "natural_frequency_rad_s", natural_frequency_rad_s)
        zeta = check.non_negative(s, "damping_ratio", damping_ratio)
        wn_sq = wn * wn
        kp = (
            KP_PER_HALF_ANGLE * jx * wn_sq,
            KP_PER_HALF_ANGLE * jy * wn_sq,
            KP_PER_HALF_ANGLE * jz * wn_sq,
        )
        kd = (KD_FACTOR * zeta * wn * jx, KD_FACTOR * zeta * wn * jy, KD_FACTOR * zeta * wn * jz)
        return cls(kp_Nm=kp, kd_Nms=kd, max_rate_rad_s=max_rate_rad_s)


class QuaternionPd:
    """Quaternion PD controller (implements ``AttitudeController``); stateless."""

    def __init__(self, params: QuaternionPdParams) -> None:
        self._params = params
        self._kp = np.array(params.kp_Nm, dtype=float)
        self._kd = np.array(params.kd_Nms, dtype=float)
        # slew-rate limit: |δq_i| is clipped at L_i = K_d,i ω_max / K_p,i (Wie & Lu 1995)
        self._q_limit = error_limit(self._kp, self._kd, params.max_rate_rad_s)

    @property
    def params(self) -> QuaternionPdParams:
        """The gains this controller was built with."""
        return self._params

    def torque_B_Nm(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        omega_BN_B: np.ndarray,
        q_RN: np.ndarray,
        omega_RN_B: np.ndarray,
        domega_RN_B: np.ndarray | None = None,
    ) -> np.ndarray:
        """``τ_B = −K_p ∘ sat_L(sgn(δq0) δq_vec) − K_d ∘ (ω_BN_B − ω_RN_B)`` [N m]."""
        dq = error_quaternion(q_RN, q_BN)
        sign = -1.0 if dq[0] < 0.0 else 1.0
        q_err = np.clip(sign * dq[1:], -self._q_limit, self._q_limit)
        rate_error = np.asarray(omega_BN_B, dtype=float) - np.asarray(omega_RN_B, dtype=float)
        return -self._kp * q_err - self._kd * rate_error
