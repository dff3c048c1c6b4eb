"""Attitude reference of a manoeuvre, as the bench's truth metrics see it.

What it does
    Pure functions giving the reference attitude q_RN(t) (scalar first, maps N to R) and
    the reference rate ω_RN_R(t) [rad/s] of a manoeuvre:

    - ``"step"``: q_RN = the target from ``t_start_s`` on, ω = 0 (the bench's historical
      behaviour).
    - ``"mrp_polynomial"``: the modified Rodrigues parameters of the reference are
      polynomials in τ = t − t_start_s (held at τ = 0 before the start), one per axis,
      coefficients highest power first (``numpy.polyval`` order):
      σ_d,i(τ) = Σ_k c_i,k τ^(deg−k) (seed 001 §5: σd1 = −1.475e-8 t⁴ + 4.559e-6 t³
      − 5.105e-4 t² + 0.02439 t + 0.08381, ...).

    MRP → quaternion: q0 = (1 − σ²)/(1 + σ²), q_v = 2σ/(1 + σ²); rate from the MRP
    kinematics σ̇ = ¼ B(σ) ω, B = (1 − σ²)I + 2[σ×] + 2σσᵀ, inverted with
    B Bᵀ = (1 + σ²)² I: ω = 4 Bᵀ σ̇ / (1 + σ²)² (Schaub & Junkins, "Analytical
    Mechanics of Space Systems", §3.7, eqs. 3.147, 3.154, 3.163). Schaub's attitude
    matrix equals the bench's C(q_BN) (``bench.station.dynamics.rigid_body``), so σ here is the
    MRP of q_RN in the same convention.

    ``attitude_error_deg`` and ``rate_error_B`` compare a true state with it:
    δω_B = ω_BN_B − C(q_BN) C(q_RN)ᵀ ω_RN_R.

Inputs: t_s [s]. Outputs: quaternions [-], rates [rad/s], angles [deg].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from bench.station.dynamics.rigid_body import Quat, Vec3, rotate_B_to_N, rotate_N_to_B
from dbc import validation as check
from dbc.errors import ConfigError

KIND_STEP = "step"
KIND_MRP_POLYNOMIAL = "mrp_polynomial"
KINDS = (KIND_STEP, KIND_MRP_POLYNOMIAL)
MRP_AXES = 3
MRP_RATE_FACTOR = 4.0
RAD_DEG = 180.0 / math.pi


def polyval(coefficients: Sequence[float], x: float) -> float:
    """Σ c_k x^(deg−k), highest power first (Horner)."""
    acc = 0.0
    for c in coefficients:
        acc = acc * x + c
    return acc


def polyder(coefficients: Sequence[float]) -> tuple[float, ...]:
    """Coefficients of the derivative, highest power first."""
    deg = len(coefficients) - 1
    return tuple(c * (deg - k) for k, c in enumerate(coefficients[:-1])) or (0.0,)


def mrp_to_quat(sigma: Vec3) -> Quat:
    """q (scalar first) of the MRP σ: q0 = (1 − σ²)/(1 + σ²), q_v = 2σ/(1 + σ²)."""
    s2 = sigma[0] ** 2 + sigma[1] ** 2 + sigma[2] ** 2
    k = 1.0 / (1.0 + s2)
    return ((1.0 - s2) * k, 2.0 * sigma[0] * k, 2.0 * sigma[1] * k, 2.0 * sigma[2] * k)


def mrp_rate_to_omega(sigma: Vec3, sigma_dot: Vec3) -> Vec3:
    """ω = 4 B(σ)ᵀ σ̇ / (1 + σ²)² [rad/s] (module docstring)."""
    s1, s2, s3 = sigma
    d1, d2, d3 = sigma_dot
    ss = s1 * s1 + s2 * s2 + s3 * s3
    a = 1.0 - ss
    sd = s1 * d1 + s2 * d2 + s3 * d3
    # Bᵀ σ̇ = (1 − σ²) σ̇ − 2 σ × σ̇ + 2 σ (σ·σ̇)
    bx = a * d1 - 2.0 * (s2 * d3 - s3 * d2) + 2.0 * s1 * sd
    by = a * d2 - 2.0 * (s3 * d1 - s1 * d3) + 2.0 * s2 * sd
    bz = a * d3 - 2.0 * (s1 * d2 - s2 * d1) + 2.0 * s3 * sd
    k = MRP_RATE_FACTOR / (1.0 + ss) ** 2
    return (k * bx, k * by, k * bz)


@dataclass(frozen=True)
class ReferenceParams:
    """A manoeuvre: ``kind``, step target q_target_BN, MRP polynomials, start time [s]."""

    kind: str = KIND_STEP
    q_target_BN: Quat = (1.0, 0.0, 0.0, 0.0)
    mrp_coefficients: tuple[tuple[float, ...], ...] = ((0.0,), (0.0,), (0.0,))
    t_start_s: float = 0.0
    source: str = field(default="ReferenceParams", compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(self.source, "kind", self.kind, f"one of {KINDS}")
        co = self.mrp_coefficients
        if isinstance(co, str) or not isinstance(co, Sequence) or len(co) != MRP_AXES:
            raise ConfigError(
                self.source, "mrp_coefficients", co, "3 non-empty lists of finite numbers"
            )
        object.__setattr__(self, "mrp_coefficients", tuple(
            check.vector(self.source, f"mrp_coefficients[{i}]", c, None) for i, c in enumerate(co)
        ))
        object.__setattr__(
            self, "t_start_s", check.number(self.source, "t_start_s", self.t_start_s)
        )


def reference_mrp(p: ReferenceParams, t_s: float) -> tuple[Vec3, Vec3]:
    """(σ_RN(t), σ̇_RN(t) [1/s]) of an ``mrp_polynomial`` manoeuvre."""
    tau = max(0.0, t_s - p.t_start_s)
    c = p.mrp_coefficients
    sigma = (polyval(c[0], tau), polyval(c[1], tau), polyval(c[2], tau))
    if t_s < p.t_start_s:
        return sigma, (0.0, 0.0, 0.0)
    rate = (polyval(polyder(c[0]), tau), polyval(polyder(c[1]), tau),
            polyval(polyder(c[2]), tau))
    return sigma, rate


def reference(p: ReferenceParams, t_s: float) -> tuple[Quat, Vec3]:
    """(q_RN(t), ω_RN_R(t) [rad/s]) of the manoeuvre ``p`` at ``t_s``."""
    if p.kind == KIND_STEP:
        return p.q_target_BN, (0.0, 0.0, 0.0)
    sigma, sigma_dot = reference_mrp(p, t_s)
    return mrp_to_quat(sigma), mrp_rate_to_omega(sigma, sigma_dot)


def attitude_error_deg(q_BN: Sequence[float], q_RN: Quat) -> float:
    """Rotation angle between the attitudes q_BN and q_RN [deg]."""
    d = abs(q_BN[0] * q_RN[0] + q_BN[1] * q_RN[1] + q_BN[2] * q_RN[2] + q_BN[3] * q_RN[3])
    return 2.0 * math.acos(min(1.0, d)) * RAD_DEG


def rate_error_B(q_BN: Quat, omega_BN_B: Vec3, q_RN: Quat, omega_RN_R: Vec3) -> Vec3:
    """δω_B = ω_BN_B − C(q_BN) C(q_RN)ᵀ ω_RN_R [rad/s]."""
    w_ref_B = rotate_N_to_B(q_BN, rotate_B_to_N(q_RN, omega_RN_R))
    return (omega_BN_B[0] - w_ref_B[0], omega_BN_B[1] - w_ref_B[1], omega_BN_B[2] - w_ref_B[2])
