"""Small pure dual-quaternion library: poses, twists (velocity motors) and error kinematics.

What it does: the dual-quaternion operations of the 6-DoF laws of seed 000 (eqs. 1–7, 10):
product, conjugate, pose <-> dual quaternion, error dual quaternion, the transformation of
a twist between frames, the dual cross product, and the kinematics matrix ``Θ̂`` of the
vector part ``ξ̂ = vec(q̂)`` with its time derivative.

Conventions (those of :mod:`flight_sw.quaternion`, extended):
- A dual quaternion ``q̂ = q + ϵ q′`` (``ϵ² = 0``) is a numpy array of shape (8,):
  ``(q0, q1, q2, q3, q′0, q′1, q′2, q′3)``, real part first, both parts scalar-first.
- The pose of frame B relative to frame A with attitude ``q_BA`` (maps A to B, as
  everywhere in the project) and the position ``r_B`` [m] of B's origin relative to A's,
  in B axes, is ``q̂_BA = q_BA + ϵ ½ q_BA ⊗ (0, r_B)`` (= ``q_BA + ϵ ½ (0, r_A) ⊗ q_BA``).
  Composition: ``q̂_CA = q̂_BA ∘ q̂_CB``; the error of B relative to a desired frame D is
  ``q̂_BD = q̂_DA* ∘ q̂_BA`` with ``r_B`` then the position error ``p_e`` in B axes (eq. 6).
- A dual vector (a twist ``ω̂ = ω + ϵ v``, a wrench ``f + ϵ τ`` or the vector part
  ``ξ̂``) is an array of shape (6,): the real 3-vector then the dual 3-vector.
- Kinematics ``q̂̇ = ½ q̂ ∘ (0, ω̂)`` with the body twist ``ω̂ = ω_B + ϵ v_B`` (angular rate
  [rad/s] and velocity of B's origin [m/s], both in B axes, relative to A): for the error
  dual quaternion ``v`` is ``ṗ_B + ω × p_B`` (eq. 7).

Inputs/outputs: float64 arrays; positions [m], rates [rad/s], velocities [m/s]. Nothing
here keeps state.

Assumptions: unit dual quaternions (``|q| = 1``, ``q·q′ = 0``) where a docstring says so,
not checked, for speed.

Sources: seed 000 (Sun, Huang, Wang, Xiao, Yeatman, "Dual quaternion based finite-time
tracking control for mechatronic systems with actuation allocation"), eqs. (1)–(7), (10);
Filipe & Tsiotras 2013, "Simultaneous position and attitude control without linear and
angular velocity feedback using dual quaternions", ACC, and Filipe & Tsiotras 2015,
"Adaptive position and attitude-tracking controller for satellite proximity operations
using dual quaternions", JGCD 38(4) 566–577 (the body-frame pose/twist conventions and
the kinematics ``q̂̇ = ½ q̂ ∘ ω̂``).
"""

from __future__ import annotations

import numpy as np

from flight_sw import quaternion as quat
from flight_sw.quaternion import cross as cross3

HALF = 0.5


def _pure(v: np.ndarray) -> np.ndarray:
    """The pure quaternion ``(0, v)`` of a 3-vector."""
    return np.array([0.0, float(v[0]), float(v[1]), float(v[2])])


def identity() -> np.ndarray:
    """The identity dual quaternion ``1 + ϵ 0`` (no rotation, no translation)."""
    return np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dual-quaternion product ``â ∘ b̂ = a ⊗ b + ϵ (a ⊗ b′ + a′ ⊗ b)`` (eq. 4)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    real = quat.multiply(a[:4], b[:4])
    dual = quat.multiply(a[:4], b[4:]) + quat.multiply(a[4:], b[:4])
    return np.concatenate((real, dual))


def conjugate(a: np.ndarray) -> np.ndarray:
    """Conjugate ``â* = a* + ϵ a′*`` (both parts conjugated); the inverse of a unit one."""
    a = np.asarray(a, dtype=float)
    return np.concatenate((quat.conjugate(a[:4]), quat.conjugate(a[4:])))


def from_pose(q_BA: np.ndarray, r_B_m: np.ndarray) -> np.ndarray:
    """``q̂ = q_BA + ϵ ½ q_BA ⊗ (0, r_B)``: the pose with attitude q_BA and position r_B [m]."""
    q = np.asarray(q_BA, dtype=float)
    return np.concatenate((q, HALF * quat.multiply(q, _pure(r_B_m))))


