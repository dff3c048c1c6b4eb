"""Modified Rodrigues parameters (MRP): conversions, shadow set and kinematics, pure functions.

What it does: the MRP ``σ = e tan(φ/4)`` of a rotation by ``φ`` about the unit axis ``e``;
conversion from and to the project's scalar-first quaternions, the shadow set, and the
kinematics matrix ``F(σ)`` of ``σ̇ = F(σ) ω`` with its inverse and time derivative.

Formulas (``s = σᵀσ``, ``[σ×]`` the cross-product matrix):
- ``σ = q_vec / (1 + q0)``; ``q0 = (1 − s)/(1 + s)``, ``q_vec = 2σ/(1 + s)``;
- shadow set ``σˢ = −σ/s``: the same attitude (it is ``−q``); :func:`from_quaternion`
  returns the representative with ``|σ| ≤ 1`` (rotation ≤ 180°, the short way);
- ``F(σ) = ¼ [(1 − s) I + 2 [σ×] + 2 σσᵀ]`` (seed 001 eq. (1));
- ``F⁻¹(σ) = 16/(1 + s)² F(σ)ᵀ`` (seed 001, below eq. (1); named ``G`` there);
- ``Ḟ(σ, σ̇) = ½ [−(σᵀσ̇) I + [σ̇×] + σ̇σᵀ + σσ̇ᵀ]`` (term-by-term derivative of ``F``);
- the body rate of an MRP trajectory ``ω = F⁻¹(σ) σ̇`` (:func:`rate_to_omega`) and its
  derivative ``ω̇ = Ġ σ̇ + G σ̈`` with ``Ġ = 16/(1 + s)² Ḟᵀ − 2ṡ/(1 + s) G``,
  ``ṡ = 2σᵀσ̇`` (:func:`omega_and_rate`; product rule on ``G = 16/(1 + s)² Fᵀ``).

Conventions: a quaternion ``q_BN`` (maps N to B, see :mod:`flight_sw.quaternion`) gives
``σ_BN`` with ``σ̇_BN = F(σ_BN) ω_BN_B`` (ω in body axes [rad/s]); the DCM is the
quaternion's, ``C(σ) = I + (8[σ×]² − 4(1 − s)[σ×])/(1 + s)²``.

Inputs/outputs: float64 numpy arrays, shape (3,) for MRP and rates, (4,) for quaternions,
(3, 3) for matrices; MRP are dimensionless, rates in rad/s.

Assumptions: unit quaternions; :func:`to_quaternion` and the kinematics accept any finite
σ (the shadow switch is the caller's, via :func:`from_quaternion` or :func:`switched`).

Sources: seed 001 (MRP kinematics eq. (1) and ``F⁻¹``); Schaub & Junkins 2018,
"Analytical Mechanics of Space Systems", 4th ed., §3.8 (MRP, shadow set, ``B(σ) = 4F(σ)``,
the DCM in terms of σ).
"""

from __future__ import annotations

import numpy as np

from flight_sw.quaternion import skew
from flight_sw.vec3 import Mat3, Vec3, mat_t_vec, vec3

# |σ| above which :func:`switched` maps to the shadow set (σ and σˢ coincide at |σ| = 1).
SHADOW_SWITCH_NORM_SQ = 1.0
# F(σ) = KINEMATICS_SCALE · B(σ) with Schaub's B(σ) = (1 − s) I + 2[σ×] + 2σσᵀ.
KINEMATICS_SCALE = 0.25
# F⁻¹(σ) = INVERSE_SCALE / (1 + s)² · F(σ)ᵀ.
INVERSE_SCALE = 16.0


def shadow(sigma: np.ndarray) -> np.ndarray:
    """The shadow MRP ``σˢ = −σ/|σ|²`` (same attitude); raises ``ValueError`` for σ = 0."""
    s = np.asarray(sigma, dtype=float)
    norm_sq = float(s @ s)
    if norm_sq == 0.0:
        raise ValueError("the zero MRP has no shadow (its shadow is at infinity)")
    return -s / norm_sq


