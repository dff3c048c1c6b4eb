"""Anti-unwinding attitude error function and error vector of seed 000 (eqs. 25–26).

What it does: for an error quaternion ``q_e = (q_e0, q_ev)`` (scalar first),
    ``ϕ = 2 (λ1 + λ2 q_e0² − exp(h))``,  ``h = q_e0² / sqrt(q_e0² + µ)``        (25)
    ``e_r = g(q_e0) q_ev``,  ``g(q_e0) = exp(h) q_e0 (|q_e0| + 2µ) / (|q_e0| + µ)²``  (26)
and the Jacobian ``Θ_r`` of ``e_r`` along the attitude kinematics ``q̇_e = ½ q_e ⊗ (0, ω_e)``,
    ``ė_r = Θ_r ω_e``,  ``Θ_r = ½ [g (q_e0 I + [q_ev×]) − g′ q_ev q_evᵀ]``,
with its time derivative, so that ``e_r`` can replace ``vec(q_e)`` as the attitude state
of the sliding-mode laws (Remark 4 of seed 000).

Properties: ``g`` is odd, so ``e_r(−q) = e_r(q)`` (both representations of an attitude
give the same error: no unwinding); ``e_r`` is continuous everywhere and vanishes both at
the target (θ = 0) and at θ = ±π (where ``g(0) = 0``; the short-way sign switch
``sgn(q_e0) q_ev`` is discontinuous there); ``|e_r| ≤ max|g| = g(1) = exp(1/sqrt(1+µ))
(1 + 2µ)/(1 + µ)²``; ``e_r · q_ev ≥ 0`` for ``q_e0 ≥ 0``, i.e. ``e_r`` points along the
short-way rotation axis. ``ϕ`` is even in ``q_e0``, continuous and bounded on [−π, π].

Caution (not in the paper): a continuous, sign-invariant error vector that vanishes at
both θ = 0 and θ = π has a maximum of ``|e_r|`` in between (about θ ≈ 104° for small µ,
90° for large µ); there the component of ``Θ_r`` along the rotation axis vanishes
(``det Θ_r = ⅛ g² (g q_e0 − g′ |q_ev|²)``), so a law inverting ``Θ_r`` is singular at that
angle and, beyond it, drives the error towards π. :func:`axis_gain` returns that component
so callers can check it.

Inputs/outputs: ``q_e`` a unit quaternion (4,); ``µ`` (``mu``), ``λ1``, ``λ2`` positive
dimensionless constants; ``ω_e`` [rad/s]; outputs dimensionless (``ė_r`` in 1/s).

Assumptions: unit quaternion (not checked). ``g′′`` jumps at ``q_e0 = 0`` (the ``|q_e0|``
of eq. 26); ``e_r`` and ``Θ_r`` are continuous there.

Source: seed 000, Remark 3 and eqs. (25)–(26), Fig. 1; the Jacobian is derived here.
"""

from __future__ import annotations

import math

import numpy as np

from flight_sw import vec3
from flight_sw.vec3 import Mat3, Vec3

HALF = 0.5


def _h_terms(q0: float, mu: float) -> tuple[float, float, float]:
    """``h``, ``h′``, ``h′′`` of ``h(q0) = q0² / sqrt(q0² + µ)``."""
    s = q0 * q0 + mu
    h = q0 * q0 / math.sqrt(s)
    dh = q0 * (q0 * q0 + 2.0 * mu) / s**1.5
    ddh = (2.0 * mu * mu - mu * q0 * q0) / s**2.5
    return h, dh, ddh


def _k_terms(q0: float, mu: float) -> tuple[float, float, float]:
    """``k``, ``k′``, ``k′′`` of the odd ``k(q0) = q0 (|q0| + 2µ)/(|q0| + µ)²``."""
    a = abs(q0) + mu
    k = q0 * (abs(q0) + 2.0 * mu) / (a * a)
    dk = 2.0 * mu * mu / a**3
    ddk = -math.copysign(6.0 * mu * mu / a**4, q0)
    return k, dk, ddk


def gain_terms(q0: float, mu: float) -> tuple[float, float, float]:
    """``g``, ``g′``, ``g′′`` of ``g(q0) = exp(h) k`` (eq. 26), derivatives w.r.t. ``q0``."""
    h, dh, ddh = _h_terms(q0, mu)
    k, dk, ddk = _k_terms(q0, mu)
    e = math.exp(h)
    g = e * k
    dg = e * (dh * k + dk)
    ddg = e * ((dh * dh + ddh) * k + 2.0 * dh * dk + ddk)
    return g, dg, ddg


def error_function(q_e: np.ndarray, mu: float, lambda1: float, lambda2: float) -> float:
    """The scalar attitude error function ``ϕ`` of eq. (25)."""
    q0 = float(q_e[0])
    h, _, _ = _h_terms(q0, mu)
    return 2.0 * (lambda1 + lambda2 * q0 * q0 - math.exp(h))


def error_vector(q_e: np.ndarray, mu: float) -> np.ndarray:
    """The anti-unwinding attitude error vector ``e_r = g(q_e0) q_ev`` of eq. (26)."""
    g, _, _ = gain_terms(float(q_e[0]), mu)
    return g * np.asarray(q_e[1:4], dtype=float)


def error_vector_bound(mu: float) -> float:
    """``max |e_r| ≤ g(1) = exp(1/sqrt(1+µ)) (1+2µ)/(1+µ)²`` (``|q_ev| ≤ 1``, ``g`` increasing)."""
    return gain_terms(1.0, mu)[0]


def error_state(e0: float, e1: float, e2: float, e3: float, w: Vec3, mu: float
                ) -> tuple[Vec3, Mat3, Mat3]:
    """``e_r``, ``Θ_r`` and ``Θ̇_r`` (row-major) on floats for ``q_e = (e0, e1, e2, e3)`` and
    ``ω_e = w`` [rad/s]: the one implementation (the pose laws call it; :func:`jacobian` and
    :func:`jacobian_rate` wrap it)."""
    g, dg, ddg = gain_terms(e0, mu)
    qv = (e1, e2, e3)
    dq0 = -HALF * (e1 * w[0] + e2 * w[1] + e3 * w[2])
    cx = vec3.cross(qv, w)
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


def jacobian(q_e: np.ndarray, mu: float) -> np.ndarray:
    """``Θ_r`` (3×3) with ``ė_r = Θ_r ω_e`` for ``q̇_e = ½ q_e ⊗ (0, ω_e)``."""
    e0, e1, e2, e3 = np.asarray(q_e, dtype=float).tolist()
    return np.reshape(error_state(e0, e1, e2, e3, (0.0, 0.0, 0.0), mu)[1], (3, 3))


def jacobian_rate(q_e: np.ndarray, omega_e: np.ndarray, mu: float) -> np.ndarray:
    """``Θ̇_r`` (3×3) along ``q̇_e = ½ q_e ⊗ (0, ω_e)``, ``ω_e`` [rad/s]."""
    e0, e1, e2, e3 = np.asarray(q_e, dtype=float).tolist()
    w1, w2, w3 = np.asarray(omega_e, dtype=float).tolist()
    return np.reshape(error_state(e0, e1, e2, e3, (w1, w2, w3), mu)[2], (3, 3))


def axis_gain(q_e: np.ndarray, mu: float) -> float:
    """``g q_e0 − g′ |q_ev|²``: twice ``Θ_r``'s eigenvalue along ``q_ev`` (0: singular)."""
    q0 = float(q_e[0])
    g, dg, _ = gain_terms(q0, mu)
    return g * q0 - dg * (1.0 - q0 * q0)