def to_pose(dq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`from_pose`: ``(q_BA, r_B)`` with ``(0, r_B) = 2 q* ⊗ q′`` [m]."""
    dq = np.asarray(dq, dtype=float)
    q = dq[:4].copy()
    r = 2.0 * quat.multiply(quat.conjugate(q), dq[4:])
    return q, r[1:].copy()


def error(dq_desired: np.ndarray, dq: np.ndarray) -> np.ndarray:
    """Error dual quaternion ``q̂_e = q̂_d* ∘ q̂ = q_e + ϵ ½ q_e ⊗ p_e`` (eq. 6).

    No sign normalisation: ``q̂_e`` and ``−q̂_e`` are the same pose (see :func:`short_way`).
    """
    return multiply(conjugate(dq_desired), dq)


def short_way(dq: np.ndarray) -> np.ndarray:
    """``q̂`` or ``−q̂``, whichever has a real scalar part ``q0 ≥ 0`` (same pose)."""
    dq = np.asarray(dq, dtype=float)
    return -dq if dq[0] < 0.0 else dq.copy()


def vector_part(dq: np.ndarray) -> np.ndarray:
    """``ξ̂ = vec(q) + ϵ vec(q′)`` as a dual vector (6,) (the state of eqs. 10–16)."""
    dq = np.asarray(dq, dtype=float)
    return np.concatenate((dq[1:4], dq[5:8]))


def scalar_part(dq: np.ndarray) -> tuple[float, float]:
    """``η̂ = q0 + ϵ q′0`` as the pair ``(q0, q′0)``."""
    dq = np.asarray(dq, dtype=float)
    return float(dq[0]), float(dq[4])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dual cross product ``â × b̂ = a × b + ϵ (a × b′ + a′ × b)`` of dual vectors (eq. 2)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    real = cross3(a[:3], b[:3])
    dual = cross3(a[:3], b[3:]) + cross3(a[3:], b[:3])
    return np.concatenate((real, dual))


def transform_twist(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``q̂* ∘ (0, ŵ) ∘ q̂``: a twist of frame D in D axes re-expressed in B (eq. 7).

    With ``q̂ = q̂_BD`` (B's pose relative to D, position ``p_B``) and ``ŵ = ω_D + ϵ v_D``
    (D's twist at D's origin, D axes), the result is ``C_BD ω_D + ϵ (C_BD v_D + (C_BD ω_D) ×
    p_B)``: the same motion, at B's origin and in B axes.
    """
    w = np.asarray(twist, dtype=float)
    wq = np.concatenate((_pure(w[:3]), _pure(w[3:])))
    out = multiply(multiply(conjugate(dq), wq), dq)
    return np.concatenate((out[1:4], out[5:8]))


def derivative(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """Kinematics ``q̂̇ = ½ q̂ ∘ (0, ω̂)`` (eq. 7) with the body twist ``ω̂`` (6,)."""
    w = np.asarray(twist, dtype=float)
    wq = np.concatenate((_pure(w[:3]), _pure(w[3:])))
    return HALF * multiply(dq, wq)


def kinematics_matrix(dq: np.ndarray) -> np.ndarray:
    """``Θ̂(q̂) = ½ (η̂ I + ξ̂×)`` as a 6×6 real matrix with ``ξ̂̇ = Θ̂ ω̂`` (eq. 10).

    Block form ``[[Θ, 0], [Θ′, Θ]]`` with ``Θ = ½ (q0 I + [vec(q)×])`` and
    ``Θ′ = ½ (q′0 I + [vec(q′)×])``. Its real block is singular only at ``q0 = 0`` (180°).
    """
    dq = np.asarray(dq, dtype=float)
    eye = np.eye(3)
    theta = HALF * (dq[0] * eye + quat.skew(dq[1:4]))
    theta_d = HALF * (dq[4] * eye + quat.skew(dq[5:8]))
    out = np.zeros((6, 6))
    out[:3, :3] = theta
    out[3:, 3:] = theta
    out[3:, :3] = theta_d
    return out


def kinematics_matrix_rate(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``Θ̂̇`` (6×6) along the motion ``q̂̇ = ½ q̂ ∘ ω̂``: ``½ (η̂̇ I + ξ̂̇×)`` blockwise.

    ``η̂̇ = −½ ⟨ξ̂, ω̂⟩`` in dual form, i.e. ``η̇ = −½ ξᵀω``, ``η̇′ = −½ (ξᵀω′ + ξ′ᵀω)``.
    """
    return kinematics_matrix(derivative(dq, twist))
