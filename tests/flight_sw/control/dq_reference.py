"""Reference form of the dual-quaternion pose laws (seed 000): the paper's terms as arrays.

The package evaluates the NFTSM and TSM laws once, on floats
(:mod:`flight_sw.control.dq_error_state`, :mod:`flight_sw.control.nftsm_dq`,
:mod:`flight_sw.control.tsm_dq`). Here the same laws are composed from array functions,
term by term as seed 000 writes them — relative motion (eqs. 6–7), the kinematics
matrix and its rate (eq. 10, anti-unwinding eqs. 25–26), the drift of the nominal error
dynamics (eq. 8 plus gravity), the surfaces (eqs. 12–16) and law (17) — as the package had
them before: the tests hold the float laws to them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from flight_sw import dual_quaternion as dq
from flight_sw.control.anti_unwinding import gain_terms
from flight_sw.control.dq_error_state import ETA_FLOOR
from flight_sw.control.nftsm_dq import NftsmDq, auxiliary_surface
from flight_sw.control.tsm_dq import XI_FLOOR, TsmDq
from flight_sw.quaternion import cross as cross3
from flight_sw.quaternion import error_quaternion, skew, to_dcm

HALF = 0.5


def au_jacobian(q_e: np.ndarray, mu: float) -> np.ndarray:
    """``Θ_r = ½ [g (q_e0 I + [q_ev×]) − g′ q_ev q_evᵀ]`` as arrays."""
    q0 = float(q_e[0])
    qv = np.asarray(q_e[1:4], dtype=float)
    g, dg, _ = gain_terms(q0, mu)
    return HALF * (g * (q0 * np.eye(3) + skew(qv)) - dg * np.outer(qv, qv))


def au_jacobian_rate(q_e: np.ndarray, omega_e: np.ndarray, mu: float) -> np.ndarray:
    """``Θ̇_r`` along ``q̇_e = ½ q_e ⊗ (0, ω_e)`` as arrays."""
    q0 = float(q_e[0])
    qv = np.asarray(q_e[1:4], dtype=float)
    w = np.asarray(omega_e, dtype=float)
    g, dg, ddg = gain_terms(q0, mu)
    dq0 = -HALF * float(qv @ w)
    dqv = HALF * (q0 * w + cross3(qv, w))
    eye = np.eye(3)
    return HALF * (
        dg * dq0 * (q0 * eye + skew(qv))
        + g * (dq0 * eye + skew(dqv))
        - ddg * dq0 * np.outer(qv, qv)
        - dg * (np.outer(dqv, qv) + np.outer(qv, dqv))
    )


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
        xi[:3] = gain_terms(float(q_e[0]), mu)[0] * np.asarray(q_e[1:4], dtype=float)
        theta[:3, :3] = au_jacobian(q_e, mu)
        theta_dot[:3, :3] = au_jacobian_rate(q_e, motion.twist_e[:3], mu)
    return xi, theta, theta_dot


def robust_wrench(k_att: np.ndarray, k_pos: np.ndarray, s: np.ndarray, width: float) -> np.ndarray:
    """``K̂ ⊙ tanh(Ŝ/w)`` in wrench slots: position surface -> force, attitude -> torque."""
    t = np.tanh(s / width)
    return np.concatenate((k_pos * t[3:], k_att * t[:3]))



def nftsm_wrench_reference(
    law: NftsmDq,
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
    """:meth:`NftsmDq.wrench_B` composed from the array functions above, term by term as the
    paper writes it (the reference the float form is tested against)."""
    p = law.params
    alpha1, alpha2, alpha3 = (np.array(a + b) for a, b in (
        (p.alpha1_att, p.alpha1_pos), (p.alpha2_att, p.alpha2_pos), (p.alpha3_att, p.alpha3_pos)))
    delta = np.array([p.delta_att] * 3 + [p.delta_pos] * 3)
    inertia = law.inertia_B_kgm2
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
    s_a, w_xi_dot = auxiliary_surface(xi, xi_dot, alpha1, alpha2, p.p1, delta)
    s = xi_dot + alpha1 * xi + alpha2 * s_a
    bracket = (
        theta_dot @ nu
        + alpha1 * xi_dot
        + alpha2 * w_xi_dot
        + alpha3 * sig(s, p.p2)
    )
    accel = -np.linalg.solve(theta, bracket)
    wrench = (
        apply_mass(p.mass_kg, inertia, accel)
        - drift_wrench(motion, p.mass_kg, inertia)
        - robust_wrench(np.array(p.k_att_Nm), np.array(p.k_pos_N), s, p.switching_width)
    )
    return np.concatenate(
        (clip_norm(wrench[:3], p.max_force_N), clip_norm(wrench[3:], p.max_torque_Nm))
    )


def tsm_wrench_reference(
    law: TsmDq,
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
    """The TSM law (eq. 12 surface, law 17 structure) composed from the array functions."""
    p = law.params
    b = np.array(p.b_att + p.b_pos, dtype=float)
    alpha3 = np.array(p.alpha3_att + p.alpha3_pos, dtype=float)
    inertia = law.inertia_B_kgm2
    motion = relative_motion(q_BN, omega_BN_B, r_N_m, v_N_m_s, q_RN, omega_RN_B, r_ref_N_m,
                             v_ref_N_m_s, p.mean_motion_rad_s, p.mu_m3_s2)
    xi, theta, theta_dot = attitude_state(motion, p.anti_unwinding, p.anti_unwinding_mu)
    nu = motion.twist_e
    xi_dot = theta @ nu
    s = xi_dot + b * sig(xi, p.alpha)
    abs_xi = np.maximum(np.abs(xi), XI_FLOOR)
    bracket = theta_dot @ nu + p.alpha * b * abs_xi ** (p.alpha - 1.0) * xi_dot + alpha3 * sig(
        s, p.p2)
    accel = -np.linalg.solve(theta, bracket)
    wrench = (
        apply_mass(p.mass_kg, inertia, accel)
        - drift_wrench(motion, p.mass_kg, inertia)
        - robust_wrench(np.array(p.k_att_Nm), np.array(p.k_pos_N), s, p.switching_width)
    )
    return np.concatenate(
        (clip_norm(wrench[:3], p.max_force_N), clip_norm(wrench[3:], p.max_torque_Nm))
    )
