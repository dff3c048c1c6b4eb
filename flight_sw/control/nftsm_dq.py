"""Dual-quaternion non-singular fast terminal sliding-mode (NFTSM) 6-DoF pose control, seed 000.

What it does: one coupled law for force and torque from the pose error of body B relative
to the reference frame R (the desired frame D of the paper), eqs. (6)–(19):
- error dual quaternion ``q̂_e = q̂_d* ∘ q̂`` (eq. 6), short way (``q_e0 ≥ 0``), state
  ``ξ̂ = vec(q̂_e)`` (6,: attitude part ``vec(q_e)``, position part ``vec(q′_e) ≈ ½ p_e``);
  error twist ``ω̂_e = ω̂ − q̂_e* ∘ ω̂_d ∘ q̂_e`` (eq. 7), kinematics ``ξ̂̇ = Θ̂ ω̂_e`` (eq. 10);
- nominal dynamics (eqs. 8, 10) ``M̂0 ω̂̇_e = û_c + F̂`` with the drift
  ``F̂ = M̂0 [ω̂_e × (q̂_e* ∘ ω̂_d ∘ q̂_e) − q̂_e* ∘ ω̂̇_d ∘ q̂_e] − ω̂ × M̂0 ω̂ + m0 ĝ``;
- surface ``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13) with the switching auxiliary surface
  ``S_a = sig(ξ)^p1`` if ``S̄ = 0`` or ``|ξ| ≥ δ``, else ``r1 ξ + r2 sig(ξ)²`` (eqs. 14–16),
  ``r1 = (2 − p1) δ^(p1−1)``, ``r2 = (p1 − 1) δ^(p1−2)`` (so ``S_a`` and ``W`` are continuous at
  ``|ξ| = δ``; the paper's ``r′2 = (2 − p1)…`` is a misprint), ``W = dS_a/dξ`` (eqs. 18–19);
- law (17), ``tanh(·/w)`` in place of ``sgn`` (as the paper's simulation section does):
  ``û_c = M̂0 ω̂̇* − F̂ − K̂ ⊙ tanh(Ŝ/w)`` with
  ``ω̂̇* = −Θ̂⁻¹ [Θ̂̇ ω̂_e + α̂1 ⊙ ξ̂̇ + α̂2 ⊙ W ⊙ ξ̂̇ + α̂3 ⊙ sig(Ŝ)^p2]``,
  which gives ``Ŝ̇ = −α̂3 ⊙ sig(Ŝ)^p2 − Θ̂ M̂0⁻¹ K̂ tanh(Ŝ/w)`` on the nominal model.

Dual-slot convention made explicit: ``M̂(ω + ϵ v) = m v + ϵ J ω`` maps a twist (angular,
linear) to a wrench (force, torque), so the paper's ``K̂ sgn(Ŝ)`` is applied the same way:
the attitude surface S (real part) drives the torque with gain ``K`` [N m], the position
surface S′ (dual part) drives the force with gain ``K′`` [N]. Then ``[Ŝ | Θ̂ M̂0⁻¹ K̂ ⋯]`` of
the proof (21) is positive, as the proof needs.

Frames (:class:`flight_sw.control.base.PoseController`): N is the navigation frame; with
``mean_motion_rad_s = n > 0`` it is the Hill (LVLH) frame of a leader on a circular orbit
of radius ``R = (µ/n²)^(1/3)`` (x radial, y along-track, z orbit normal, rotating at
``n ẑ`` relative to inertial), ``r_N``/``v_N`` the relative position and its derivative
taken in N, ``ω_BN`` the body rate relative to N. Inertial twists (paper's ``ω̂``, ``ω̂_d``):
``ω = ω_BN + C_BN n ẑ``, ``v = C_BN (v_N + n R ŷ + n ẑ × r_N)`` and likewise for R with
``r_ref``, ``v_ref``; ``ω̂̇_d`` assumes ``ω_RN`` constant in R and ``v_ref`` constant in N
(zero for a reference fixed in N, the formation-keeping case). The leader's orbit enters
only through ``ω̂_d`` and the point-mass gravity ``ĝ = −µ (R x̂ + r)/|R x̂ + r|³`` on the
follower (not in the paper's eq. 8, which has no gravity; without it the law would
supply the 22 N centripetal force of a 100 kg vehicle on the 42,240 km orbit): together
they make the nominal drift the exact nonlinear relative orbital dynamics, to first order
the Hill–Clohessy–Wiltshire terms. ``n = 0``: N inertial, no gravity (free space).
Gravity-gradient torque (< 1e-6 N m here) is neglected.

Anti-unwinding option (Remark 4, eqs. 25–26): the attitude part of ``ξ̂`` becomes
``e_r = g(q_e0) vec(q_e)`` of :mod:`flight_sw.control.anti_unwinding`, with its Jacobian in
the real block of ``Θ̂``. See that module for the singular angle of ``Θ_r`` (103.1° for
µ = 0.01, 99.1° for µ = 0.1): the paper's initial error (102.7°) lies next to it (µ = 0.01:
converges, after a 160 kN initial force demand; µ = 0.1: diverges), hence off by default.

Inputs/outputs: see ``PoseController``; force in body axes [N], torque about the centre
of mass in body axes [N m]. Unbounded unless ``max_force_N``/``max_torque_Nm`` are finite
(then each 3-vector is scaled down, direction preserved); the allocator owns the thruster
limits (5 N in the paper).

Assumptions: unit quaternions; the nominal model is ``mass_kg`` and ``inertia_B_kgm2``
(updated by :meth:`NftsmDq.set_inertia_B_kgm2`); ``Θ̂`` is singular at a 180° attitude
error, where its scalar part is floored at ``ETA_FLOOR`` (bounded but large output);
the branch ``S̄_i = 0`` of eqs. (14)–(19) is taken only on exact equality.

Implementation: :meth:`NftsmDq.wrench_B` evaluates the law on floats (a few µs compiled);
:meth:`NftsmDq.wrench_B_reference` composes it from this module's array functions
(:func:`relative_motion`, :func:`attitude_state`, :func:`drift_wrench`, ... which the TSM
baseline shares), term by term as the paper writes it; tests hold the two equal to round-off.

Source: seed 000, eqs. (6)–(19), (24)–(26), Section V (gains: p1 = 0.6, p2 = 0.67,
δ̂ = 0.05 + ϵ 0.001, K̂ = 20 + ϵ 20, α̂1 = α̂2 = 0.05 + ϵ 0.1, α̂3 = 2 + ϵ 2, m0 = 100 kg,
J0 = diag(18, 18, 24) kg m², leader orbit 42,240 km); Filipe & Tsiotras 2015 (JGCD
38(4) 566–577) for the dual-quaternion relative dynamics with gravity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from mypy_extensions import mypyc_attr

from flight_sw import dual_quaternion as dq
from flight_sw import validation as check
from flight_sw.control import anti_unwinding as au
from flight_sw.quaternion import cross as cross3
from flight_sw.quaternion import error_quaternion, to_dcm

N_AXES = 3
HALF = 0.5
# Earth's gravitational parameter [m³/s²] (EGM/WGS-84 value).
MU_EARTH_M3_S2 = 3.986004418e14
# The leader's orbit radius of seed 000, Section V [m], and its mean motion [rad/s].
PAPER_ORBIT_RADIUS_M = 42_240e3
PAPER_MEAN_MOTION_RAD_S = math.sqrt(MU_EARTH_M3_S2 / PAPER_ORBIT_RADIUS_M**3)
# Floor of the scalar part q_e0 in Θ̂ (its inverse is singular at a 180° error).
ETA_FLOOR = 1e-3
# Default width w of tanh(S/w) replacing sgn(S) (the paper gives no value).
DEFAULT_SWITCHING_WIDTH = 0.05
# Default µ of the anti-unwinding error vector (the paper gives no value); with it Θ_r is
# singular at 103.1° (0.1: 99.1°, beyond the paper's initial 102.7°, which then diverges).
DEFAULT_ANTI_UNWINDING_MU = 0.01

_SOURCE = "NftsmDqParams"


def validate_orbit(source: str, mean_motion_rad_s: object, mu_m3_s2: object) -> None:
    """Validate the mean motion (finite, ≥ 0) [rad/s] and µ (finite, > 0) [m³/s²]."""
    check.non_negative(source, "mean_motion_rad_s", mean_motion_rad_s, unit="rad/s")
    check.positive(source, "mu_m3_s2", mu_m3_s2, unit="m^3/s^2")


def validate_inertia(inertia: object) -> np.ndarray:
    """A 3×3 symmetric positive-definite inertia [kg m²] (or 3 principal moments)."""
    return check.inertia("PoseController", "inertia_B_kgm2", inertia)


def sig(x: np.ndarray, power: float) -> np.ndarray:
    """``sig(x)^a = sgn(x) |x|^a`` element-wise."""
    return np.sign(x) * np.abs(x) ** power


def clip_norm(v: np.ndarray, limit: float) -> np.ndarray:
    """``v`` scaled down to norm ``limit`` if longer (direction preserved)."""
    norm = float(np.linalg.norm(v))
    return v * (limit / norm) if norm > limit else v


class RelativeMotion(NamedTuple):
    """The dual-quaternion error state of B relative to the desired frame D (= R).

    ``dq_e`` error dual quaternion (8,), short way; ``twist_e`` ``ω̂_e`` (6,) [rad/s; m/s];
    ``twist_B`` the inertial twist ``ω̂`` of B in B axes (6,); ``twist_d_B`` ``q̂_e* ∘ ω̂_d ∘
    q̂_e`` (6,); ``dtwist_d_B`` ``q̂_e* ∘ ω̂̇_d ∘ q̂_e`` (6,); ``gravity_B_m_s2`` the nominal
    gravitational acceleration of B in B axes (3,).
    """

    dq_e: np.ndarray
    twist_e: np.ndarray
    twist_B: np.ndarray
    twist_d_B: np.ndarray
    dtwist_d_B: np.ndarray
    gravity_B_m_s2: np.ndarray


def relative_motion(
    q_BN: np.ndarray,
    omega_BN_B: np.ndarray,
    r_N_m: np.ndarray,
    v_N_m_s: np.ndarray,
    q_RN: np.ndarray,
    omega_RN_B: np.ndarray,
    r_ref_N_m: np.ndarray,
    v_ref_N_m_s: np.ndarray,
    mean_motion_rad_s: float,
    mu_m3_s2: float,
) -> RelativeMotion:
    """The error state of eqs. (6)–(7) from the PoseController inputs (see module docstring)."""
    r = np.asarray(r_N_m, dtype=float)
    v = np.asarray(v_N_m_s, dtype=float)
    r_ref = np.asarray(r_ref_N_m, dtype=float)
    v_ref = np.asarray(v_ref_N_m_s, dtype=float)
    C_BN = to_dcm(q_BN)
    q_BR = error_quaternion(q_RN, q_BN)
    C_BR = to_dcm(q_BR)
    C_RN = to_dcm(q_RN)
    n = mean_motion_rad_s
    omega_NI_N = np.array([0.0, 0.0, n])
    if n > 0.0:
        radius = (mu_m3_s2 / (n * n)) ** (1.0 / 3.0)
        leader_pos_N = np.array([radius, 0.0, 0.0])
        leader_vel_N = np.array([0.0, n * radius, 0.0])
        pos_N = leader_pos_N + r
        gravity_N = -mu_m3_s2 * pos_N / float(np.linalg.norm(pos_N)) ** 3
    else:
        leader_pos_N = np.zeros(3)
        leader_vel_N = np.zeros(3)
        gravity_N = np.zeros(3)

    # inertial twists: B at its origin in B axes; D (= R) at its origin in R axes
    omega_B = np.asarray(omega_BN_B, dtype=float) + C_BN @ omega_NI_N
    vel_B = C_BN @ (v + leader_vel_N + cross3(omega_NI_N, r))
    twist_B = np.concatenate((omega_B, vel_B))
    omega_RN_R = C_BR.T @ np.asarray(omega_RN_B, dtype=float)
    omega_d = C_RN @ omega_NI_N + omega_RN_R
    vel_d = C_RN @ (v_ref + leader_vel_N + cross3(omega_NI_N, r_ref))
    # derivatives of the R-axes components (ω_RN constant in R, v_ref constant in N)
    domega_d = -cross3(omega_RN_R, C_RN @ omega_NI_N)
    dvel_d = -cross3(omega_RN_R, vel_d) + C_RN @ cross3(omega_NI_N, v_ref)

    dq_e = dq.short_way(dq.from_pose(q_BR, C_BN @ (r - r_ref)))
    twist_d_B = dq.transform_twist(dq_e, np.concatenate((omega_d, vel_d)))
    dtwist_d_B = dq.transform_twist(dq_e, np.concatenate((domega_d, dvel_d)))
    return RelativeMotion(
        dq_e=dq_e,
        twist_e=twist_B - twist_d_B,
        twist_B=twist_B,
        twist_d_B=twist_d_B,
        dtwist_d_B=dtwist_d_B,
        gravity_B_m_s2=C_BN @ gravity_N,
    )


def apply_mass(mass_kg: float, inertia_B_kgm2: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``M̂ (ω + ϵ v) = m v + ϵ J ω``: twist-shaped (6,) -> wrench-shaped (6,) [force; torque]."""
    return np.concatenate((mass_kg * twist[3:], inertia_B_kgm2 @ twist[:3]))


