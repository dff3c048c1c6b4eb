"""Polynomial MRP guidance: a reference attitude whose MRP components are polynomials in time.

What it does: ``σ_RN(τ)`` with each component a polynomial in ``τ = (t − t0)`` [s],
converted to the reference quaternion, with the reference rate and angular acceleration
from the MRP kinematics, all analytic:
- MRP → quaternion (``s = σᵀσ``): ``q0 = (1 − s)/(1 + s)``, ``q_vec = 2σ/(1 + s)``
  (``σ = e tan(φ/4)``, the MRP of the rotation the quaternion describes, same N → R sense,
  so ``C(σ) = C(q)`` of :mod:`flight_sw.quaternion`);
- kinematics (seed 001 eq. (1)): ``σ̇ = F(σ) ω``, ``F(σ) = ¼ B(σ)``,
  ``B(σ) = (1 − s) I3 + 2[σ×] + 2σσᵀ``; inverse (seed 001, after eq. (1)):
  ``F⁻¹ = 16/(1 + s)² Fᵀ``, so ``ω_RN_R = 4/(1 + s)² Bᵀ σ̇``;
- its derivative (product rule, ``ṡ = 2σᵀσ̇``):
  ``ω̇ = 4/(1 + s)² (Ḃᵀ σ̇ + Bᵀ σ̈) − 2 ṡ/(1 + s) · ω``, with
  ``Ḃᵀ = −ṡ I3 − 2[σ̇×] + 2(σσ̇ᵀ + σ̇σᵀ)``.

Default trajectory: seed 001 §5 (its desired MRP ``σ_d``, 100 s manoeuvre):
    ``σd1 = −1.475e−8 τ⁴ + 4.559e−6 τ³ − 5.105e−4 τ² + 0.02439 τ + 0.08381``,
    ``σd2 = 1.136e−6 τ³ − 2.5e−4 τ² + 0.01768 τ + 0.101``,
    ``σd3 = 8.899e−7 τ³ − 2.088e−4 τ² + 0.01578 τ + 0.1205``.
The seed's text prints the σd3 term as "− 2.088 × 10⁻⁴" without ``t²``; read as ``τ²``: it
is the only reading with which all three components arrive together (σ ≈ 0.50, 0.51, 0.50)
at rest (|σ̇| < 2e−3 /s) at τ = 100 s, and which starts at the seed's initial MRP
(0.08381, 0.101, 0.1205).

Outside ``[0, duration_s]`` the reference holds ``σ(0)`` (before) or ``σ(duration_s)``
(after) with zero rate and acceleration (the polynomials diverge beyond the manoeuvre).

Inputs/outputs: see :mod:`flight_sw.guidance.base`; parameters ``sigma_coeffs`` (per axis,
ascending powers: entry ``i`` multiplies ``τ^i`` and has unit 1/sⁱ), ``t0_ns`` [ns, the
caller's time base], ``duration_s`` [s].

Assumptions: the MRP stays in the unit ball on the manoeuvre (true for the default:
|σ| < 0.88), so ``q0 > 0`` and the quaternion is continuous; no switching to the shadow
set is done. The MRP helpers live here on purpose (no dependency on a shared MRP module).

Sources: seed 001 eq. (1) and the expression of F⁻¹ after it (MRP kinematics), §5
(desired trajectory σ_d); Schaub & Junkins, "Analytical Mechanics of Space Systems",
MRP ↔ quaternion relations and ``ω = 4/(1 + σ²)² Bᵀ σ̇``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from dbc.errors import ConfigError
from flight_sw import validation as check
from flight_sw.guidance.base import VECTOR_SIZE, AttitudeReference
from flight_sw.quaternion import skew

NS_PER_S = 1_000_000_000
_SOURCE = "MrpPolynomialGuidance"
# Kinematics constants (ω = OMEGA_GAIN/(1 + s)² Bᵀ σ̇; B = (1 − s) I + 2[σ×] + 2σσᵀ).
OMEGA_GAIN = 4.0
B_CROSS = 2.0
B_OUTER = 2.0

# Seed 001 §5, desired MRP σ_d (ascending powers of τ [s]); see the module docstring.
SEED001_SIGMA_COEFFS: tuple[tuple[float, ...], ...] = (
    (0.08381, 0.02439, -5.105e-4, 4.559e-6, -1.475e-8),
    (0.101, 0.01768, -2.5e-4, 1.136e-6),
    (0.1205, 0.01578, -2.088e-4, 8.899e-7),
)
SEED001_DURATION_S = 100.0  # "The time of the attitude control is 100 s."


def mrp_to_quaternion(sigma: np.ndarray) -> np.ndarray:
    """Scalar-first quaternion of the MRP ``σ``: ``((1 − s)/(1 + s), 2σ/(1 + s))``, s = σᵀσ."""
    sig = np.asarray(sigma, dtype=float)
    s = float(sig @ sig)
    return np.concatenate(([(1.0 - s) / (1.0 + s)], 2.0 * sig / (1.0 + s)))


def quaternion_to_mrp(q: np.ndarray) -> np.ndarray:
    """MRP ``q_vec/(1 + q0)`` of a unit quaternion, short way (q and −q give the same σ)."""
    qa = np.asarray(q, dtype=float)
    if qa[0] < 0.0:
        qa = -qa
    return qa[1:] / (1.0 + qa[0])


def mrp_b_matrix(sigma: np.ndarray) -> np.ndarray:
    """``B(σ) = (1 − σᵀσ) I3 + 2[σ×] + 2σσᵀ`` (σ̇ = ¼ B(σ) ω, seed 001 eq. (1))."""
    sig = np.asarray(sigma, dtype=float)
    s = float(sig @ sig)
    return (1.0 - s) * np.eye(VECTOR_SIZE) + B_CROSS * skew(sig) + B_OUTER * np.outer(sig, sig)


def mrp_rate_to_omega(sigma: np.ndarray, sigma_dot: np.ndarray) -> np.ndarray:
    """Body rate [rad/s] from the MRP rate: ``ω = 4/(1 + σᵀσ)² B(σ)ᵀ σ̇``."""
    sig = np.asarray(sigma, dtype=float)
    s = float(sig @ sig)
    return OMEGA_GAIN / (1.0 + s) ** 2 * (mrp_b_matrix(sig).T @ np.asarray(sigma_dot, float))


def mrp_omega_dot(sigma: np.ndarray, sigma_dot: np.ndarray, sigma_ddot: np.ndarray) -> np.ndarray:
    """Angular acceleration [rad/s²]: the time derivative of :func:`mrp_rate_to_omega`."""
    sig = np.asarray(sigma, dtype=float)
    sd = np.asarray(sigma_dot, dtype=float)
    sdd = np.asarray(sigma_ddot, dtype=float)
    s = float(sig @ sig)
    s_dot = 2.0 * float(sig @ sd)
    b_t = mrp_b_matrix(sig).T
    b_dot_t = (
        -s_dot * np.eye(VECTOR_SIZE)
        - B_CROSS * skew(sd)
        + B_OUTER * (np.outer(sig, sd) + np.outer(sd, sig))
    )
    omega = OMEGA_GAIN / (1.0 + s) ** 2 * (b_t @ sd)
    return (
        OMEGA_GAIN / (1.0 + s) ** 2 * (b_dot_t @ sd + b_t @ sdd) - 2.0 * s_dot / (1.0 + s) * omega
    )


def _coeffs(value: object) -> tuple[tuple[float, ...], ...]:
    """Three non-empty lists of finite coefficients (ConfigError naming ``sigma_coeffs``)."""
    items = list(value) if isinstance(value, Sequence) and not isinstance(value, str) else []
    if len(items) != VECTOR_SIZE:
        raise ConfigError(_SOURCE, "sigma_coeffs", value,
                          "3 non-empty lists of finite numbers (ascending powers of t [s])")
    return tuple(check.vector(_SOURCE, "sigma_coeffs", axis, None) for axis in items)


def _derivative(coeffs: tuple[float, ...]) -> tuple[float, ...]:
    """Coefficients (ascending) of the derivative of an ascending-power polynomial."""
    return tuple(i * c for i, c in enumerate(coeffs) if i > 0) or (0.0,)


def _polyval(coeffs: tuple[float, ...], t_s: float) -> float:
    """Horner evaluation of an ascending-power polynomial."""
    acc = 0.0
    for c in reversed(coeffs):
        acc = acc * t_s + c
    return acc


@dataclass(frozen=True)
class MrpPolynomialGuidance:
    """Reference attitude with polynomial MRP components (default: seed 001 §5).

    Attributes:
        sigma_coeffs: per axis (3), the polynomial coefficients of σ_RN in ascending
            powers of τ = t − t0 [s] (entry i in 1/sⁱ).
        t0_ns: the time τ = 0 [ns] (caller's time base).
        duration_s: the manoeuvre length [s] (> 0; inf: never ends); outside
            [0, duration_s] the end attitude is held with zero rates.
    """

    sigma_coeffs: Sequence[Sequence[float]] = SEED001_SIGMA_COEFFS
    t0_ns: int = 0
    duration_s: float = SEED001_DURATION_S
    _c: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)
    _d1: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)
    _d2: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        coeffs = _coeffs(self.sigma_coeffs)
        check.integer(_SOURCE, "t0_ns", self.t0_ns)
        check.limit(_SOURCE, "duration_s", self.duration_s, unit="s")
        d1 = tuple(_derivative(c) for c in coeffs)
        object.__setattr__(self, "sigma_coeffs", coeffs)
        object.__setattr__(self, "_c", coeffs)
        object.__setattr__(self, "_d1", d1)
        object.__setattr__(self, "_d2", tuple(_derivative(c) for c in d1))

    def sigma(self, tau_s: float) -> np.ndarray:
        """σ_RN at ``tau_s`` [s] after t0 (the polynomial itself, no clamping)."""
        return np.array([_polyval(c, tau_s) for c in self._c])

    def reference(self, t_ns: int) -> AttitudeReference:
        """The reference at ``t_ns``: quaternion, rate and acceleration in R axes."""
        tau_s = (t_ns - self.t0_ns) / NS_PER_S
        zero = np.zeros(VECTOR_SIZE)
        if tau_s < 0.0:
            return AttitudeReference(mrp_to_quaternion(self.sigma(0.0)), zero, zero)
        if tau_s > self.duration_s:
            return AttitudeReference(mrp_to_quaternion(self.sigma(self.duration_s)), zero, zero)
        sig = self.sigma(tau_s)
        sd = np.array([_polyval(c, tau_s) for c in self._d1])
        sdd = np.array([_polyval(c, tau_s) for c in self._d2])
        return AttitudeReference(
            mrp_to_quaternion(sig), mrp_rate_to_omega(sig, sd), mrp_omega_dot(sig, sd, sdd)
        )
