"""Tests of the robust allocators (seed 001, sec. 4, Theorems 1–3) on seed 001's Table 1."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy.optimize import minimize

from dbc.errors import ConfigError
from flight_sw.allocation.qp_osqp import (
    DEFAULT_REGULARIZATION,
    BoundedQpAllocator,
    BoundedQpParams,
)
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator
from flight_sw.allocation.uncertainty import (
    SEED001_BASIS_WEIGHTS,
    SEED001_LFT_E_SHAPE,
    SEED001_LFT_H,
    lft_worst_case_residual,
    relative_basis,
)

LOWER_N, UPPER_N = -2.3, 2.35  # seed 001 sec. 5
N_DEMANDS = 25
DEMAND_SCALE = 2.0  # [N m]
# Robust optimum vs a non-robust thrust: worst case may exceed it by at most this (solver
# accuracy), relative to max(1, worst case).
WC_RTOL = 1e-5
RHO0_TOL = 1e-4  # ρ = 0 result vs the bounded QP [N m]
BOUND_SLACK = 1e-12
PAPER_BASIS_SHAPES_SEED = 7


Factory = Callable[[np.ndarray, float, np.ndarray | None], object]


def polyhedral(b: np.ndarray, rho: float, basis: np.ndarray | None) -> RobustPolyhedralAllocator:
    """Theorem 1 allocator."""
    return RobustPolyhedralAllocator(b, RobustParams(UPPER_N, LOWER_N, rho=rho), basis=basis)


def polytopic(b: np.ndarray, rho: float, basis: np.ndarray | None) -> RobustPolytopicAllocator:
    """Theorem 2 allocator."""
    return RobustPolytopicAllocator(b, RobustParams(UPPER_N, LOWER_N, rho=rho), basis=basis)


def lft(b: np.ndarray, rho: float, basis: np.ndarray | None) -> RobustLftAllocator:
    """Theorem 3 allocator with the paper's E and H."""
    del basis
    params = RobustLftParams(
        UPPER_N, LOWER_N, rho=rho, e_shape=SEED001_LFT_E_SHAPE, h_matrix=SEED001_LFT_H
    )
    return RobustLftAllocator(b, params)


@pytest.mark.parametrize("factory", [polyhedral, polytopic, lft])
@pytest.mark.parametrize("structure", ["paper", "random"])
def test_worst_case_not_worse_than_nominal_methods(
    b001: np.ndarray, rng: np.random.Generator, factory: Factory, structure: str
) -> None:
    """Robust worst-case residual ≤ that of the clipped pseudo-inverse and the bounded QP."""
    basis = None if structure == "paper" else rng.normal(size=(4, 3, 8)) * np.abs(b001).mean()
    robust = factory(b001, 0.1, basis)
    qp = BoundedQpAllocator(b001, BoundedQpParams(UPPER_N, LOWER_N))
    pinv = np.linalg.pinv(b001)
    for _ in range(N_DEMANDS):
        d = rng.normal(size=3) * DEMAND_SCALE
        res = robust.allocate(d)  # type: ignore[attr-defined]
        assert np.all(res.thrust_N >= LOWER_N - BOUND_SLACK)
        assert np.all(res.thrust_N <= UPPER_N + BOUND_SLACK)
        wc = robust.worst_case_residual(res.thrust_N, d)  # type: ignore[attr-defined]
        for other in (np.clip(pinv @ d, LOWER_N, UPPER_N), qp.allocate(d).thrust_N):
            wc_other = robust.worst_case_residual(other, d)  # type: ignore[attr-defined]
            assert wc <= wc_other + WC_RTOL * max(1.0, wc_other)


@pytest.mark.parametrize("factory", [polyhedral, polytopic, lft])
def test_rho_zero_is_bounded_least_squares(
    b001: np.ndarray, rng: np.random.Generator, factory: Factory
) -> None:
    """With ρ = 0 the robust answer achieves what the bounded least-squares QP achieves."""
    robust = factory(b001, 0.0, None)
    qp = BoundedQpAllocator(b001, BoundedQpParams(UPPER_N, LOWER_N))
    for _ in range(N_DEMANDS):
        d = rng.normal(size=3) * DEMAND_SCALE * 3.0
        a, b = robust.allocate(d), qp.allocate(d)  # type: ignore[attr-defined]
        assert np.linalg.norm(a.achieved - b.achieved) <= RHO0_TOL
        assert abs(a.residual_norm - b.residual_norm) <= RHO0_TOL


def test_polyhedral_vertex_set_of_paper(b001: np.ndarray) -> None:
    """The paper's B_i = (0.1, 0.1, 0.2, 0.2)·B give corners (1 + c)B, c ∈ {−0.6, …, 0.6}."""
    verts = polyhedral(b001, 0.1, None).vertices
    scales = sorted(float(v[0, 0] / b001[0, 0]) for v in verts)
    assert np.allclose(scales, np.linspace(0.4, 1.6, PAPER_BASIS_SHAPES_SEED))


def test_polyhedral_basis_limit(b001: np.ndarray) -> None:
    """More than 8 polyhedral basis matrices (2^q corners) are refused."""
    with pytest.raises(ConfigError):
        polyhedral(b001, 0.1, np.zeros((9, 3, 8)))


@pytest.mark.parametrize(
    "kwargs",
    [{"rho": -0.1}, {"basis_weights": (1.0, float("inf"))}, {"max_sqp_iter": 0}],
)
def test_robust_params_validation(kwargs: dict[str, object]) -> None:
    """Bad robust parameters raise ConfigError."""
    with pytest.raises(ConfigError):
        RobustParams(UPPER_N, LOWER_N, **kwargs)  # type: ignore[arg-type]


