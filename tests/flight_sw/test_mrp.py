"""Round trips and invariants of the MRP helpers (conversions, shadow set, kinematics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw import mrp
from flight_sw import quaternion as qt

EXACT_TOL = 1e-12
FD_STEP = 1e-6  # s, central differences
FD_TOL = 1e-8
RNG_SEED = 3
N_RANDOM = 20


def _random_quaternions() -> list[np.ndarray]:
    rng = np.random.default_rng(RNG_SEED)
    return [qt.normalise(rng.normal(size=4)) for _ in range(N_RANDOM)]


def test_known_mrp_of_a_90_deg_rotation() -> None:
    """A 90° rotation about z has σ = tan(22.5°) e_z."""
    q = qt.from_rotation_vector(np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(
        mrp.from_quaternion(q), [0.0, 0.0, math.tan(math.pi / 8)], atol=EXACT_TOL
    )


@pytest.mark.parametrize("q", _random_quaternions())
def test_quaternion_round_trip_and_short_way(q: np.ndarray) -> None:
    """q → σ → q gives q with q0 ≥ 0; |σ| ≤ 1; q and −q give the same σ."""
    sigma = mrp.from_quaternion(q)
    assert float(sigma @ sigma) <= 1.0 + EXACT_TOL
    np.testing.assert_allclose(mrp.to_quaternion(sigma), qt.with_positive_scalar(q), atol=EXACT_TOL)
    np.testing.assert_allclose(mrp.from_quaternion(-q), sigma, atol=EXACT_TOL)


@pytest.mark.parametrize("q", _random_quaternions())
def test_shadow_is_the_same_attitude(q: np.ndarray) -> None:
    """σ and σˢ have the same DCM, equal to the quaternion's; switched() picks |σ| ≤ 1."""
    sigma = mrp.from_quaternion(q)
    sigma_s = mrp.shadow(sigma)
    np.testing.assert_allclose(mrp.to_dcm(sigma), qt.to_dcm(q), atol=EXACT_TOL)
    np.testing.assert_allclose(mrp.to_dcm(sigma_s), qt.to_dcm(q), atol=EXACT_TOL)
    np.testing.assert_allclose(mrp.switched(sigma_s), sigma, atol=EXACT_TOL)
    np.testing.assert_allclose(mrp.shadow(sigma_s), sigma, atol=EXACT_TOL)


def test_shadow_of_zero_is_rejected() -> None:
    """The zero MRP has no finite shadow."""
    with pytest.raises(ValueError, match="zero MRP"):
        mrp.shadow(np.zeros(3))


@pytest.mark.parametrize("q", _random_quaternions())
def test_inverse_kinematics_matrix(q: np.ndarray) -> None:
    """G(σ) F(σ) = I, also for a shadow (|σ| > 1) MRP."""
    for sigma in (mrp.from_quaternion(q), mrp.shadow(mrp.from_quaternion(q))):
        g = mrp.kinematics_matrix_inverse(sigma)
        np.testing.assert_allclose(g @ mrp.kinematics_matrix(sigma), np.eye(3), atol=EXACT_TOL)


def test_kinematics_match_quaternion_propagation() -> None:
    """σ̇ = F(σ) ω equals the central difference of σ(q ⊗ exp(ω t)); Ḟ matches F's difference."""
    q = qt.normalise(np.array([0.8, 0.3, -0.4, 0.2]))
    omega = np.array([0.3, -0.2, 0.5])

    def sigma_at(t: float) -> np.ndarray:
        return mrp.from_quaternion(qt.multiply(q, qt.from_rotation_vector(omega * t)))

    sigma = sigma_at(0.0)
    sigma_dot_fd = (sigma_at(FD_STEP) - sigma_at(-FD_STEP)) / (2 * FD_STEP)
    sigma_dot = mrp.kinematics_matrix(sigma) @ omega
    np.testing.assert_allclose(sigma_dot, sigma_dot_fd, atol=FD_TOL)
    f_dot_fd = (
        mrp.kinematics_matrix(sigma_at(FD_STEP)) - mrp.kinematics_matrix(sigma_at(-FD_STEP))
    ) / (2 * FD_STEP)
    np.testing.assert_allclose(mrp.kinematics_matrix_rate(sigma, sigma_dot), f_dot_fd, atol=FD_TOL)
