"""Position PD control: position/velocity error in the navigation frame -> body-axes force.

What it does: the proportional-derivative law on the translational error, per axis of the
navigation frame N,
    ``F_N = −K_p ∘ sat_L(r_N − r_ref_N) − K_d ∘ (v_N − v_ref_N)``,
limited in magnitude to ``max_force_N`` (direction-preserving scaling of the whole vector),
then expressed in body axes with the estimated attitude, ``F_B = C(q_BN) F_N``, because
the thrusters act in body axes. ``sat_L`` clips each component of the position error at
``L_i = K_d,i v_max / K_p,i`` (optional ``max_speed_m_s``): far from the reference the law
drives the speed towards v_max per axis instead of accelerating to more than the
thrusters can brake (the translational twin of the slew-rate limit of
:mod:`flight_sw.control.quaternion_pd`).

Bandwidth design (:meth:`PositionPdParams.from_bandwidth`): with the nominal mass m, each
axis obeys ``m ẍ = −K_p x − K_d ẋ``, i.e. ``ẍ + 2ζω_n ẋ + ω_n² x = 0`` with
``K_p = m ω_n²`` and ``K_d = 2 ζ ω_n m``.

Inputs/outputs: see :class:`flight_sw.control.base.TranslationController`; positions [m],
velocities [m/s], gains ``kp_N_m`` [N/m] and ``kd_N_s_m`` [N s/m], force [N].

Assumptions: translation in an inertial frame (no orbital or Hill-frame coupling terms;
the relative motion over a 1-minute manoeuvre is dominated by the thrusters); the
navigation solution is fresh (the caller falls back to zero force when it is not);
the attitude estimate is good enough to rotate the force (an error of θ rotates the force
by θ, a second-order effect on the closed loop).

Sources: the PD (proportional-derivative) position regulator of textbook translational
control, e.g. Wie 2008, "Space Vehicle Dynamics and Control", 2nd ed., ch. 7; the
per-axis saturation mirrors Wie & Lu 1995 (JGCD 18(6) 1372–1379) for rates. Seed 000
controls the same six degrees of freedom with a dual-quaternion sliding-mode law; this
baseline decouples translation from attitude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw import vec3
from flight_sw.control.base import error_limit
from flight_sw.quaternion import dcm

N_AXES = 3
_SOURCE = "PositionPdParams"


@dataclass(frozen=True)
class PositionPdParams:
    """Per-axis gains and limits of the position PD law.

    Attributes:
        kp_N_m: proportional gains (x, y, z of N) [N/m], each ≥ 0.
        kd_N_s_m: derivative gains (x, y, z of N) [N s/m], each ≥ 0.
        max_force_N: limit of the force magnitude [N] (> 0; inf: none).
        max_speed_m_s: approach-speed limit per axis [m/s] (> 0; inf: none).
    """

    kp_N_m: tuple[float, float, float]
    kd_N_s_m: tuple[float, float, float]
    max_force_N: float = math.inf
    max_speed_m_s: float = math.inf

    def __post_init__(self) -> None:
        s = _SOURCE
        object.__setattr__(self, "kp_N_m", check.triple(s, "kp_N_m", self.kp_N_m, 0.0))
        object.__setattr__(self, "kd_N_s_m", check.triple(s, "kd_N_s_m", self.kd_N_s_m, 0.0))
        object.__setattr__(self, "max_force_N", check.limit(s, "max_force_N", self.max_force_N))
        max_speed = check.limit(s, "max_speed_m_s", self.max_speed_m_s, unit="m/s")
        object.__setattr__(self, "max_speed_m_s", max_speed)

    @classmethod
    def from_bandwidth(
        cls,
        mass_kg: float,
        natural_frequency_rad_s: float,
        damping_ratio: float,
        max_force_N: float = math.inf,
        max_speed_m_s: float = math.inf,
    ) -> PositionPdParams:
        """Gains giving each axis ω_n and ζ: ``K_p = m ω_n²``, ``K_d = 2 ζ ω_n m``."""
        s = _SOURCE
        mass_kg = check.positive(s, "mass_kg", mass_kg, unit="kg")
        wn = check.positive(s, "natural_frequency_rad_s", natural_frequency_rad_s)
        zeta = check.non_negative(s, "damping_ratio", damping_ratio)
        kp = mass_kg * wn * wn
        kd = 2.0 * zeta * wn * mass_kg
        return cls((kp, kp, kp), (kd, kd, kd), max_force_N, max_speed_m_s)


class PositionPd:
    """Position PD controller (implements ``TranslationController``); stateless."""

    def __init__(self, params: PositionPdParams) -> None:
        self._params = params
        self._kp = np.array(params.kp_N_m, dtype=float)
        self._kd = np.array(params.kd_N_s_m, dtype=float)
        self._r_limit = error_limit(self._kp, self._kd, params.max_speed_m_s)
        self._f_max = params.max_force_N

    @property
    def params(self) -> PositionPdParams:
        """The gains this controller was built with."""
        return self._params

    def force_N_N(
        self,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """The limited force demand in the navigation frame [N]."""
        r_err = np.clip(
            np.asarray(r_N_m, dtype=float) - np.asarray(r_ref_N_m, dtype=float),
            -self._r_limit,
            self._r_limit,
        )
        v_err = np.asarray(v_N_m_s, dtype=float) - np.asarray(v_ref_N_m_s, dtype=float)
        f = -self._kp * r_err - self._kd * v_err
        f0, f1, f2 = f.tolist()
        norm = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
        if norm > self._f_max:
            f *= self._f_max / norm
        return f

    def force_B_N(
        self,
        t_ns: int,
        q_BN: np.ndarray,
        r_N_m: np.ndarray,
        v_N_m_s: np.ndarray,
        r_ref_N_m: np.ndarray,
        v_ref_N_m_s: np.ndarray,
    ) -> np.ndarray:
        """``F_B = C(q_BN) F_N`` [N] (see the module docstring)."""
        f0, f1, f2 = self.force_N_N(r_N_m, v_N_m_s, r_ref_N_m, v_ref_N_m_s).tolist()
        q0, q1, q2, q3 = np.asarray(q_BN, dtype=float).tolist()
        return np.array(vec3.mat_vec(dcm(q0, q1, q2, q3), f0, f1, f2))
