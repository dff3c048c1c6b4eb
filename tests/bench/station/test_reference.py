"""Tracking reference: MRP polynomials -> q_RN(t), ω_RN(t) consistent with quaternion kinematics."""

from __future__ import annotations

import math

import pytest

from bench.station.dynamics.rigid_body import quat_conjugate, quat_multiply
from bench.station.reference import (
    KIND_MRP_POLYNOMIAL,
    ReferenceParams,
    attitude_error_deg,
    mrp_to_quat,
    polyder,
    polyval,
    rate_error_B,
    reference,
)
from dbc.errors import ConfigError

# seed 001 §5 (σd3's t² term as printed lacks its t; restored)
SEED001_MRP = (
    (-1.475e-8, 4.559e-6, -5.105e-4, 0.02439, 0.08381),
    (1.136e-6, -2.5e-4, 0.01768, 0.101),
    (8.899e-7, -2.088e-4, 0.01578, 0.1205),
)
FD_H_S = 1e-5
RATE_ABS_TOL = 1e-8
ABS_TOL = 1e-14
ACOS_TOL_DEG = 1e-5  # acos near 1 resolves ~sqrt(eps) rad


def _params(t_start_s: float = 0.0) -> ReferenceParams:
    return ReferenceParams(KIND_MRP_POLYNOMIAL, mrp_coefficients=SEED001_MRP, t_start_s=t_start_s)


def test_polynomial_helpers_known_values() -> None:
    """polyval(3x² + 2x + 1, 2) = 17; its derivative 6x + 2."""
    assert polyval((3.0, 2.0, 1.0), 2.0) == 17.0
    assert polyder((3.0, 2.0, 1.0)) == (6.0, 2.0)


def test_mrp_to_quat_unit_and_known_value() -> None:
    """σ = tan(θ/4) e gives q = (cos θ/2, sin θ/2 e)."""
    theta = 1.2
    q = mrp_to_quat((0.0, 0.0, math.tan(theta / 4)))
    assert q == pytest.approx((math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)), abs=ABS_TOL)


@pytest.mark.parametrize("t_s", [0.0, 10.0, 37.5, 100.0])
def test_reference_rate_matches_numerical_derivative(t_s: float) -> None:
    """ω from 2 q* ⊗ q̇ (central differences of q_RN) equals the analytic MRP rate."""
    p = _params()
    q, w = reference(p, t_s + 2 * FD_H_S)
    qp, _ = reference(p, t_s + 3 * FD_H_S)
    qm, _ = reference(p, t_s + FD_H_S)
    qdot = tuple((a - b) / (2 * FD_H_S) for a, b in zip(qp, qm, strict=True))
    w_fd = quat_multiply(quat_conjugate(q), qdot)  # type: ignore[arg-type]
    assert [2 * x for x in w_fd[1:]] == pytest.approx(list(w), abs=RATE_ABS_TOL)


def test_before_start_the_reference_holds() -> None:
    """Before t_start the reference is σ(0) with zero rate; errors vs itself are zero."""
    p = _params(t_start_s=5.0)
    q, w = reference(p, 1.0)
    assert q == pytest.approx(mrp_to_quat((0.08381, 0.101, 0.1205)), abs=ABS_TOL)
    assert w == (0.0, 0.0, 0.0)
    q2, w2 = reference(p, 30.0)
    assert attitude_error_deg(q2, q2) == pytest.approx(0.0, abs=ACOS_TOL_DEG)
    assert rate_error_B(q2, w2, q2, w2) == pytest.approx((0.0, 0.0, 0.0), abs=ABS_TOL)


def test_bad_coefficients_raise() -> None:
    """Two axes only is a ConfigError on mrp_coefficients."""
    with pytest.raises(ConfigError, match="mrp_coefficients"):
        ReferenceParams(KIND_MRP_POLYNOMIAL, mrp_coefficients=((1.0,), (2.0,)))
