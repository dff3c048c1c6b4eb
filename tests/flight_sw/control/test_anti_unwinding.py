"""Tests of the anti-unwinding attitude error function and vector of seed 000 (eqs. 25–26)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flight_sw import quaternion as quat
from flight_sw.control import anti_unwinding as au

from .dq_reference import au_jacobian, au_jacobian_rate

MU = 0.01
LAMBDA1 = 1.0
LAMBDA2 = 1.0
N_SAMPLES = 20001
# A continuous e_r moves between neighbouring samples by at most its slope bound
# |de_r/dθ| ≤ ½ (max|g′| + max|g|) times the step; margin for the bound's looseness.
SLOPE_MARGIN = 1.5
# ϕ is smooth with |dϕ/dθ| < 10 for these µ, so neighbours differ by less than this.
PHI_JUMP_TOL = 1e-2
# The short-way switch sgn(q_e0) q_ev jumps by 2|q_ev| = 2 at θ = π: what e_r avoids.
SHORT_WAY_JUMP = 2.0
FD_STEP = 1e-6
FD_TOL = 1e-6
AXIS = np.array([1.0, 2.0, -2.0]) / 3.0


def _q_of_angle(theta: float) -> np.ndarray:
    return np.concatenate(([math.cos(theta / 2.0)], math.sin(theta / 2.0) * AXIS))


@pytest.mark.parametrize("mu", [MU, 0.1, 1.0])
def test_error_vector_continuous_and_bounded(mu: float) -> None:
    """e_r and ϕ have no jumps on θ ∈ [−2π, 2π] (both signs of q_e0) and |e_r| stays in bound."""
    thetas = np.linspace(-2.0 * math.pi, 2.0 * math.pi, N_SAMPLES)
    step = float(thetas[1] - thetas[0])
    e = np.array([au.error_vector(_q_of_angle(t), mu) for t in thetas])
    phi = np.array([au.error_function(_q_of_angle(t), mu, LAMBDA1, LAMBDA2) for t in thetas])
    gains = np.array([au.gain_terms(math.cos(t / 2.0), mu)[:2] for t in thetas])
    slope = 0.5 * (np.max(np.abs(gains[:, 1])) + np.max(np.abs(gains[:, 0])))
    jump_tol = SLOPE_MARGIN * slope * step
    assert jump_tol < SHORT_WAY_JUMP / 10.0
    assert np.max(np.linalg.norm(np.diff(e, axis=0), axis=1)) < jump_tol
    assert np.max(np.abs(np.diff(phi))) < PHI_JUMP_TOL
    assert np.max(np.linalg.norm(e, axis=1)) <= au.error_vector_bound(mu)
    bound_phi = 2.0 * (LAMBDA1 + LAMBDA2 + math.exp(1.0))
    assert np.all(np.abs(phi) <= bound_phi)


def test_short_way_sign_vanishing_ends_and_no_unwinding() -> None:
    """e_r ∥ +q_ev for q_e0 > 0, e_r(−q) = e_r(q), e_r = 0 at θ = 0 and θ = π."""
    for theta in np.linspace(0.05, math.pi - 0.05, 50):
        q = _q_of_angle(float(theta))
        e = au.error_vector(q, MU)
        assert float(e @ q[1:]) > 0.0
        np.testing.assert_allclose(au.error_vector(-q, MU), e, atol=1e-15)
    np.testing.assert_allclose(au.error_vector(quat.identity(), MU), np.zeros(3), atol=0.0)
    np.testing.assert_allclose(au.error_vector(_q_of_angle(math.pi), MU), np.zeros(3), atol=1e-13)


def test_jacobian_and_its_rate_match_finite_differences(rng: np.random.Generator) -> None:
    """ė_r = Θ_r ω and Θ̇_r agree with central differences along q̇ = ½ q ⊗ (0, ω)."""
    for _ in range(20):
        q = quat.normalise(rng.normal(size=4))
        w = rng.normal(size=3)
        qdot = 0.5 * quat.multiply(q, np.concatenate(([0.0], w)))
        qp, qm = q + FD_STEP * qdot, q - FD_STEP * qdot
        fd_e = (au.error_vector(qp, MU) - au.error_vector(qm, MU)) / (2.0 * FD_STEP)
        np.testing.assert_allclose(au.jacobian(q, MU) @ w, fd_e, atol=FD_TOL)
        fd_j = (au.jacobian(qp, MU) - au.jacobian(qm, MU)) / (2.0 * FD_STEP)
        np.testing.assert_allclose(au.jacobian_rate(q, w, MU), fd_j, atol=FD_TOL)


def test_axis_gain_vanishes_at_the_maximum_of_the_error_norm() -> None:
    """The Θ_r singularity (axis_gain = 0) sits where |e_r(θ)| peaks (about 103° for µ = 0.01)."""
    thetas = np.linspace(0.0, math.pi, N_SAMPLES)
    norms = [float(np.linalg.norm(au.error_vector(_q_of_angle(t), MU))) for t in thetas]
    theta_max = float(thetas[int(np.argmax(norms))])
    step = float(thetas[1] - thetas[0])
    assert au.axis_gain(_q_of_angle(theta_max - 2 * step), MU) > 0.0
    assert au.axis_gain(_q_of_angle(theta_max + 2 * step), MU) < 0.0
    assert math.degrees(theta_max) == pytest.approx(103.1, abs=0.1)


ARRAY_FORM_RTOL = 1e-14  # the float form against the array form: round-off only


def _close(got: object, want: np.ndarray) -> None:
    """Equal to ARRAY_FORM_RTOL of the larger of 1 and the reference's largest entry."""
    scale = max(1.0, float(np.max(np.abs(want))))
    np.testing.assert_allclose(np.reshape(np.asarray(got), want.shape), want, rtol=0.0,
                               atol=ARRAY_FORM_RTOL * scale)


def test_float_error_state_equals_the_array_form(rng: np.random.Generator) -> None:
    """error_state's e_r, Θ_r, Θ̇_r equal the matrix expressions (dq_reference) to round-off."""
    for _ in range(200):
        q = quat.normalise(rng.normal(size=4))
        w = rng.normal(size=3)
        er, jac, rate = au.error_state(*q.tolist(), tuple(w.tolist()), MU)
        _close(er, au.error_vector(q, MU))
        _close(jac, au_jacobian(q, MU))
        _close(rate, au_jacobian_rate(q, w, MU))