def test_lft_params_validation() -> None:
    """A ragged H or a negative ρ raise ConfigError."""
    with pytest.raises(ConfigError):
        RobustLftParams(UPPER_N, h_matrix=((1.0, 2.0), (1.0,)))
    with pytest.raises(ConfigError):
        RobustLftParams(UPPER_N, rho=-1.0)


LFT_REF_RHO = 0.5
LFT_REF_PROBLEMS = 5
LFT_REF_BOUND_N = 1.0
LFT_REF_RTOL = 1e-6  # objective excess over the scipy reference, relative to max(1e-2, ref)
LFT_REF_THETA_MARGIN = 1e-9
SCALAR_PATH_RTOL = 1e-7  # scalar dual path vs general SQP objective, relative
SCALAR_PERTURBATION = 1e-9  # breaks the B_k = s_k B₀ structure (forces the general path)


def eps_of(b: np.ndarray) -> float:
    """ε of the default regularisation for the matrix ``b``."""
    return DEFAULT_REGULARIZATION * float(np.mean(np.sum(b * b, axis=0)))


def lft_objective(
    alloc: RobustLftAllocator, b: np.ndarray, t: np.ndarray, d: np.ndarray
) -> float:
    """Exact squared worst case plus the regulariser (the allocator's objective)."""
    e, h = alloc.lft_matrices
    return lft_worst_case_residual(b, e, h, t, d) ** 2 + eps_of(b) * float(t @ t)


def test_lft_matches_scipy_reference(rng: np.random.Generator) -> None:
    """Random B, E, H at ρ = 0.5: objective within 1e-6 of scipy L-BFGS-B's (no early stop)."""
    m, n = 3, 8
    lo, hi = -LFT_REF_BOUND_N, LFT_REF_BOUND_N
    for _ in range(LFT_REF_PROBLEMS):
        b = rng.normal(size=(m, n))
        e_shape = rng.normal(size=(m, m))
        h = 0.3 * rng.normal(size=(int(rng.choice([3, 8])), n))
        params = RobustLftParams(
            hi, lo, rho=LFT_REF_RHO,
            e_shape=tuple(map(tuple, e_shape)), h_matrix=tuple(map(tuple, h)),
        )  # fmt: skip
        alloc = RobustLftAllocator(b, params)
        e = LFT_REF_RHO * e_shape
        eey = e @ e.T
        d = 2.0 * rng.normal(size=m)
        t = alloc.allocate(d).thrust_N

        def joint(x: np.ndarray, args: tuple[np.ndarray, ...] = (b, h, eey, d)) -> float:
            """S-lemma form f(T, θ) (jointly convex, smooth)."""
            bb, hh, ee, dd = args
            tt, tau = x[:n], x[n] / float(np.linalg.eigvalsh(ee).max())
            r = bb @ tt - dd
            y = np.eye(m) - tau * ee
            reg = eps_of(bb) * float(tt @ tt)
            return float(r @ np.linalg.solve(y, r) + np.sum((hh @ tt) ** 2) / tau) + reg

        ref = math.inf
        bounds = [(lo, hi)] * n + [(LFT_REF_THETA_MARGIN, 1.0 - LFT_REF_THETA_MARGIN)]
        for x0 in (np.r_[np.zeros(n), 0.5], np.r_[t, 0.5]):
            sol = minimize(joint, x0, method="L-BFGS-B", bounds=bounds,
                           options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 5000})  # fmt: skip
            ref = min(ref, lft_objective(alloc, b, sol.x[:n], d))
        assert lft_objective(alloc, b, t, d) <= ref + LFT_REF_RTOL * max(1e-2, ref)


@pytest.mark.parametrize("cls", [RobustPolytopicAllocator, RobustPolyhedralAllocator])
def test_scalar_dual_path_matches_general_sqp(
    b001: np.ndarray, rng: np.random.Generator, cls: type[RobustPolytopicAllocator]
) -> None:
    """Paper structure B_k = s_k B₀ (1-D dual) gives the SQP's optimum on a perturbed copy."""
    shapes = relative_basis(b001, 1.0, SEED001_BASIS_WEIGHTS)
    params = RobustParams(UPPER_N, LOWER_N, rho=0.3)
    fast = cls(b001, params)
    general = cls(b001, params, basis=shapes + SCALAR_PERTURBATION * rng.normal(size=shapes.shape))
    verts = fast.vertices
    eps = params.regularization * float(np.mean(np.einsum("kmi,kmi->ki", verts, verts)))
    for _ in range(N_DEMANDS):
        d = rng.normal(size=3) * DEMAND_SCALE * float(rng.choice([0.3, 1.0, 5.0]))
        objs = []
        for alloc in (fast, general):
            t = alloc.allocate(d).thrust_N
            objs.append(fast.worst_case_residual(t, d) ** 2 + eps * float(t @ t))
        assert objs[0] <= objs[1] + SCALAR_PATH_RTOL * max(1.0, objs[1])


@pytest.mark.parametrize("factory", [polyhedral, polytopic, lft])
def test_warm_start_is_deterministic(
    b001: np.ndarray, rng: np.random.Generator, factory: Factory
) -> None:
    """Two instances fed the same demand sequence return bit-identical thrusts."""
    first, second = factory(b001, 0.1, None), factory(b001, 0.1, None)
    for _ in range(N_DEMANDS):
        d = rng.normal(size=3) * DEMAND_SCALE
        a, b = first.allocate(d), second.allocate(d)  # type: ignore[attr-defined]
        assert np.array_equal(a.thrust_N, b.thrust_N)
