"""Tests of the polynomial MRP guidance (seed 001 §5 trajectory) and the MRP rates it uses."""

from __future__ import annotations

import numpy as np
import pytest

from flight_sw import mrp
from flight_sw.guidance.mrp_polynomial import SEED001_DURATION_S, MrpPolynomialGuidance
from flight_sw.quaternion import (
    conjugate,
    from_rotation_vector,
    multiply,
    skew,
    to_dcm,
)

NS_PER_S = 1_000_000_000
T0_NS = 3 * NS_PER_S
SEED001_SIGMA0 = np.array([0.08381, 0.101, 0.1205])  # seed 001 §5 initial MRP
SAMPLE_TIMES_S = (0.5, 13.0, 37.25, 50.0, 81.0, 99.0)
FD_STEP_NS = 1_000_000  # 1 ms central-difference step
# Central difference error ≈ step²/6 · |third derivative|; the rates vary on ~10 s scales.
FD_RATE_TOL = 1e-8  # [rad/s]
FD_ACCEL_TOL = 1e-8  # [rad/s²]
ROUND_TRIP_TOL = 1e-14
REST_RATE_TOL = 1e-2  # [rad/s]: the seed's trajectory nearly stops at 100 s
B_FORM_RTOL = 1e-14  # mrp's F⁻¹ forms against the B-matrix textbook form: round-off only


def b_matrix(sigma: np.ndarray) -> np.ndarray:
    """Schaub & Junkins' ``B(σ) = (1 − s) I + 2[σ×] + 2σσᵀ`` (σ̇ = ¼ B ω)."""
    s = float(sigma @ sigma)
    return (1.0 - s) * np.eye(3) + 2.0 * skew(sigma) + 2.0 * np.outer(sigma, sigma)


