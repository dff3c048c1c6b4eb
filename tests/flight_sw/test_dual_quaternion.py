"""Tests of flight_sw.dual_quaternion: algebra identities, pose round trip, error kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from flight_sw import dual_quaternion as dq
from flight_sw import quaternion as quat

TOL = 1e-12
# Central finite differences with step FD_STEP_S are accurate to about FD_STEP_S² here.
FD_STEP_S = 1e-5
FD_TOL = 1e-8
N_RANDOM = 20
POSITION_SCALE_M = 30.0


def _random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q = quat.normalise(rng.normal(size=4))
    return q, POSITION_SCALE_M * rng.normal(size=3)


def _random_unit(rng: np.random.Generator) -> np.ndarray:
    q, r = _random_pose(rng)
    return dq.from_pose(q, r)


def test_product_is_associative(rng: np.random.Generator) -> None:
    """(â ∘ b̂) ∘ ĉ = â ∘ (b̂ ∘ ĉ) for arbitrary dual quaternions."""
    for _ in range(N_RANDOM):
        a, b, c = (rng.normal(size=8) for _ in range(3))
        left = dq.multiply(dq.multiply(a, b), c)
        right = dq.multiply(a, dq.multiply(b, c))
        np.testing.assert_allclose(left, right, atol=1e-10)


def test_conjugate_inverts_unit_and_reverses_products(rng: np.random.Generator) -> None:
    """q̂ ∘ q̂* = 1 for a unit dual quaternion and (â ∘ b̂)* = b̂* ∘ â*."""
    for _ in range(N_RANDOM):
        a, b = _random_unit(rng), rng.normal(size=8)
        np.testing.assert_allclose(dq.multiply(a, dq.conjugate(a)), dq.identity(), atol=1e-12)
        np.testing.assert_allclose(
            dq.conjugate(dq.multiply(a, b)),
            dq.multiply(dq.conjugate(b), dq.conjugate(a)),
            atol=1e-10,
        )


def test_pose_round_trip(rng: np.random.Generator) -> None:
    """Pose -> dual quaternion -> (q, r) returns the pose; the result is a unit dual quaternion."""
    for _ in range(N_RANDOM):
        q, r = _random_pose(rng)
        d = dq.from_pose(q, r)
        q2, r2 = dq.to_pose(d)
        np.testing.assert_allclose(q2, q, atol=TOL)
        np.testing.assert_allclose(r2, r, atol=1e-10)
        assert abs(float(d[:4] @ d[4:])) < 1e-10


def test_error_of_identical_poses_is_identity(rng: np.random.Generator) -> None:
    """q̂* ∘ q̂ is the identity and its vector part ξ̂ (the error state) is zero."""
    for _ in range(N_RANDOM):
        d = _random_unit(rng)
        e = dq.error(d, d)
        np.testing.assert_allclose(e, dq.identity(), atol=1e-10)
        np.testing.assert_allclose(dq.vector_part(e), np.zeros(6), atol=1e-10)


def test_error_holds_attitude_and_position_error_in_body_axes(rng: np.random.Generator) -> None:
    """q̂_d* ∘ q̂ = q_e + ϵ ½ q_e ⊗ p_e with q_e = q_d* ⊗ q, p_e = C(q_BN)(r_N − r_d,N) (eq. 6)."""
    for _ in range(N_RANDOM):
        q_BN, r_N = _random_pose(rng)
        q_DN, rd_N = _random_pose(rng)
        e = dq.error(
            dq.from_pose(q_DN, quat.rotate(q_DN, rd_N)), dq.from_pose(q_BN, quat.rotate(q_BN, r_N))
        )
        q_e, p_e = dq.to_pose(e)
        np.testing.assert_allclose(q_e, quat.error_quaternion(q_DN, q_BN), atol=TOL)
        np.testing.assert_allclose(p_e, quat.rotate(q_BN, r_N - rd_N), atol=1e-10)


def test_transform_twist_moves_the_twist_to_the_body_origin(rng: np.random.Generator) -> None:
    """q̂* ∘ ŵ ∘ q̂ = C ω + ϵ (C v + (C ω) × p) (eq. 7)."""
    for _ in range(N_RANDOM):
        q, p = _random_pose(rng)
        w = rng.normal(size=6)
        c = quat.to_dcm(q)
        expected = np.concatenate((c @ w[:3], c @ w[3:] + np.cross(c @ w[:3], p)))
        np.testing.assert_allclose(dq.transform_twist(dq.from_pose(q, p), w), expected, atol=1e-10)


def test_kinematics_matrix_matches_finite_differences(rng: np.random.Generator) -> None:
    """ξ̂̇ = Θ̂ ω̂ and Θ̂̇ agree with central differences along q̂̇ = ½ q̂ ∘ ω̂ (eq. 10)."""
    for _ in range(N_RANDOM):
        d = _random_unit(rng)
        w = rng.normal(size=6)
        d_plus = d + FD_STEP_S * dq.derivative(d, w)
        d_minus = d - FD_STEP_S * dq.derivative(d, w)
        fd_xi = (dq.vector_part(d_plus) - dq.vector_part(d_minus)) / (2.0 * FD_STEP_S)
        np.testing.assert_allclose(dq.kinematics_matrix(d) @ w, fd_xi, atol=FD_TOL)
        fd_theta = (dq.kinematics_matrix(d_plus) - dq.kinematics_matrix(d_minus)) / (
            2.0 * FD_STEP_S
        )
        np.testing.assert_allclose(dq.kinematics_matrix_rate(d, w), fd_theta, atol=FD_TOL)


def test_cross_product_is_the_dual_extension(rng: np.random.Generator) -> None:
    """â × b̂ = a × b + ϵ (a × b′ + a′ × b) and â × â = 0 (eq. 2)."""
    a, b = rng.normal(size=6), rng.normal(size=6)
    out = dq.cross(a, b)
    np.testing.assert_allclose(out[:3], np.cross(a[:3], b[:3]), atol=TOL)
    np.testing.assert_allclose(out[3:], np.cross(a[:3], b[3:]) + np.cross(a[3:], b[:3]), atol=TOL)
    np.testing.assert_allclose(dq.cross(a, a), np.zeros(6), atol=TOL)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_short_way_keeps_the_pose(sign: float, rng: np.random.Generator) -> None:
    """short_way returns ±q̂ with q0 ≥ 0 and the same pose."""
    q, r = _random_pose(rng)
    d = sign * dq.from_pose(q, r)
    s = dq.short_way(d)
    assert s[0] >= 0.0
    q_s, r_s = dq.to_pose(s)
    np.testing.assert_allclose(quat.to_dcm(q_s), quat.to_dcm(q), atol=TOL)
    np.testing.assert_allclose(r_s, r, atol=1e-10)


def test_product_is_bit_identical_to_three_hamilton_products(rng: np.random.Generator) -> None:
    """â ∘ b̂ written out on floats equals a ⊗ b + ϵ (a ⊗ b′ + a′ ⊗ b) from quat.multiply exactly."""
    for _ in range(N_RANDOM):
        a, b = rng.normal(size=8), rng.normal(size=8)
        real = quat.multiply(a[:4], b[:4])
        dual = quat.multiply(a[:4], b[4:]) + quat.multiply(a[4:], b[:4])
        assert np.array_equal(dq.multiply(a, b), np.concatenate((real, dual)))


def test_kinematics_matrix_is_the_block_form(rng: np.random.Generator) -> None:
    """Θ̂ = [[Θ, 0], [Θ′, Θ]] with Θ = ½ (q0 I + [vec(q)×]), Θ′ likewise from the dual part."""
    q = rng.normal(size=8)
    theta = 0.5 * (q[0] * np.eye(3) + quat.skew(q[1:4]))
    theta_d = 0.5 * (q[4] * np.eye(3) + quat.skew(q[5:8]))
    expected = np.block([[theta, np.zeros((3, 3))], [theta_d, theta]])
    assert np.array_equal(dq.kinematics_matrix(q), expected)