def drift_wrench(motion: RelativeMotion, mass_kg: float, inertia_B_kgm2: np.ndarray) -> np.ndarray:
    """``F̂`` of the nominal error dynamics ``M̂0 ω̂̇_e = û_c + F̂`` (eq. 8 plus gravity), (6,)."""
    w_e, w, w_d = motion.twist_e, motion.twist_B, motion.twist_d_B
    feed = dq.cross(w_e, w_d) - motion.dtwist_d_B
    gyro = dq.cross(w, apply_mass(mass_kg, inertia_B_kgm2, w))
    gravity = np.concatenate((mass_kg * motion.gravity_B_m_s2, np.zeros(3)))
    return apply_mass(mass_kg, inertia_B_kgm2, feed) - gyro + gravity


def attitude_state(
    motion: RelativeMotion, anti_unwinding: bool, mu: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``ξ̂`` (6,), ``Θ̂`` (6×6) and ``Θ̂̇`` (6×6) of eq. (10); attitude part per eq. (26) if asked."""
    dq_e = motion.dq_e.copy()
    dq_e[0] = max(dq_e[0], ETA_FLOOR)
    xi = dq.vector_part(dq_e)
    theta = dq.kinematics_matrix(dq_e)
    theta_dot = dq.kinematics_matrix_rate(dq_e, motion.twist_e)
    if anti_unwinding:
        q_e = motion.dq_e[:4]
        xi[:3] = au.error_vector(q_e, mu)
        theta[:3, :3] = au.jacobian(q_e, mu)
        theta_dot[:3, :3] = au.jacobian_rate(q_e, motion.twist_e[:3], mu)
    return xi, theta, theta_dot


def robust_wrench(k_att: np.ndarray, k_pos: np.ndarray, s: np.ndarray, width: float) -> np.ndarray:
    """``K̂ ⊙ tanh(Ŝ/w)`` in wrench slots: position surface -> force, attitude -> torque."""
    t = np.tanh(s / width)
    return np.concatenate((k_pos * t[3:], k_att * t[:3]))


def auxiliary_surface(
    xi: np.ndarray,
    xi_dot: np.ndarray,
    alpha1: np.ndarray,
    alpha2: np.ndarray,
    p1: float,
    delta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``(S_a, W ⊙ ξ̇)`` of eqs. (14)–(16), (18)–(19), element-wise over the 6 components.

    On the exact-zero branch with ``ξ_i = 0`` the product ``W_i ξ̇_i`` is 0 (there
    ``S̄_i = 0`` forces ``ξ̇_i = 0``; its limit is ``p1 α2 sig(ξ)^(2p1−1)`` → 0, Remark 2).
    """
    n = np.shape(xi)[0]
    s_a, w_xi_dot = auxiliary_surface_f(_floats(xi, n), _floats(xi_dot, n), _floats(alpha1, n),
                                        _floats(alpha2, n), p1, _floats(delta, n))
    return np.array(s_a), np.array(w_xi_dot)


def auxiliary_surface_f(
    xi: list[float],
    xi_dot: list[float],
    alpha1: list[float],
    alpha2: list[float],
    p1: float,
    delta: list[float],
) -> tuple[list[float], list[float]]:
    """:func:`auxiliary_surface` on lists of floats (one entry per component)."""
    s_a: list[float] = []
    w_xi_dot: list[float] = []
    for x, xd, a1, a2, d in zip(xi, xi_dot, alpha1, alpha2, delta, strict=True):
        ax = abs(x)
        sig_p = _sig1(x, ax, p1)
        s_bar = xd + a1 * x + a2 * sig_p
        r1 = (2.0 - p1) * d ** (p1 - 1.0)
        r2 = (p1 - 1.0) * d ** (p1 - 2.0)
        if s_bar == 0.0 or ax >= d:  # the power branch
            s_a.append(sig_p)
            w_xi_dot.append(p1 * ax ** (p1 - 1.0) * xd if ax > 0.0 else 0.0)
        else:  # the polynomial branch near ξ = 0
            s_a.append(r1 * x + r2 * _sig1(x, ax, 2.0))
            w_xi_dot.append((r1 + 2.0 * r2 * ax) * xd)
    return s_a, w_xi_dot


def _floats(v: np.ndarray | float, n: int) -> list[float]:
    """``v`` (an (n,) array, or a scalar broadcast to n) as a list of n floats."""
    arr = np.asarray(v, dtype=float)
    return (arr if arr.shape == (n,) else np.broadcast_to(arr, (n,))).tolist()


def _sig1(x: float, abs_x: float, power: float) -> float:
    """``sig(x)^a`` of one float (as :func:`sig`: 0 at 0)."""
    if x > 0.0:
        return abs_x**power
    if x < 0.0:
        return -(abs_x**power)
    return 0.0 * x


Vec = tuple[float, float, float]
Mat3 = tuple[float, float, float, float, float, float, float, float, float]  # row-major


def _dcm(q0: float, q1: float, q2: float, q3: float) -> Mat3:
    """``C(q)`` row-major, as :func:`flight_sw.quaternion.to_dcm`."""
    q00, q11, q22, q33 = q0 * q0, q1 * q1, q2 * q2, q3 * q3
    q01, q02, q03 = q0 * q1, q0 * q2, q0 * q3
    q12, q13, q23 = q1 * q2, q1 * q3, q2 * q3
    return (q00 + q11 - q22 - q33, 2.0 * (q12 + q03), 2.0 * (q13 - q02),
            2.0 * (q12 - q03), q00 - q11 + q22 - q33, 2.0 * (q23 + q01),
            2.0 * (q13 + q02), 2.0 * (q23 - q01), q00 - q11 - q22 + q33)


def _mv(m: Mat3, x: float, y: float, z: float) -> Vec:
    """``M v``."""
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def _mtv(m: Mat3, x: float, y: float, z: float) -> Vec:
    """``Mᵀ v``."""
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _theta_blocks(e0: float, e1: float, e2: float, e3: float, d0: float, d1: float,
                  d2: float, d3: float) -> tuple[Mat3, Mat3]:
    """The blocks Θ, Θ′ of :func:`flight_sw.dual_quaternion.kinematics_matrix`."""
    q0, q1, q2, q3 = HALF * e0, HALF * e1, HALF * e2, HALF * e3
    p0, p1, p2, p3 = HALF * d0, HALF * d1, HALF * d2, HALF * d3
    return ((q0, -q3, q2, q3, q0, -q1, -q2, q1, q0),
            (p0, -p3, p2, p3, p0, -p1, -p2, p1, p0))


def _au_blocks(e0: float, e1: float, e2: float, e3: float, w: Vec, mu: float
               ) -> tuple[Vec, Mat3, Mat3]:
    """Anti-unwinding ``e_r``, ``Θ_r`` and ``Θ̇_r`` (:mod:`flight_sw.control.anti_unwinding`)."""
    g, dg, ddg = au.gain_terms(e0, mu)
    qv = (e1, e2, e3)
    dq0 = -HALF * (e1 * w[0] + e2 * w[1] + e3 * w[2])
    cx = _cross(qv, w)
    dqv = (HALF * (e0 * w[0] + cx[0]), HALF * (e0 * w[1] + cx[1]), HALF * (e0 * w[2] + cx[2]))
    jac = [0.0] * 9
    rate = [0.0] * 9
    sk = (0.0, -e3, e2, e3, 0.0, -e1, -e2, e1, 0.0)
    dsk = (0.0, -dqv[2], dqv[1], dqv[2], 0.0, -dqv[0], -dqv[1], dqv[0], 0.0)
    for i in range(3):
        for j in range(3):
            k = 3 * i + j
            eye = 1.0 if i == j else 0.0
            base = e0 * eye + sk[k]
            jac[k] = HALF * (g * base - dg * qv[i] * qv[j])
            rate[k] = HALF * (dg * dq0 * base + g * (dq0 * eye + dsk[k])
                              - ddg * dq0 * qv[i] * qv[j]
                              - dg * (dqv[i] * qv[j] + qv[i] * dqv[j]))
    return ((g * e1, g * e2, g * e3), (jac[0], jac[1], jac[2], jac[3], jac[4], jac[5], jac[6],
            jac[7], jac[8]), (rate[0], rate[1], rate[2], rate[3], rate[4], rate[5], rate[6],
            rate[7], rate[8]))


def _solve3(m: Mat3, b: Vec) -> Vec:
    """``M⁻¹ b`` by the adjugate (Cramer's rule); M non-singular."""
    c0 = m[4] * m[8] - m[5] * m[7]
    c1 = m[5] * m[6] - m[3] * m[8]
    c2 = m[3] * m[7] - m[4] * m[6]
    inv_det = 1.0 / (m[0] * c0 + m[1] * c1 + m[2] * c2)
    return (
        (c0 * b[0] + (m[2] * m[7] - m[1] * m[8]) * b[1] + (m[1] * m[5] - m[2] * m[4]) * b[2])
        * inv_det,
        (c1 * b[0] + (m[0] * m[8] - m[2] * m[6]) * b[1] + (m[2] * m[3] - m[0] * m[5]) * b[2])
        * inv_det,
        (c2 * b[0] + (m[1] * m[6] - m[0] * m[7]) * b[1] + (m[0] * m[4] - m[1] * m[3]) * b[2])
        * inv_det,
    )


def _dq_mul(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, ...]:
    return dq._mul(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7],
                   b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7])