def omega_b_form(sigma: np.ndarray, sd: np.ndarray, sdd: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """``ω = 4/(1+s)² Bᵀσ̇`` and ``ω̇ = 4/(1+s)² (Ḃᵀσ̇ + Bᵀσ̈) − 2ṡ/(1+s) ω``, the textbook
    form (the guidance's own before it used flight_sw.mrp)."""
    s, s_dot = float(sigma @ sigma), 2.0 * float(sigma @ sd)
    omega = 4.0 / (1.0 + s) ** 2 * (b_matrix(sigma).T @ sd)
    outer = np.outer(sigma, sd) + np.outer(sd, sigma)
    b_dot_t = -s_dot * np.eye(3) - 2.0 * skew(sd) + 2.0 * outer
    omega_dot = (4.0 / (1.0 + s) ** 2 * (b_dot_t @ sd + b_matrix(sigma).T @ sdd)
                 - 2.0 * s_dot / (1.0 + s) * omega)
    return omega, omega_dot


def numeric_rate(g: MrpPolynomialGuidance, t_ns: int) -> np.ndarray:
    """ω_RN_R from a central difference of q_RN: ω = 2 vec(q* ⊗ q̇)."""
    q = g.reference(t_ns).q_RN
    q_dot = (g.reference(t_ns + FD_STEP_NS).q_RN - g.reference(t_ns - FD_STEP_NS).q_RN) / (
        2.0 * FD_STEP_NS / NS_PER_S
    )
    return 2.0 * multiply(conjugate(q), q_dot)[1:]


def test_starts_at_seed_initial_mrp() -> None:
    """At t0 the reference quaternion is that of the seed's initial MRP."""
    g = MrpPolynomialGuidance(t0_ns=T0_NS)
    q = g.reference(T0_NS).q_RN
    np.testing.assert_allclose(mrp.from_quaternion(q), SEED001_SIGMA0, rtol=0.0, atol=1e-15)


@pytest.mark.parametrize("t_s", SAMPLE_TIMES_S)
def test_rate_matches_numerical_quaternion_derivative(t_s: float) -> None:
    """ω from the MRP inverse kinematics equals 2 vec(q* ⊗ q̇) by central difference."""
    g = MrpPolynomialGuidance(t0_ns=T0_NS)
    t_ns = T0_NS + round(t_s * NS_PER_S)
    np.testing.assert_allclose(
        g.reference(t_ns).omega_RN_R, numeric_rate(g, t_ns), rtol=0.0, atol=FD_RATE_TOL
    )


@pytest.mark.parametrize("t_s", SAMPLE_TIMES_S)
def test_acceleration_matches_numerical_rate_derivative(t_s: float) -> None:
    """ω̇ (analytic) equals the central difference of ω."""
    g = MrpPolynomialGuidance(t0_ns=T0_NS)
    t_ns = T0_NS + round(t_s * NS_PER_S)
    w_plus = g.reference(t_ns + FD_STEP_NS).omega_RN_R
    w_minus = g.reference(t_ns - FD_STEP_NS).omega_RN_R
    numeric = (w_plus - w_minus) / (2.0 * FD_STEP_NS / NS_PER_S)
    np.testing.assert_allclose(g.reference(t_ns).domega_RN_R, numeric, rtol=0.0, atol=FD_ACCEL_TOL)


def test_mrp_kinematics_round_trip() -> None:
    """σ̇ = ¼ B(σ) ω inverts ω = F⁻¹(σ) σ̇ (seed 001 eq. (1) and F⁻¹)."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        sigma = rng.uniform(-0.6, 0.6, 3)
        omega = rng.normal(0.0, 0.1, 3)
        sigma_dot = 0.25 * b_matrix(sigma) @ omega
        np.testing.assert_allclose(
            mrp.rate_to_omega(sigma, sigma_dot), omega, rtol=0.0, atol=ROUND_TRIP_TOL
        )


def test_rates_equal_the_b_matrix_form() -> None:
    """ω and ω̇ from flight_sw.mrp (F⁻¹, Ḟ) equal the B-matrix form to round-off."""
    rng = np.random.default_rng(6)
    for _ in range(50):
        sigma, sd, sdd = rng.uniform(-0.6, 0.6, 3), rng.normal(0, 0.05, 3), rng.normal(0, 0.01, 3)
        omega, omega_dot = omega_b_form(sigma, sd, sdd)
        np.testing.assert_allclose(mrp.rate_to_omega(sigma, sd), omega, rtol=0.0,
                                   atol=B_FORM_RTOL * max(1.0, float(np.abs(omega).max())))
        got_omega, got_omega_dot = mrp.omega_and_rate(sigma, sd, sdd)
        assert np.array_equal(got_omega, mrp.rate_to_omega(sigma, sd))
        np.testing.assert_allclose(got_omega_dot, omega_dot, rtol=0.0,
                                   atol=B_FORM_RTOL * max(1.0, float(np.abs(omega_dot).max())))


def test_mrp_quaternion_conventions() -> None:
    """σ = e tan(φ/4) maps to the quaternion of the same rotation; round trip and DCM agree."""
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    angle = 1.3
    q = from_rotation_vector(angle * axis)
    sigma = axis * np.tan(angle / 4.0)
    np.testing.assert_allclose(mrp.to_quaternion(sigma), q, rtol=0.0, atol=ROUND_TRIP_TOL)
    np.testing.assert_allclose(mrp.from_quaternion(-q), sigma, rtol=0.0, atol=ROUND_TRIP_TOL)
    # Schaub & Junkins: C(σ) = I + (8[σ×]² − 4(1 − σ²)[σ×])/(1 + σ²)²
    s = float(sigma @ sigma)
    sx = np.array([[0, -sigma[2], sigma[1]], [sigma[2], 0, -sigma[0]], [-sigma[1], sigma[0], 0]])
    c = np.eye(3) + (8.0 * sx @ sx - 4.0 * (1.0 - s) * sx) / (1.0 + s) ** 2
    np.testing.assert_allclose(c, to_dcm(q), rtol=0.0, atol=ROUND_TRIP_TOL)


def test_holds_outside_the_manoeuvre() -> None:
    """Before t0 and after the duration the end attitudes are held with zero rates."""
    g = MrpPolynomialGuidance(t0_ns=T0_NS)
    before = g.reference(T0_NS - 1)
    end_ns = T0_NS + round(SEED001_DURATION_S * NS_PER_S)
    after = g.reference(end_ns + 1)
    np.testing.assert_allclose(before.q_RN, g.reference(T0_NS).q_RN, rtol=0.0, atol=0.0)
    np.testing.assert_allclose(after.q_RN, g.reference(end_ns).q_RN, rtol=0.0, atol=1e-15)
    for ref in (before, after):
        np.testing.assert_array_equal(ref.omega_RN_R, np.zeros(3))
        np.testing.assert_array_equal(ref.domega_RN_R, np.zeros(3))
    assert np.linalg.norm(g.reference(end_ns).omega_RN_R) < REST_RATE_TOL


def test_quaternion_is_unit_and_continuous() -> None:
    """Along the manoeuvre |q| = 1, q0 > 0 and consecutive samples (1 s) stay close."""
    g = MrpPolynomialGuidance()
    qs = np.array([g.reference(k * NS_PER_S).q_RN for k in range(101)])
    np.testing.assert_allclose(np.linalg.norm(qs, axis=1), 1.0, rtol=0.0, atol=1e-15)
    assert np.all(qs[:, 0] > 0.0)
    assert np.max(np.linalg.norm(np.diff(qs, axis=0), axis=1)) < 0.1


def test_custom_constant_coefficients_give_fixed_attitude() -> None:
    """Constant polynomials give a fixed attitude and zero rates."""
    g = MrpPolynomialGuidance(sigma_coeffs=[[0.1], [0.0], [-0.2]], duration_s=float("inf"))
    ref = g.reference(123 * NS_PER_S)
    np.testing.assert_allclose(mrp.from_quaternion(ref.q_RN), [0.1, 0.0, -0.2], atol=1e-15)
    np.testing.assert_array_equal(ref.omega_RN_R, np.zeros(3))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"sigma_coeffs": [[0.1], [0.2]]}, "sigma_coeffs"),
        ({"sigma_coeffs": [[0.1], [], [0.2]]}, "sigma_coeffs"),
        ({"sigma_coeffs": [[0.1], [float("nan")], [0.2]]}, "sigma_coeffs"),
        ({"t0_ns": 0.5}, "t0_ns"),
        ({"duration_s": 0.0}, "duration_s"),
    ],
)
def test_invalid_arguments_are_rejected(kwargs: dict[str, object], name: str) -> None:
    """Bad coefficients, start time or duration raise ValueError naming the argument."""
    with pytest.raises(ValueError, match=name):
        MrpPolynomialGuidance(**kwargs)  # type: ignore[arg-type]
