"""Reference form of the RLS inertia identifier's equations, on numpy (seed 001, §2).

The package computes the regressor, the window sums and the RLS step once, on floats
(:mod:`flight_sw.estimation.rls_kernel`). These are the same equations written as matrix
expressions with numpy and LAPACK (``np.linalg.solve`` for the gain), as the package had
them before: the tests hold the kernel to them.

Equations (module docstring of :mod:`flight_sw.estimation.rls_inertia`): ``J ω = Ω(ω) θ``;
the period-integrated Euler equation ``Φ θ = T̄`` with
``Φ = Ω((ω_k − ω_{k−1})/h) + ½ ([ω_{k−1}×] Ω(ω_{k−1}) + [ω_k×] Ω(ω_k))``, and its window
form; the RLS step with forgetting factor λ, ``K = P Φᵀ (λ I + Φ P Φᵀ)⁻¹``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from flight_sw.quaternion import skew

N_AXES = 3
NS_PER_S = 1_000_000_000
TRAPEZOID_WEIGHT = 0.5


def momentum_regressor(omega_B: np.ndarray) -> np.ndarray:
    """``Ω(ω)`` (3×6) with ``J ω = Ω(ω) θ``."""
    w1, w2, w3 = np.asarray(omega_B, dtype=float).tolist()
    return np.array(
        [
            [w1, w2, w3, 0.0, 0.0, 0.0],
            [0.0, w1, 0.0, w2, w3, 0.0],
            [0.0, 0.0, w1, 0.0, w2, w3],
        ]
    )


def euler_regressor(omega_prev_B: np.ndarray, omega_B: np.ndarray, dt_s: float) -> np.ndarray:
    """``Φ`` (3×6) of the period-integrated Euler equation, ``Φ θ ≈ mean torque`` [N m]."""
    w0 = np.asarray(omega_prev_B, dtype=float)
    w1 = np.asarray(omega_B, dtype=float)
    gyro = skew(w0) @ momentum_regressor(w0) + skew(w1) @ momentum_regressor(w1)
    return momentum_regressor((w1 - w0) / dt_s) + TRAPEZOID_WEIGHT * gyro


def window_equation_reference(
    t_ns: Sequence[int], omega_B: Sequence[np.ndarray], torque_B_Nm: Sequence[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """``(Φ, y)`` over the samples given (``torque_B_Nm[0]`` unused)."""
    if len(t_ns) == 2:  # one period: the single-step form
        return euler_regressor(omega_B[0], omega_B[1], (t_ns[1] - t_ns[0]) / NS_PER_S), \
            np.asarray(torque_B_Nm[1], dtype=float)
    h = np.diff(np.asarray(t_ns, dtype=float)) / NS_PER_S  # period lengths [s]
    g = np.stack([skew(w) @ momentum_regressor(w) for w in omega_B])  # (N+1)×3×6
    tau = np.stack([np.asarray(x, dtype=float) for x in torque_B_Nm[1:]])
    total_s = float(h.sum())
    gyro = TRAPEZOID_WEIGHT * np.einsum("k,kij->ij", h, g[:-1] + g[1:])
    dw = (np.asarray(omega_B[-1], dtype=float) - np.asarray(omega_B[0], dtype=float)) / total_s
    return momentum_regressor(dw) + gyro / total_s, h @ tau / total_s


def rls_step_reference(
    p: np.ndarray, theta: np.ndarray, info: np.ndarray, phi: np.ndarray, y: np.ndarray,
    lam: float, trace_cap: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One RLS step (seed 001 §2): ``(P_k, θ_k, R_k)``, the gain by LAPACK's LU solve."""
    p_phi_t = p @ phi.T
    s = lam * np.eye(N_AXES) + phi @ p_phi_t
    gain = np.linalg.solve(s, p_phi_t.T).T  # P Φᵀ S⁻¹ (S symmetric)
    theta_new = theta + gain @ (y - phi @ theta)
    p_new = (p - gain @ phi @ p) / lam
    p_new = 0.5 * (p_new + p_new.T)
    trace = float(np.trace(p_new))
    if trace > trace_cap:
        p_new *= trace_cap / trace
    return p_new, theta_new, lam * info + phi.T @ phi