def _transform(e: tuple[float, ...], w: Vec, v: Vec) -> tuple[Vec, Vec]:
    """:func:`flight_sw.dual_quaternion.transform_twist` on floats: (angular, linear)."""
    conj = (e[0], -e[1], -e[2], -e[3], e[4], -e[5], -e[6], -e[7])
    out = _dq_mul(_dq_mul(conj, (0.0, w[0], w[1], w[2], 0.0, v[0], v[1], v[2])), e)
    return (out[1], out[2], out[3]), (out[5], out[6], out[7])


def _mat3(m: np.ndarray) -> Mat3:
    """A 3×3 array as a row-major tuple."""
    a = m.reshape(-1).tolist()
    return (a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8])


def _clip(x: float, y: float, z: float, limit: float) -> Vec:
    norm = math.sqrt(x * x + y * y + z * z)
    if norm > limit:
        k = limit / norm
        return (x * k, y * k, z * k)
    return (x, y, z)


def _sig_vec(v: list[float], power: float) -> list[float]:
    return [_sig1(x, abs(x), power) for x in v]


@mypyc_attr(native_class=False)  # validates its own field types (see setup.py)
@dataclass(frozen=True)
class NftsmDqParams:
    """Gains and nominal model of the NFTSM law; defaults are seed 000, Section V.

    Attributes (``_att``: real part, attitude, 3 body axes; ``_pos``: dual part, position):
        mass_kg: nominal mass m0 [kg] (> 0).
        inertia_B_kgm2: nominal principal moments J0 [kg m²] (3 numbers > 0).
        alpha1_att, alpha1_pos: α̂1 of eq. (13) [1/s].
        alpha2_att, alpha2_pos: α̂2 of eq. (13) [1/s].
        alpha3_att, alpha3_pos: α̂3 of eq. (17) (reaching gain).
        k_att_Nm: K, torque gain of the attitude surface [N m]; k_pos_N: K′ [N].
        p1: exponent of the auxiliary surface, in (0.5, 1); p2: reaching exponent, (0, 1).
        delta_att, delta_pos: δ, δ′ switching thresholds of eqs. (14)–(15) (> 0).
        switching_width: w of tanh(S/w) replacing sgn(S) (> 0).
        mean_motion_rad_s: n of the leader's circular orbit (0: N inertial, no gravity).
        mu_m3_s2: gravitational parameter [m³/s²].
        anti_unwinding: use e_r of eq. (26) as the attitude state.
        anti_unwinding_mu: µ of eqs. (25)–(26) (> 0).
        max_force_N, max_torque_Nm: optional output norm limits (inf: unbounded).
    """

    mass_kg: float = 100.0
    inertia_B_kgm2: tuple[float, float, float] = (18.0, 18.0, 24.0)
    alpha1_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha1_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha2_att: tuple[float, float, float] = (0.05, 0.05, 0.05)
    alpha2_pos: tuple[float, float, float] = (0.1, 0.1, 0.1)
    alpha3_att: tuple[float, float, float] = (2.0, 2.0, 2.0)
    alpha3_pos: tuple[float, float, float] = (2.0, 2.0, 2.0)
    k_att_Nm: tuple[float, float, float] = (20.0, 20.0, 20.0)
    k_pos_N: tuple[float, float, float] = (20.0, 20.0, 20.0)
    p1: float = 0.6
    p2: float = 0.67
    delta_att: float = 0.05
    delta_pos: float = 0.001
    switching_width: float = DEFAULT_SWITCHING_WIDTH
    mean_motion_rad_s: float = 0.0
    mu_m3_s2: float = MU_EARTH_M3_S2
    anti_unwinding: bool = False
    anti_unwinding_mu: float = DEFAULT_ANTI_UNWINDING_MU
    max_force_N: float = math.inf
    max_torque_Nm: float = math.inf

    def __post_init__(self) -> None:
        s = _SOURCE
        check.positive(s, "mass_kg", self.mass_kg, unit="kg")
        for key in (
            "inertia_B_kgm2",
            "alpha1_att",
            "alpha1_pos",
            "alpha2_att",
            "alpha2_pos",
            "alpha3_att",
            "alpha3_pos",
            "k_att_Nm",
            "k_pos_N",
        ):
            object.__setattr__(self, key, check.triple(s, key, getattr(self, key), 0.0,
                                                        lo_open=True))
        check.number(s, "p1", self.p1, 0.5, 1.0, lo_open=True, hi_open=True)
        check.number(s, "p2", self.p2, 0.0, 1.0, lo_open=True, hi_open=True)
        for key in ("delta_att", "delta_pos", "switching_width", "anti_unwinding_mu"):
            check.positive(s, key, getattr(self, key))
        validate_orbit(s, self.mean_motion_rad_s, self.mu_m3_s2)
        check.flag(s, "anti_unwinding", self.anti_unwinding)
        check.limit(s, "max_force_N", self.max_force_N, unit="N")
        check.limit(s, "max_torque_Nm", self.max_torque_Nm, unit="N m")