def switched(sigma: np.ndarray) -> np.ndarray:
    """``σ`` if ``|σ| ≤ 1``, else its shadow ``σˢ``: the representative of rotation ≤ 180°."""
    s = np.asarray(sigma, dtype=float)
    return shadow(s) if float(s @ s) > SHADOW_SWITCH_NORM_SQ else s.copy()


def from_quaternion_f(q0: float, q1: float, q2: float, q3: float) -> Vec3:
    """``σ = q_vec / (1 + q0)`` on floats, of ``q`` or ``−q`` whichever has ``q0 ≥ 0``
    (``|σ| ≤ 1``: the short way)."""
    if q0 < 0.0:
        q0, q1, q2, q3 = -q0, -q1, -q2, -q3
    return (q1 / (1.0 + q0), q2 / (1.0 + q0), q3 / (1.0 + q0))


def from_quaternion(q: np.ndarray) -> np.ndarray:
    """The MRP of the unit quaternion ``q`` with ``|σ| ≤ 1`` (``q`` and ``−q`` agree)."""
    q0, q1, q2, q3 = np.asarray(q, dtype=float).tolist()
    return np.array(from_quaternion_f(q0, q1, q2, q3))


def inverse_factor(norm_sq: float) -> float:
    """``16/(1 + s)²``: ``F⁻¹(σ) = 16/(1 + s)² F(σ)ᵀ`` for ``s = σᵀσ``."""
    return INVERSE_SCALE / (1.0 + norm_sq) ** 2


def to_quaternion(sigma: np.ndarray) -> np.ndarray:
    """The unit quaternion ``((1 − s)/(1 + s), 2σ/(1 + s))`` of σ; ``q0 ≥ 0`` iff ``|σ| ≤ 1``."""
    s0, s1, s2 = np.asarray(sigma, dtype=float).tolist()
    norm_sq = s0 * s0 + s1 * s1 + s2 * s2  # one fixed order (``s @ s`` is the CPU's BLAS)
    denom = 1.0 + norm_sq
    return np.array([(1.0 - norm_sq) / denom, 2.0 * s0 / denom, 2.0 * s1 / denom,
                     2.0 * s2 / denom])


def to_dcm(sigma: np.ndarray) -> np.ndarray:
    """``C(σ) = I + (8[σ×]² − 4(1 − s)[σ×])/(1 + s)²``, equal to the quaternion's DCM."""
    s = np.asarray(sigma, dtype=float)
    norm_sq = float(s @ s)
    sk = skew(s)
    return np.eye(3) + (8.0 * sk @ sk - 4.0 * (1.0 - norm_sq) * sk) / (1.0 + norm_sq) ** 2


def kinematics(s0: float, s1: float, s2: float) -> Mat3:
    """``F(σ) = ¼[(1 − s) I + 2[σ×] + 2σσᵀ]`` on floats, row-major (seed 001 eq. (1)):
    the one implementation (the flight software's per-cycle laws call it directly)."""
    k = KINEMATICS_SCALE
    a = 1.0 - (s0 * s0 + s1 * s1 + s2 * s2)
    return (k * (a + 2.0 * s0 * s0), k * (2.0 * s0 * s1 - 2.0 * s2), k * (2.0 * s0 * s2 + 2.0 * s1),
            k * (2.0 * s1 * s0 + 2.0 * s2), k * (a + 2.0 * s1 * s1), k * (2.0 * s1 * s2 - 2.0 * s0),
            k * (2.0 * s2 * s0 - 2.0 * s1), k * (2.0 * s2 * s1 + 2.0 * s0), k * (a + 2.0 * s2 * s2))


