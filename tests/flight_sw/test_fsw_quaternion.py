"""Known-answer and identity tests of flight_sw.quaternion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw import quaternion as qt

EXACT_TOL = 1e-12  # identities that hold to round-off
SERIES_TOL = 1e-15  # exp/log maps across the small-angle series switch
FINITE_DIFF_TOL = 1e-9  # kinematics check by a 1 µs central difference
N_RANDOM = 200
SWITCH_STRADDLE = 1e-9  # relative distance either side of the series switch


def random_unit_quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    """n random unit quaternions (uniform on the 3-sphere)."""
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_product_with_conjugate_is_identity(rng: np.random.Generator) -> None:
    """q ⊗ q* = q* ⊗ q = 1 for unit quaternions."""
    for q in random_unit_quaternions(rng, N_RANDOM):
        np.testing.assert_allclose(qt.multiply(q, qt.conjugate(q)), qt.identity(), atol=EXACT_TOL)
        np.testing.assert_allclose(qt.multiply(qt.conjugate(q), q), qt.identity(), atol=EXACT_TOL)


def test_hamilton_basis_products() -> None:
    """i ⊗ j = k, j ⊗ k = i, k ⊗ i = j, i ⊗ i = −1 (Hamilton's rules)."""
    i, j, k = np.eye(4)[1], np.eye(4)[2], np.eye(4)[3]
    np.testing.assert_array_equal(qt.multiply(i, j), k)
    np.testing.assert_array_equal(qt.multiply(j, k), i)
    np.testing.assert_array_equal(qt.multiply(k, i), j)
    np.testing.assert_array_equal(qt.multiply(i, i), -qt.identity())


def test_dcm_is_orthonormal_with_unit_determinant(rng: np.random.Generator) -> None:
    """C(q) Cᵀ = I and det C = +1."""
    for q in random_unit_quaternions(rng, N_RANDOM):
        c = qt.to_dcm(q)
        np.testing.assert_allclose(c @ c.T, np.eye(3), atol=EXACT_TOL)
        assert math.isclose(np.linalg.det(c), 1.0, abs_tol=EXACT_TOL)


def test_dcm_of_frame_rotation_about_z() -> None:
    """B rotated by +90° about z from N: the N x-axis has body components (0, −1, 0)."""
    q_BN = qt.from_rotation_vector(np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(
        qt.rotate(q_BN, np.array([1.0, 0.0, 0.0])), [0, -1, 0], atol=SERIES_TOL
    )


def test_dcm_composition_matches_product(rng: np.random.Generator) -> None:
    """C(p ⊗ q) = C(q) C(p), so q_BN = q_RN ⊗ q_BR composes frames."""
    qs = random_unit_quaternions(rng, 2 * N_RANDOM)
    for p, q in zip(qs[::2], qs[1::2], strict=True):
        np.testing.assert_allclose(
            qt.to_dcm(qt.multiply(p, q)), qt.to_dcm(q) @ qt.to_dcm(p), atol=EXACT_TOL
        )


def test_kinematics_convention_matches_dcm_rate() -> None:
    """q ⊗ exp(ω dt) realises Ċ_BN = −[ω_BN_B×] C_BN."""
    q = qt.normalise(np.array([0.9, 0.1, -0.3, 0.2]))
    omega_BN_B = np.array([0.3, -0.2, 0.5])
    dt_s = 1e-6
    c_plus = qt.to_dcm(qt.multiply(q, qt.from_rotation_vector(omega_BN_B * dt_s)))
    c_minus = qt.to_dcm(qt.multiply(q, qt.from_rotation_vector(-omega_BN_B * dt_s)))
    c_dot = (c_plus - c_minus) / (2.0 * dt_s)  # central difference
    np.testing.assert_allclose(c_dot, -qt.skew(omega_BN_B) @ qt.to_dcm(q), atol=FINITE_DIFF_TOL)


def test_exp_log_round_trip(rng: np.random.Generator) -> None:
    """Log(exp(θ)) = θ for |θ| < π, including tiny angles below the series switch."""
    axes = rng.normal(size=(N_RANDOM, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate(
        [rng.uniform(0.0, 3.1, N_RANDOM // 2), 10.0 ** rng.uniform(-12, -3, N_RANDOM // 2)]
    )
    for axis, angle in zip(axes, angles, strict=True):
        theta = axis * angle
        q = qt.from_rotation_vector(theta)
        assert math.isclose(float(np.linalg.norm(q)), 1.0, abs_tol=EXACT_TOL)
        np.testing.assert_allclose(qt.to_rotation_vector(q), theta, rtol=EXACT_TOL, atol=SERIES_TOL)
        assert math.isclose(qt.rotation_angle_rad(q), angle, rel_tol=EXACT_TOL, abs_tol=SERIES_TOL)


def test_exp_is_continuous_across_series_switch() -> None:
    """The exp map agrees just below and above SMALL_ANGLE_RAD."""
    axis = np.array([0.6, 0.0, 0.8])
    below = qt.from_rotation_vector(axis * qt.SMALL_ANGLE_RAD * (1 - SWITCH_STRADDLE))
    above = qt.from_rotation_vector(axis * qt.SMALL_ANGLE_RAD * (1 + SWITCH_STRADDLE))
    np.testing.assert_allclose(below, above, atol=SERIES_TOL)


def test_zero_rotation_is_identity() -> None:
    """exp(0) = 1 exactly and Log(1) = 0."""
    np.testing.assert_array_equal(qt.from_rotation_vector(np.zeros(3)), qt.identity())
    np.testing.assert_array_equal(qt.to_rotation_vector(qt.identity()), np.zeros(3))


def test_log_and_angle_take_the_short_way() -> None:
    """q and −q give the same rotation vector and angle; 270° is reported as −90°."""
    q = qt.from_rotation_vector(np.array([3 * math.pi / 2, 0.0, 0.0]))
    np.testing.assert_allclose(qt.to_rotation_vector(q), [-math.pi / 2, 0, 0], atol=EXACT_TOL)
    np.testing.assert_allclose(qt.to_rotation_vector(-q), [-math.pi / 2, 0, 0], atol=EXACT_TOL)
    assert math.isclose(qt.rotation_angle_rad(q), math.pi / 2, abs_tol=EXACT_TOL)
    assert qt.with_positive_scalar(q)[0] >= 0.0


def test_error_quaternion_recovers_relative_rotation(rng: np.random.Generator) -> None:
    """q_RN* ⊗ (q_RN ⊗ q_BR) = q_BR."""
    qs = random_unit_quaternions(rng, 2 * N_RANDOM)
    for q_RN, q_BR in zip(qs[::2], qs[1::2], strict=True):
        q_BN = qt.multiply(q_RN, q_BR)
        np.testing.assert_allclose(qt.error_quaternion(q_RN, q_BN), q_BR, atol=EXACT_TOL)


def test_normalise_rejects_zero() -> None:
    """A zero quaternion cannot be normalised."""
    with pytest.raises(ValueError):
        qt.normalise(np.zeros(4))
    np.testing.assert_allclose(qt.normalise(np.array([2.0, 0, 0, 0])), qt.identity())


def test_cross_matches_numpy_and_known_answer() -> None:
    """``cross`` gives x × y = z and equals numpy's cross on random 3-vectors."""
    np.testing.assert_array_equal(qt.cross(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])),
                                  [0.0, 0.0, 1.0])
    rng = np.random.default_rng(7)
    for _ in range(200):
        a, b = rng.normal(size=3), rng.normal(size=3)
        np.testing.assert_allclose(qt.cross(a, b), np.cross(a, b), rtol=0.0, atol=1e-15)
