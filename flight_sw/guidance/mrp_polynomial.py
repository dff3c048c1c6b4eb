"""Polynomial MRP guidance: a reference attitude whose MRP components are polynomials in time.

What it does: ``σ_RN(τ)`` with each component a polynomial in ``τ = (t − t0)`` [s],
converted to the reference quaternion, with the reference rate and angular acceleration
from the MRP kinematics, all analytic (the MRP algebra is :mod:`flight_sw.mrp`'s):
- MRP → quaternion (``s = σᵀσ``): ``q0 = (1 − s)/(1 + s)``, ``q_vec = 2σ/(1 + s)``
  (``σ = e tan(φ/4)``, the MRP of the rotation the quaternion describes, same N → R sense,
  so ``C(σ) = C(q)`` of :mod:`flight_sw.quaternion`);
- kinematics (seed 001 eq. (1)): ``σ̇ = F(σ) ω``; inverse (seed 001, after eq. (1)):
  ``ω_RN_R = F⁻¹(σ) σ̇ = 16/(1 + s)² F(σ)ᵀ σ̇``;
- its derivative (product rule, ``ṡ = 2σᵀσ̇``): ``ω̇ = Ġ σ̇ + G σ̈`` with ``G = F⁻¹``,
  ``Ġ = 16/(1 + s)² Ḟᵀ − 2ṡ/(1 + s) G``.

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
set is done.

Sources: seed 001 eq. (1) and the expression of F⁻¹ after it (MRP kinematics), §5
(desired trajectory σ_d); Schaub & Junkins, "Analytical Mechanics of Space Systems",
MRP ↔ quaternion relations and ``ω = 4/(1 + σ²)² Bᵀ σ̇``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw import mrp
from flight_sw.guidance.base import VECTOR_SIZE, AttitudeReference

NS_PER_S = 1_000_000_000
_SOURCE = "MrpPolynomialGuidance"

# Seed 001 §5, desired MRP σ_d (ascending powers of τ [s]); see the module docstring.
SEED001_SIGMA_COEFFS: tuple[tuple[float, ...], ...] = (
    (0.08381, 0.02439, -5.105e-4, 4.559e-6, -1.475e-8),
    (0.101, 0.01768, -2.5e-4, 1.136e-6),
    (0.1205, 0.01578, -2.088e-4, 8.899e-7),
)
SEED001_DURATION_S = 100.0  # "The time of the attitude control is 100 s."


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
            return AttitudeReference(mrp.to_quaternion(self.sigma(0.0)), zero, zero)
        if tau_s > self.duration_s:
            return AttitudeReference(mrp.to_quaternion(self.sigma(self.duration_s)), zero, zero)
        sig = self.sigma(tau_s)
        sd = np.array([_polyval(c, tau_s) for c in self._d1])
        sdd = np.array([_polyval(c, tau_s) for c in self._d2])
        omega, omega_dot = mrp.omega_and_rate(sig, sd, sdd)
        return AttitudeReference(mrp.to_quaternion(sig), omega, omega_dot)
