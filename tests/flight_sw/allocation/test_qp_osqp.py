"""Tests of the OSQP bounded least-squares allocator (seed 000, eqs. 27–32)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from dbc.errors import ConfigError
from flight_sw.allocation.active_set import FREE, box_qp
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams

N_RANDOM = 60
T_MAX_N = 5.0
KKT_TOL = 1e-6  # gradient / complementarity tolerance [demand units × N]
AGREE_TOL = 1e-6  # residual vs scipy's bounded least squares [demand units]
EXACT_TOL = 1e-9  # attainable demands: residual [demand units]
BOUND_SLACK = 1e-12
INFEASIBLE_SCALE = 40.0


def kkt_violation(
    b: np.ndarray, d: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> float:
    """Largest violation of the KKT conditions of min ½‖BT−d‖², lo ≤ T ≤ hi."""
    g = b.T @ (b @ t - d)  # gradient; multipliers: mu_lo = max(g, 0), mu_hi = max(−g, 0)
    mu_lo, mu_hi = np.maximum(g, 0.0), np.maximum(-g, 0.0)
    stationarity = np.abs(g - mu_lo + mu_hi).max()
    complementarity = max(np.abs(mu_lo * (t - lo)).max(), np.abs(mu_hi * (hi - t)).max())
    feasibility = max(np.maximum(lo - t, 0.0).max(), np.maximum(t - hi, 0.0).max())
    return float(max(stationarity, complementarity, feasibility))


def random_demands(
    b: np.ndarray, rng: np.random.Generator, lo: float, hi: float
) -> list[np.ndarray]:
    """Attainable, random-direction and far-infeasible demands."""
    n = b.shape[1]
    scale = float(np.abs(b).max()) * hi
    out = [b @ rng.uniform(lo, hi, n) for _ in range(N_RANDOM)]
    out += [rng.normal(size=b.shape[0]) * scale for _ in range(N_RANDOM)]
    out += [rng.normal(size=b.shape[0]) * scale * INFEASIBLE_SCALE for _ in range(N_RANDOM // 4)]
    return out


@pytest.mark.parametrize("which", ["seed000", "random"])
def test_kkt_and_agreement_with_scipy(
    b16: np.ndarray, rng: np.random.Generator, which: str
) -> None:
    """Solutions satisfy the KKT conditions and match scipy's bounded least squares."""
    b = b16 if which == "seed000" else rng.normal(size=(6, 16))
    alloc = BoundedQpAllocator(b, BoundedQpParams(T_MAX_N))
    lo, hi = np.zeros(16), np.full(16, T_MAX_N)
    for d in random_demands(b, rng, 0.0, T_MAX_N):
        res = alloc.allocate(d)
        scale = max(1.0, float(np.linalg.norm(d)))
        assert kkt_violation(b, d, res.thrust_N, lo, hi) <= KKT_TOL * scale
        ref = lsq_linear(b, d, bounds=(0.0, T_MAX_N), method="bvls", tol=1e-13)
        ref_norm = float(np.linalg.norm(b @ ref.x - d))
        assert abs(res.residual_norm - ref_norm) <= AGREE_TOL * scale
        assert np.linalg.norm(res.achieved - b @ ref.x) <= np.sqrt(AGREE_TOL) * scale


def test_attainable_demands_reproduced_exactly(b16: np.ndarray, rng: np.random.Generator) -> None:
    """Demands B·T with T in the box (vertices included) are met to round-off, unsaturated."""
    alloc = BoundedQpAllocator(b16, BoundedQpParams(T_MAX_N))
    samples = np.vstack(
        [rng.uniform(0.0, T_MAX_N, (N_RANDOM, 16)), T_MAX_N * rng.integers(0, 2, (N_RANDOM, 16))]
    )
    for t_true in samples:
        res = alloc.allocate(b16 @ t_true)
        assert res.residual_norm <= EXACT_TOL
        assert not res.saturated


