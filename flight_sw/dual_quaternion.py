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
here keeps state. The products, the twist transformation and the blocks of ``Θ̂`` are
also given on floats (``_mul``, :func:`transform`, :func:`theta_blocks`: the one
implementation, which the array functions wrap and the per-cycle laws call).

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
from flight_sw.vec3 import Mat3, Vec3

HALF = 0.5


def _pure(v: np.ndarray) -> np.ndarray:
    """The pure quaternion ``(0, v)`` of a 3-vector."""
    return np.array([0.0, float(v[0]), float(v[1]), float(v[2])])


def identity() -> np.ndarray:
    """The identity dual quaternion ``1 + ϵ 0`` (no rotation, no translation)."""
    return np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dual-quaternion product ``â ∘ b̂ = a ⊗ b + ϵ (a ⊗ b′ + a′ ⊗ b)`` (eq. 4).

    Written out on floats (the hot path of the 6-DoF law: one array per product instead
    of three Hamilton products and their sums); each component is evaluated in the order
    of :func:`flight_sw.quaternion.multiply`, so the result is bit-identical to building it
    from three of those (``tests/flight_sw/test_dual_quaternion.py`` checks it).
    """
    a0, a1, a2, a3, c0, c1, c2, c3 = np.asarray(a, dtype=float).tolist()
    b0, b1, b2, b3, e0, e1, e2, e3 = np.asarray(b, dtype=float).tolist()
    return np.array(_mul(a0, a1, a2, a3, c0, c1, c2, c3, b0, b1, b2, b3, e0, e1, e2, e3))


def _mul(
    a0: float, a1: float, a2: float, a3: float, c0: float, c1: float, c2: float, c3: float,
    b0: float, b1: float, b2: float, b3: float, e0: float, e1: float, e2: float, e3: float,
) -> tuple[float, float, float, float, float, float, float, float]:
    """``(a + ϵ c) ∘ (b + ϵ e)`` on floats (see :func:`multiply`)."""
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
        (a0 * e0 - a1 * e1 - a2 * e2 - a3 * e3) + (c0 * b0 - c1 * b1 - c2 * b2 - c3 * b3),
        (a0 * e1 + a1 * e0 + a2 * e3 - a3 * e2) + (c0 * b1 + c1 * b0 + c2 * b3 - c3 * b2),
        (a0 * e2 - a1 * e3 + a2 * e0 + a3 * e1) + (c0 * b2 - c1 * b3 + c2 * b0 + c3 * b1),
        (a0 * e3 + a1 * e2 - a2 * e1 + a3 * e0) + (c0 * b3 + c1 * b2 - c2 * b1 + c3 * b0),
    )


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
    a0, a1, a2, c0, c1, c2 = np.asarray(a, dtype=float).tolist()
    b0, b1, b2, e0, e1, e2 = np.asarray(b, dtype=float).tolist()
    return np.array(
        (
            a1 * b2 - a2 * b1,
            a2 * b0 - a0 * b2,
            a0 * b1 - a1 * b0,
            (a1 * e2 - a2 * e1) + (c1 * b2 - c2 * b1),
            (a2 * e0 - a0 * e2) + (c2 * b0 - c0 * b2),
            (a0 * e1 - a1 * e0) + (c0 * b1 - c1 * b0),
        )
    )


def transform_twist(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``q̂* ∘ (0, ŵ) ∘ q̂``: a twist of frame D in D axes re-expressed in B (eq. 7).

    With ``q̂ = q̂_BD`` (B's pose relative to D, position ``p_B``) and ``ŵ = ω_D + ϵ v_D``
    (D's twist at D's origin, D axes), the result is ``C_BD ω_D + ϵ (C_BD v_D + (C_BD ω_D) ×
    p_B)``: the same motion, at B's origin and in B axes.
    """
    w1, w2, w3, v1, v2, v3 = np.asarray(twist, dtype=float).tolist()
    a0, a1, a2, a3, c0, c1, c2, c3 = np.asarray(dq, dtype=float).tolist()
    w, v = transform(a0, a1, a2, a3, c0, c1, c2, c3, (w1, w2, w3), (v1, v2, v3))
    return np.array((w[0], w[1], w[2], v[0], v[1], v[2]))


def transform(a0: float, a1: float, a2: float, a3: float, c0: float, c1: float, c2: float,
              c3: float, w: Vec3, v: Vec3) -> tuple[Vec3, Vec3]:
    """:func:`transform_twist` on floats: ``q̂* ∘ (0, w + ϵ v) ∘ q̂`` as (angular, linear)."""
    # (q̂* ∘ ŵ) ∘ q̂, as two products of multiply
    p = _mul(a0, -a1, -a2, -a3, c0, -c1, -c2, -c3, 0.0, w[0], w[1], w[2], 0.0, v[0], v[1], v[2])
    out = _mul(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], a0, a1, a2, a3, c0, c1, c2, c3)
    return (out[1], out[2], out[3]), (out[5], out[6], out[7])


def derivative(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """Kinematics ``q̂̇ = ½ q̂ ∘ (0, ω̂)`` (eq. 7) with the body twist ``ω̂`` (6,)."""
    w1, w2, w3, v1, v2, v3 = np.asarray(twist, dtype=float).tolist()
    a0, a1, a2, a3, c0, c1, c2, c3 = np.asarray(dq, dtype=float).tolist()
    out = _mul(a0, a1, a2, a3, c0, c1, c2, c3, 0.0, w1, w2, w3, 0.0, v1, v2, v3)
    return HALF * np.array(out)


def kinematics_matrix(dq: np.ndarray) -> np.ndarray:
    """``Θ̂(q̂) = ½ (η̂ I + ξ̂×)`` as a 6×6 real matrix with ``ξ̂̇ = Θ̂ ω̂`` (eq. 10).

    Block form ``[[Θ, 0], [Θ′, Θ]]`` with ``Θ = ½ (q0 I + [vec(q)×])`` and
    ``Θ′ = ½ (q′0 I + [vec(q′)×])``. Its real block is singular only at ``q0 = 0`` (180°).
    """
    e0, e1, e2, e3, e4, e5, e6, e7 = np.asarray(dq, dtype=float).tolist()
    th, thd = theta_blocks(e0, e1, e2, e3, e4, e5, e6, e7)
    out = np.zeros((6, 6))
    out[:3, :3] = out[3:, 3:] = np.reshape(th, (3, 3))
    out[3:, :3] = np.reshape(thd, (3, 3))
    return out


def theta_blocks(e0: float, e1: float, e2: float, e3: float, d0: float, d1: float,
                 d2: float, d3: float) -> tuple[Mat3, Mat3]:
    """The blocks Θ, Θ′ of :func:`kinematics_matrix` on floats (row-major 3×3)."""
    q0, q1, q2, q3 = HALF * e0, HALF * e1, HALF * e2, HALF * e3
    p0, p1, p2, p3 = HALF * d0, HALF * d1, HALF * d2, HALF * d3
    return ((q0, -q3, q2, q3, q0, -q1, -q2, q1, q0),
            (p0, -p3, p2, p3, p0, -p1, -p2, p1, p0))


def kinematics_matrix_rate(dq: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """``Θ̂̇`` (6×6) along the motion ``q̂̇ = ½ q̂ ∘ ω̂``: ``½ (η̂̇ I + ξ̂̇×)`` blockwise.

    ``η̂̇ = −½ ⟨ξ̂, ω̂⟩`` in dual form, i.e. ``η̇ = −½ ξᵀω``, ``η̇′ = −½ (ξᵀω′ + ξ′ᵀω)``.
    """
    return kinematics_matrix(derivative(dq, twist))