def _dual_gain(att: tuple[float, float, float], pos: tuple[float, float, float]) -> np.ndarray:
    return np.array(att + pos, dtype=float)


class NftsmDq:
    """Dual-quaternion NFTSM pose controller (implements ``PoseController``, ``InertiaAware``).

    Stateless apart from the nominal inertia, which :meth:`set_inertia_B_kgm2` replaces.
    """

    def __init__(self, params: NftsmDqParams) -> None:
        self._params = params
        self._inertia = validate_inertia(params.inertia_B_kgm2)
        p = params
        self._alpha1 = _dual_gain(p.alpha1_att, p.alpha1_pos)
        self._alpha2 = _dual_gain(p.alpha2_att, p.alpha2_pos)
        self._alpha3 = _dual_gain(p.alpha3_att, p.alpha3_pos)
        self._k_att = np.array(p.k_att_Nm, dtype=float)
        self._k_pos = np.array(p.k_pos_N, dtype=float)
        self._delta = np.array([p.delta_att] * N_AXES + [p.delta_pos] * N_AXES)
        # the same as floats, for wrench_B
        self._alpha1_f: list[float] = self._alpha1.tolist()
        self._alpha2_f: list[float] = self._alpha2.tolist()
        self._alpha3_f: list[float] = self._alpha3.tolist()
        self._k_att_f: list[float] = self._k_att.tolist()
        self._k_pos_f: list[float] = self._k_pos.tolist()
        self._delta_f: list[float] = self._delta.tolist()
        self._inertia_f = _mat3(self._inertia)

    @property
    def params(self) -> NftsmDqParams:
        """The gains this controller was built with."""
        return self._params

    @property
    def inertia_B_kgm2(self) -> np.ndarray:
        """The nominal inertia in use (3×3) [kg m²]."""
        return self._inertia.copy()

    def set_inertia_B_kgm2(self, inertia_B_kgm2: np.ndarray) -> None:
        """Use ``inertia_B_kgm2`` (3×3 SPD, or 3 principal moments) [kg m²] from now on."""
        self._inertia = validate_inertia(inertia_B_kgm2)
        self._inertia_f = _mat3(self._inertia)

    def surface(self, xi: np.ndarray, xi_dot: np.ndarray) -> np.ndarray:
        """``Ŝ = ξ̂̇ + α̂1 ⊙ ξ̂ + α̂2 ⊙ Ŝ_a`` (eq. 13), (6,)."""
        s_a, _ = auxiliary_surface(
            xi, xi_dot, self._alpha1, self._alpha2, self._params.p1, self._delta
        )
        return np.asarray(xi_dot + self._alpha1 * xi + self._alpha2 * s_a)

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
        """Law (17): the demanded wrench [force_B_N; torque_B_Nm], shape (6,).

        Evaluated on floats, equal to :meth:`wrench_B_reference` up to round-off
        (``tests/flight_sw/control/test_nftsm_dq.py``): the same steps (module docstring)
        without one array per 3- or 6-vector; Θ̂ is block lower triangular, so its inverse
        is two 3×3 solves.
        """
        p = self._params
        b0, b1, b2, b3 = np.asarray(q_BN, dtype=float).tolist()
        w_bn = np.asarray(omega_BN_B, dtype=float).tolist()
        r = np.asarray(r_N_m, dtype=float).tolist()
        v = np.asarray(v_N_m_s, dtype=float).tolist()
        n0, n1, n2, n3 = np.asarray(q_RN, dtype=float).tolist()
        w_rn = np.asarray(omega_RN_B, dtype=float).tolist()
        r_ref = np.asarray(r_ref_N_m, dtype=float).tolist()
        v_ref = np.asarray(v_ref_N_m_s, dtype=float).tolist()
        # relative motion (eqs. 6-7; relative_motion)
        c_bn = _dcm(b0, b1, b2, b3)
        qe = dq._mul(n0, -n1, -n2, -n3, 0.0, 0.0, 0.0, 0.0, b0, b1, b2, b3, 0.0, 0.0, 0.0, 0.0)
        c_br = _dcm(qe[0], qe[1], qe[2], qe[3])
        c_rn = _dcm(n0, n1, n2, n3)
        n = p.mean_motion_rad_s
        w_ni: Vec = (0.0, 0.0, n)
        lead_v: Vec = (0.0, 0.0, 0.0)
        grav: Vec = (0.0, 0.0, 0.0)
        if n > 0.0:
            radius = (p.mu_m3_s2 / (n * n)) ** (1.0 / 3.0)
            lead_v = (0.0, n * radius, 0.0)
            px, py, pz = radius + r[0], r[1], r[2]
            k = -p.mu_m3_s2 / math.sqrt(px * px + py * py + pz * pz) ** 3
            grav = (k * px, k * py, k * pz)
        w_ni_b = _mv(c_bn, w_ni[0], w_ni[1], w_ni[2])
        om_b: Vec = (w_bn[0] + w_ni_b[0], w_bn[1] + w_ni_b[1], w_bn[2] + w_ni_b[2])
        cr = _cross(w_ni, (r[0], r[1], r[2]))
        vel_b = _mv(c_bn, v[0] + lead_v[0] + cr[0], v[1] + lead_v[1] + cr[1],
                    v[2] + lead_v[2] + cr[2])
        om_rn_r = _mtv(c_br, w_rn[0], w_rn[1], w_rn[2])
        w_ni_r = _mv(c_rn, w_ni[0], w_ni[1], w_ni[2])
        om_d: Vec = (w_ni_r[0] + om_rn_r[0], w_ni_r[1] + om_rn_r[1], w_ni_r[2] + om_rn_r[2])
        cr = _cross(w_ni, (r_ref[0], r_ref[1], r_ref[2]))
        vel_d = _mv(c_rn, v_ref[0] + lead_v[0] + cr[0], v_ref[1] + lead_v[1] + cr[1],
                    v_ref[2] + lead_v[2] + cr[2])
        dom = _cross(om_rn_r, w_ni_r)
        dom_d: Vec = (-dom[0], -dom[1], -dom[2])
        cv = _cross(om_rn_r, vel_d)
        cr = _cross(w_ni, (v_ref[0], v_ref[1], v_ref[2]))
        cn = _mv(c_rn, cr[0], cr[1], cr[2])
        dvel_d: Vec = (-cv[0] + cn[0], -cv[1] + cn[1], -cv[2] + cn[2])
        pe = _mv(c_bn, r[0] - r_ref[0], r[1] - r_ref[1], r[2] - r_ref[2])
        half = dq._mul(qe[0], qe[1], qe[2], qe[3], 0.0, 0.0, 0.0, 0.0,
                       0.0, pe[0], pe[1], pe[2], 0.0, 0.0, 0.0, 0.0)
        e: tuple[float, ...] = (qe[0], qe[1], qe[2], qe[3], HALF * half[0], HALF * half[1],
                                HALF * half[2], HALF * half[3])
        if e[0] < 0.0:
            e = tuple(-x for x in e)
        wd, vd = _transform(e, om_d, vel_d)
        dwd, dvd = _transform(e, dom_d, dvel_d)
        nu = [om_b[0] - wd[0], om_b[1] - wd[1], om_b[2] - wd[2],
              vel_b[0] - vd[0], vel_b[1] - vd[1], vel_b[2] - vd[2]]
        # attitude state (eq. 10; attitude_state), Θ̂ = [[th, 0], [thd, th]]
        f0 = max(e[0], ETA_FLOOR)
        th, thd = _theta_blocks(f0, e[1], e[2], e[3], e[4], e[5], e[6], e[7])
        de = dq._mul(f0, e[1], e[2], e[3], e[4], e[5], e[6], e[7],
                     0.0, nu[0], nu[1], nu[2], 0.0, nu[3], nu[4], nu[5])
        th_dot, thd_dot = _theta_blocks(HALF * de[0], HALF * de[1], HALF * de[2],
                                        HALF * de[3], HALF * de[4], HALF * de[5],
                                        HALF * de[6], HALF * de[7])
        xi = [e[1], e[2], e[3], e[5], e[6], e[7]]
        th_r = th
        th_r_dot = th_dot
        if p.anti_unwinding:
            er, th_r, th_r_dot = _au_blocks(e[0], e[1], e[2], e[3], (nu[0], nu[1], nu[2]),
                                            p.anti_unwinding_mu)
            xi[0], xi[1], xi[2] = er
        nu_w: Vec = (nu[0], nu[1], nu[2])
        nu_v: Vec = (nu[3], nu[4], nu[5])
        x_r = _mv(th_r, nu[0], nu[1], nu[2])
        x_d1 = _mv(thd, nu[0], nu[1], nu[2])
        x_d2 = _mv(th, nu[3], nu[4], nu[5])
        xi_dot = [x_r[0], x_r[1], x_r[2], x_d1[0] + x_d2[0], x_d1[1] + x_d2[1],
                  x_d1[2] + x_d2[2]]
        # surfaces (eqs. 13-19) and the bracket of law (17)
        a1 = self._alpha1_f
        a2 = self._alpha2_f
        a3 = self._alpha3_f
        s_a, w_xd = auxiliary_surface_f(xi, xi_dot, a1, a2, p.p1, self._delta_f)
        s_sl = [xi_dot[i] + a1[i] * xi[i] + a2[i] * s_a[i] for i in range(6)]
        sp = _sig_vec(s_sl, p.p2)
        t_r = _mv(th_r_dot, nu_w[0], nu_w[1], nu_w[2])
        t_d1 = _mv(thd_dot, nu_w[0], nu_w[1], nu_w[2])
        t_d2 = _mv(th_dot, nu_v[0], nu_v[1], nu_v[2])
        tdot_nu = [t_r[0], t_r[1], t_r[2], t_d1[0] + t_d2[0], t_d1[1] + t_d2[1],
                   t_d1[2] + t_d2[2]]
        br = [tdot_nu[i] + a1[i] * xi_dot[i] + a2[i] * w_xd[i] + a3[i] * sp[i]
              for i in range(6)]
        # ω̂̇* = −Θ̂⁻¹ bracket, by blocks: Θ_r x = b_r; Θ y = b_d − Θ′ x
        acc_w = _solve3(th_r, (br[0], br[1], br[2]))
        tx = _mv(thd, acc_w[0], acc_w[1], acc_w[2])
        acc_v = _solve3(th, (br[3] - tx[0], br[4] - tx[1], br[5] - tx[2]))
        acc_w = (-acc_w[0], -acc_w[1], -acc_w[2])
        acc_v = (-acc_v[0], -acc_v[1], -acc_v[2])
        # drift (eq. 8 + gravity; drift_wrench): M̂ [ω̂_e × ω̂_d' − ω̂̇_d'] − ω̂ × M̂ ω̂ + m ĝ
        m = p.mass_kg
        jm = self._inertia_f
        fa = _cross(nu_w, wd)
        fb = _cross(nu_w, vd)
        fc = _cross(nu_v, wd)
        feed_w: Vec = (fa[0] - dwd[0], fa[1] - dwd[1], fa[2] - dwd[2])
        feed_v: Vec = (fb[0] + fc[0] - dvd[0], fb[1] + fc[1] - dvd[1], fb[2] + fc[2] - dvd[2])
        h_b = _mv(jm, om_b[0], om_b[1], om_b[2])
        g_w = _cross(om_b, (m * vel_b[0], m * vel_b[1], m * vel_b[2]))
        g_v1 = _cross(om_b, h_b)
        g_v2 = _cross(vel_b, (m * vel_b[0], m * vel_b[1], m * vel_b[2]))
        j_feed = _mv(jm, feed_w[0], feed_w[1], feed_w[2])
        j_acc = _mv(jm, acc_w[0], acc_w[1], acc_w[2])
        g_b = _mv(c_bn, grav[0], grav[1], grav[2])
        tk = [math.tanh(x / p.switching_width) for x in s_sl]
        kp = self._k_pos_f
        ka = self._k_att_f
        force = [m * acc_v[i] - (m * feed_v[i] - g_w[i] + m * g_b[i]) - kp[i] * tk[3 + i]
                 for i in range(3)]
        torque = [j_acc[i] - (j_feed[i] - (g_v1[i] + g_v2[i])) - ka[i] * tk[i]
                  for i in range(3)]
        fo = _clip(force[0], force[1], force[2], p.max_force_N)
        to = _clip(torque[0], torque[1], torque[2], p.max_torque_Nm)
        return np.array((fo[0], fo[1], fo[2], to[0], to[1], to[2]))

    def wrench_B_reference(
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
        """:meth:`wrench_B` composed from this module's array functions, term by term as the
        paper writes it (the reference the float form is tested against)."""
        p = self._params
        motion = relative_motion(
            q_BN,
            omega_BN_B,
            r_N_m,
            v_N_m_s,
            q_RN,
            omega_RN_B,
            r_ref_N_m,
            v_ref_N_m_s,
            p.mean_motion_rad_s,
            p.mu_m3_s2,
        )
        xi, theta, theta_dot = attitude_state(motion, p.anti_unwinding, p.anti_unwinding_mu)
        nu = motion.twist_e
        xi_dot = theta @ nu
        s_a, w_xi_dot = auxiliary_surface(xi, xi_dot, self._alpha1, self._alpha2, p.p1, self._delta)
        s = xi_dot + self._alpha1 * xi + self._alpha2 * s_a
        bracket = (
            theta_dot @ nu
            + self._alpha1 * xi_dot
            + self._alpha2 * w_xi_dot
            + self._alpha3 * sig(s, p.p2)
        )
        accel = -np.linalg.solve(theta, bracket)
        wrench = (
            apply_mass(p.mass_kg, self._inertia, accel)
            - drift_wrench(motion, p.mass_kg, self._inertia)
            - robust_wrench(self._k_att, self._k_pos, s, p.switching_width)
        )
        return np.concatenate(
            (clip_norm(wrench[:3], p.max_force_N), clip_norm(wrench[3:], p.max_torque_Nm))
        )
