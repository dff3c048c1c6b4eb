"""The MEKF's covariance kernels against the textbook numpy forms (Markley & Crassidis §6.2).

Back to back on random symmetric positive-definite covariances, random transitions and
residuals: the block-written propagation equals ``Φ P Φᵀ + Q_k`` with the full 6×6 ``Φ``,
and the update equals ``K = P Hᵀ (H P Hᵀ + R)⁻¹``, ``x̂ = K y`` and the Joseph form. Both
outputs are exactly symmetric; a non-finite covariance is refused.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from flight_sw.estimation.mekf_kernel import propagate_covariance, star_tracker_update

SEED = 20261207
CASES = 200
N = 6
# Two summation orders of the same sums (a 6×6 product vs its blocks): round-off only,
# relative to the largest entry.
PROPAGATE_RTOL = 1e-14
# Cholesky vs LU solve of S (condition ≤ ~1e4 here) and the Joseph form's cancellations.
UPDATE_RTOL = 1e-11
SIGMA_A_RAD = 1e-3
SIGMA_B_RAD_S = 1e-5
SIGMA_ST_RAD = 5e-5
DT_S = 0.01


def _covariance(rng: np.random.Generator) -> np.ndarray:
    """A random SPD covariance scaled like the filter's (attitude rad², bias (rad/s)²)."""
    scale = np.diag([SIGMA_A_RAD] * 3 + [SIGMA_B_RAD_S] * 3)
    a = rng.normal(size=(N, N))
    return scale @ (a @ a.T / N + 0.1 * np.eye(N)) @ scale


def _close(got: np.ndarray, want: np.ndarray, rtol: float) -> None:
    np.testing.assert_allclose(got, want, rtol=0.0, atol=rtol * np.abs(want).max())


@pytest.fixture
def rng() -> np.random.Generator:
    """Seeded generator: the same random cases in every run."""
    return np.random.default_rng(SEED)


def test_propagation_equals_the_full_product(rng: np.random.Generator) -> None:
    """Block propagation == Φ P Φᵀ + Q_k with Φ = [[Φ11, Φ12], [0, I]], exactly symmetric."""
    for _ in range(CASES):
        p = _covariance(rng)
        phi11 = Rotation.random(random_state=rng).as_matrix()
        phi12 = -DT_S * np.eye(3) + 1e-4 * rng.normal(size=(3, 3))
        q11, q12, q22 = rng.uniform(1e-12, 1e-10), -rng.uniform(1e-16, 1e-14), 1e-16
        phi = np.eye(N)
        phi[:3, :3], phi[:3, 3:] = phi11, phi12
        qd = np.block([[q11 * np.eye(3), q12 * np.eye(3)], [q12 * np.eye(3), q22 * np.eye(3)]])
        got = np.array(propagate_covariance(p.ravel().tolist(), phi11.ravel().tolist(),
                                            phi12.ravel().tolist(), q11, q12, q22)).reshape(N, N)
        _close(got, phi @ p @ phi.T + qd, PROPAGATE_RTOL)
        assert np.array_equal(got, got.T)


def test_update_equals_the_textbook_form(rng: np.random.Generator) -> None:
    """x̂ and P⁺ equal K = P Hᵀ S⁻¹, K y and the Joseph form; P⁺ is exactly symmetric."""
    h = np.hstack([np.eye(3), np.zeros((3, 3))])
    r = SIGMA_ST_RAD**2
    for _ in range(CASES):
        p = _covariance(rng)
        y = rng.normal(scale=SIGMA_A_RAD, size=3)
        k = p @ h.T @ np.linalg.inv(h @ p @ h.T + r * np.eye(3))
        ikh = np.eye(N) - k @ h
        want = ikh @ p @ ikh.T + r * k @ k.T
        out = star_tracker_update(p.ravel().tolist(), r, y.tolist())
        assert out is not None
        dx, p_new = out
        _close(np.array(dx), k @ y, UPDATE_RTOL)
        got = np.array(p_new).reshape(N, N)
        _close(got, 0.5 * (want + want.T), UPDATE_RTOL)
        assert np.array_equal(got, got.T)
        # the update shrinks the attitude variance (S > R, so the gain is below one)
        assert all(got[i, i] < p[i, i] for i in range(3))


@pytest.mark.parametrize("index", [0, 4 * N + 4, 2 * N + 5])
def test_non_finite_covariance_is_refused(index: int) -> None:
    """A NaN anywhere in P (attitude block, bias block, cross terms): no update (None),
    nothing raised; so is a NaN residual."""
    p = np.eye(N).ravel().tolist()
    p[index] = math.nan
    assert star_tracker_update(p, SIGMA_ST_RAD**2, [0.0, 0.0, 0.0]) is None
    assert star_tracker_update(np.eye(N).ravel().tolist(), SIGMA_ST_RAD**2,
                               [math.nan, 0.0, 0.0]) is None