def test_unattainable_demand_is_saturated(b16: np.ndarray) -> None:
    """A far-out demand is flagged saturated and pins thrusters to their bounds."""
    alloc = BoundedQpAllocator(b16, BoundedQpParams(T_MAX_N))
    res = alloc.allocate(np.array([1e3, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert res.saturated
    assert np.isclose(res.thrust_N.max(), T_MAX_N)


def test_signed_bounds_seed001(b001: np.ndarray, rng: np.random.Generator) -> None:
    """Signed per-thruster bounds (seed 001: −2.3…2.35 N) are honoured, KKT holds."""
    lo, hi = np.full(8, -2.3), np.full(8, 2.35)
    alloc = BoundedQpAllocator(b001, BoundedQpParams(upper_N=2.35, lower_N=-2.3))
    for d in random_demands(b001, rng, -2.3, 2.35):
        res = alloc.allocate(d)
        assert np.all(res.thrust_N >= lo - BOUND_SLACK) and np.all(res.thrust_N <= hi + BOUND_SLACK)
        assert kkt_violation(b001, d, res.thrust_N, lo, hi) <= KKT_TOL * max(1.0, np.linalg.norm(d))


def test_min_norm_on_attainable_matches_pseudo_inverse(
    b16: np.ndarray, rng: np.random.Generator
) -> None:
    """With loose bounds the answer is the pseudo-inverse (least-shift, eq. 28–30)."""
    alloc = BoundedQpAllocator(b16, BoundedQpParams(upper_N=1e3, lower_N=-1e3))
    d = rng.normal(size=6)
    assert np.allclose(alloc.allocate(d).thrust_N, np.linalg.pinv(b16) @ d, atol=1e-9)


def test_warm_start_and_determinism(b16: np.ndarray, rng: np.random.Generator) -> None:
    """Warm and cold starts agree; the same call sequence gives bit-identical outputs."""
    demands = random_demands(b16, rng, 0.0, T_MAX_N)
    warm = BoundedQpAllocator(b16, BoundedQpParams(T_MAX_N))
    warm2 = BoundedQpAllocator(b16, BoundedQpParams(T_MAX_N))
    cold = BoundedQpAllocator(b16, BoundedQpParams(T_MAX_N, warm_start=False))
    for d in demands:
        a, b, c = warm.allocate(d), warm2.allocate(d), cold.allocate(d)
        assert np.array_equal(a.thrust_N, b.thrust_N)
        assert abs(a.residual_norm - c.residual_norm) <= AGREE_TOL * max(1.0, np.linalg.norm(d))


@pytest.mark.parametrize(
    "kwargs",
    [
        {"upper_N": float("nan")},
        {"upper_N": (1.0, "x")},
        {"upper_N": 1.0, "regularization": -1.0},
        {"upper_N": 1.0, "demand_weights": (1.0, 0.0)},
        {"upper_N": 1.0, "warm_start": 1},
    ],
)
def test_params_validation(kwargs: dict[str, object]) -> None:
    """Bad parameter values raise ConfigError."""
    with pytest.raises(ConfigError):
        BoundedQpParams(**kwargs)  # type: ignore[arg-type]


def test_bounds_shape_and_order_checked(b16: np.ndarray) -> None:
    """Per-thruster bounds of the wrong length or with lo > hi are refused."""
    with pytest.raises(ConfigError):
        BoundedQpAllocator(b16, BoundedQpParams(upper_N=(1.0, 2.0)))
    with pytest.raises(ConfigError):
        BoundedQpAllocator(b16, BoundedQpParams(upper_N=1.0, lower_N=2.0))


BOX_QP_PROBLEMS = 80
BOX_QP_RTOL = 1e-12  # objective excess over scipy's BVLS, relative to max(1, |objective|)


def test_box_qp_matches_scipy_bvls(rng: np.random.Generator) -> None:
    """The dense active-set box QP reaches scipy's bounded least-squares optimum."""
    for i in range(BOX_QP_PROBLEMS):
        m, n = (3, 8) if i % 2 else (6, 16)
        a = rng.normal(size=(m, n))
        b = rng.normal(size=m) * float(rng.choice([1.0, 5.0, 30.0]))
        lo = np.zeros(n) if i % 4 < 2 else np.full(n, -2.3)
        hi = np.full(n, 2.35)
        eps = 1e-6 * float(np.mean(np.sum(a * a, axis=0)))
        m_mat, c = a.T @ a + eps * np.eye(n), a.T @ b
        x, state = box_qp(m_mat, c, lo, hi, np.full(n, FREE, dtype=np.int8), True)
        assert np.all(x >= lo) and np.all(x <= hi) and state.shape == (n,)
        stacked = np.vstack([a, math.sqrt(eps) * np.eye(n)])
        ref = lsq_linear(stacked, np.r_[b, np.zeros(n)], bounds=(lo, hi), method="bvls", tol=1e-14)

        ours, theirs = (float(0.5 * y @ m_mat @ y - c @ y) for y in (x, ref.x))
        assert ours <= theirs + BOX_QP_RTOL * max(1.0, abs(theirs))