def kinematics_rate(s: Vec3, sd: Vec3) -> Mat3:
    """``Ḟ(σ, σ̇) = ½[−(σᵀσ̇) I + [σ̇×] + σ̇σᵀ + σσ̇ᵀ]`` on floats, row-major."""
    s0, s1, s2 = s
    d0, d1, d2 = sd
    dot = s0 * d0 + s1 * d1 + s2 * d2
    return (0.5 * (2.0 * d0 * s0 - dot), 0.5 * (d0 * s1 + s0 * d1 - d2),
            0.5 * (d0 * s2 + s0 * d2 + d1),
            0.5 * (d1 * s0 + s1 * d0 + d2), 0.5 * (2.0 * d1 * s1 - dot),
            0.5 * (d1 * s2 + s1 * d2 - d0),
            0.5 * (d2 * s0 + s2 * d0 - d1), 0.5 * (d2 * s1 + s2 * d1 + d0),
            0.5 * (2.0 * d2 * s2 - dot))


def kinematics_matrix(sigma: np.ndarray) -> np.ndarray:
    """``F(σ)`` (:func:`kinematics`) as a 3×3 array, ``σ̇ = F(σ) ω``."""
    s0, s1, s2 = np.asarray(sigma, dtype=float).tolist()
    return np.array(kinematics(s0, s1, s2)).reshape(3, 3)


def kinematics_matrix_inverse(sigma: np.ndarray) -> np.ndarray:
    """``G(σ) = F⁻¹(σ) = 16/(1 + s)² F(σ)ᵀ``, so ``ω = G(σ) σ̇`` (seed 001)."""
    s = np.asarray(sigma, dtype=float)
    return inverse_factor(float(s @ s)) * kinematics_matrix(s).T


def kinematics_matrix_rate(sigma: np.ndarray, sigma_dot: np.ndarray) -> np.ndarray:
    """``Ḟ(σ, σ̇)`` (:func:`kinematics_rate`) as a 3×3 array: the derivative of ``F(σ(t))``."""
    s = vec3(np.asarray(sigma, dtype=float))
    sd = vec3(np.asarray(sigma_dot, dtype=float))
    return np.array(kinematics_rate(s, sd)).reshape(3, 3)


def rate_to_omega(sigma: np.ndarray, sigma_dot: np.ndarray) -> np.ndarray:
    """``ω = F⁻¹(σ) σ̇`` [rad/s]: the body rate of the MRP trajectory at ``σ`` with rate ``σ̇``."""
    s = vec3(sigma)
    f = inverse_factor(s[0] * s[0] + s[1] * s[1] + s[2] * s[2])
    return np.array(_g_times(f, kinematics(s[0], s[1], s[2]), vec3(sigma_dot)))


def _g_times(f: float, fk: Mat3, x: Vec3) -> Vec3:
    """``G x = f Fᵀ x`` on floats, one fixed order (numpy's 3×3 products are the CPU's
    BLAS): :func:`rate_to_omega` and :func:`omega_and_rate` share it."""
    w = mat_t_vec(fk, *x)
    return (f * w[0], f * w[1], f * w[2])


def omega_and_rate(sigma: np.ndarray, sigma_dot: np.ndarray, sigma_ddot: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``(ω, ω̇)`` of an MRP trajectory: :func:`rate_to_omega` and its derivative
    ``ω̇ = Ġ σ̇ + G σ̈`` [rad/s²] (module docstring), sharing ``G = F⁻¹(σ)``."""
    s, sd, sdd = vec3(sigma), vec3(sigma_dot), vec3(sigma_ddot)
    norm_sq = s[0] * s[0] + s[1] * s[1] + s[2] * s[2]
    s_dot = 2.0 * (s[0] * sd[0] + s[1] * sd[1] + s[2] * sd[2])
    f = inverse_factor(norm_sq)
    fk = kinematics(s[0], s[1], s[2])
    # ω = G σ̇ with G = f Fᵀ; ω̇ = Ġ σ̇ + G σ̈ with Ġ = f Ḟᵀ − (2ṡ/(1 + s)) G
    omega = _g_times(f, fk, sd)
    a = _g_times(f, kinematics_rate(s, sd), sd)
    b = _g_times(f, fk, sdd)
    c = 2.0 * s_dot / (1.0 + norm_sq)
    return np.array(omega), np.array([a[i] - c * omega[i] + b[i] for i in range(3)])
