"""Tests of the robust allocators (seed 001, sec. 4, Theorems 1–3) on seed 001's Table 1."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from dbc.errors import ConfigError
from flight_sw.allocation.qp_osqp import (
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
    SEED001_RHO,
    lft_worst_case_residual,
    relative_basis,
)

from .lft_sdp_reference import LftSdpReference

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
LFT_REF_DEMANDS = 4
LFT_REF_BOUND_N = 1.0
# The allocator's worst case may exceed the SDP reference's by this, relative to
# max(optimum, ‖v‖) (the optimum is often exactly 0: then relative to the demand).
LFT_EXACT_RTOL = 1e-6
# Seed-001 demand scales [N m]: small ones are met robustly (optimum 0), large ones not.
SEED001_DEMAND_SCALES = (0.05, 0.5, 2.0, 5.0)
SEED001_DEMANDS_PER_SCALE = 8
ZERO_OPTIMUM_N_M = 1e-6  # a reference optimum below this counts as 0 [N m]
SCALAR_PATH_RTOL = 1e-7  # scalar dual path vs general SQP objective, relative
SCALAR_PERTURBATION = 1e-9  # breaks the B_k = s_k B₀ structure (forces the general path)


def lft_excess(alloc: RobustLftAllocator, b: np.ndarray, ref: LftSdpReference,
               d: np.ndarray) -> tuple[float, float]:
    """``(excess, optimum)``: the allocator's exact worst case above the SDP optimum,
    relative to max(optimum, ‖d‖), and that optimum [N m]."""
    e, h = alloc.lft_matrices
    opt = ref.optimum(d)
    got = lft_worst_case_residual(b, e, h, alloc.allocate(d).thrust_N, d)
    return (got - opt) / max(opt, float(np.linalg.norm(d))), opt


def test_lft_exact_on_seed001(b001: np.ndarray, rng: np.random.Generator) -> None:
    """Seed 001's E, H and bounds: worst case equals Theorem 3's SDP optimum (zero or not)."""
    alloc = lft(b001, SEED001_RHO, None)
    e, h = alloc.lft_matrices
    ref = LftSdpReference(b001, e, h, LOWER_N, UPPER_N)
    optima = []
    for scale in SEED001_DEMAND_SCALES:
        for _ in range(SEED001_DEMANDS_PER_SCALE):
            excess, opt = lft_excess(alloc, b001, ref, rng.normal(size=3) * scale)
            assert excess <= LFT_EXACT_RTOL
            optima.append(opt)
    # Both regimes were exercised: robustly met (optimum 0: the ridge's bias was here) and not.
    assert min(optima) < ZERO_OPTIMUM_N_M < max(optima)


def test_lft_exact_on_random_problems(rng: np.random.Generator) -> None:
    """Random B, E, H at ρ = 0.5: worst case equals Theorem 3's SDP optimum."""
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
        ref = LftSdpReference(b, LFT_REF_RHO * e_shape, h, lo, hi)
        for _ in range(LFT_REF_DEMANDS):
            excess, _ = lft_excess(alloc, b, ref, 2.0 * rng.normal(size=m))
            assert excess <= LFT_EXACT_RTOL


@pytest.mark.parametrize("regularization", [0.0, 1e-9, 1e-4])
def test_lft_ridge_outside_exact_range_refused(regularization: float) -> None:
    """A ridge outside the range the refinement makes exact is refused, naming the value."""
    with pytest.raises(ConfigError, match="regularization") as info:
        RobustLftParams(UPPER_N, LOWER_N, regularization=regularization)
    assert repr(regularization) in str(info.value) or str(regularization) in str(info.value)


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
