"""Tests of the bounded pseudo-inverse allocator on the seed-003 layout (torque and wrench)."""

from __future__ import annotations

import numpy as np
import osqp
import pytest
import scipy.sparse as sp
from scipy.optimize import lsq_linear

from dbc.errors import ConfigError
from flight_sw.allocation.effectiveness import TORQUE_ROWS, effectiveness_matrix
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams

N_RANDOM = 500
FEASIBLE_RESIDUAL_TOL = 1e-9  # brief: attainable demands reproduced to ≤ 1e-9
DIRECTION_TOL = 1e-12  # 1 − cos(angle) between achieved and demanded on scaling
LSQ_MATCH_TOL = 1e-9  # fallback result vs a direct scipy bounded least squares
# Worst peak/T_max of the shifted pseudo-inverse over the vertices of [0, T_max]^8 for the
# seed-003 layout (both torque-only and wrench): demands built with T ≤ T_max / 1.5 never
# overflow, even without the exact repair.
# worst peak of the shifted pseudo-inverse over vertex demands B·{0,1}^8 (torque, wrench)
SEED003_SHIFT_OVERFLOW_BOUND = {"torque": 1.5, "wrench": 1.875}
INFEASIBLE_SCALE = 50.0  # demands this many times the largest single-thruster effect
# The repair's thrusts vs the least-norm exact ones from OSQP (polished, tolerances far
# below this).
LEAST_NORM_TOL_N = 1e-6
OSQP_EPS = 1e-12
OSQP_MAX_ITER = 100_000
N_LEAST_NORM = 40  # repaired demands checked against OSQP
CLIPPED_DRAW_RANGE = (-0.5, 1.5)  # × T_max, clipped to [0, 1]: bound and free thrusts mixed


def matrix(layout: tuple[np.ndarray, np.ndarray], rows: str) -> np.ndarray:
    """Torque-only (3×8) or wrench (6×8) effectiveness matrix."""
    b = effectiveness_matrix(*layout)
    return b[TORQUE_ROWS] if rows == "torque" else b


def repaired_and_plain(
    b: np.ndarray, tmax: float
) -> tuple[PseudoInverseAllocator, PseudoInverseAllocator]:
    """The allocator with its exact repair (step 3a) and the same without it."""
    return (PseudoInverseAllocator(b, PseudoInverseParams(tmax)),
            PseudoInverseAllocator(b, PseudoInverseParams(tmax, exact_repair=False)))


def assert_within_bounds(thrust: np.ndarray, tmax: float) -> None:
    """Every thrust in [0, T_max]."""
    assert np.all(thrust >= 0.0)
    assert np.all(thrust <= tmax)


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_reproduces_every_feasible_demand_exactly(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Random attainable demands B·T, T ∈ [0, T_max]^8 (vertices included), are reproduced."""
    b = matrix(layout, rows)
    alloc, plain = repaired_and_plain(b, max_thrust_n)
    overflowed = 0
    samples = np.vstack(
        [
            rng.uniform(0.0, max_thrust_n, (N_RANDOM, 8)),
            max_thrust_n * rng.integers(0, 2, (N_RANDOM, 8)),  # vertices: the hard cases
        ]
    )
    for t_true in samples:
        demand = b @ t_true
        res = alloc.allocate(demand)
        assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL
        assert not res.saturated
        assert_within_bounds(res.thrust_N, max_thrust_n)
        overflowed += plain.allocate(demand).saturated
    assert overflowed > 0  # the repair path was needed and exercised


def test_known_counterexample_needs_the_repair(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float
) -> None:
    """Thrusters 3, 4, 5, 6, 8 at T_max: the plain shift needs 1.25 T_max; the repair is exact."""
    b = matrix(layout, "torque")
    t_true = np.zeros(8)
    t_true[[2, 3, 4, 5, 7]] = max_thrust_n
    demand = b @ t_true
    plain = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n, exact_repair=False))
    res_plain = plain.allocate(demand)
    assert res_plain.saturated
    np.testing.assert_allclose(res_plain.achieved, demand / 1.25, atol=FEASIBLE_RESIDUAL_TOL)
    res = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n)).allocate(demand)
    assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL and not res.saturated


def _least_norm_reference(b: np.ndarray, demand: np.ndarray, tmax: float) -> np.ndarray:
    """min ½‖T‖² subject to B T = d and 0 ≤ T ≤ T_max, by OSQP at tight tolerances with
    its polish step (the independent reference: B may have dependent rows)."""
    n = b.shape[1]
    a = sp.vstack([sp.csc_matrix(b), sp.identity(n)], format="csc")
    solver = osqp.OSQP()
    solver.setup(sp.identity(n, format="csc"), np.zeros(n), a,
                 np.concatenate([demand, np.zeros(n)]), np.concatenate([demand, np.full(n, tmax)]),
                 eps_abs=OSQP_EPS, eps_rel=OSQP_EPS, max_iter=OSQP_MAX_ITER, polishing=True,
                 verbose=False)
    res = solver.solve(raise_error=False)
    assert res.info.status_val == osqp.SolverStatus.OSQP_SOLVED, res.info.status
    return np.asarray(res.x)


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_repair_gives_the_least_norm_exact_thrusts(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Overflowing attainable demands: the repair's thrusts are the least-norm exact ones."""
    b = matrix(layout, rows)
    alloc, plain = repaired_and_plain(b, max_thrust_n)
    checked = 0
    # thrusts clipped from a wider range: about a quarter at each bound, half inside
    lo, hi = CLIPPED_DRAW_RANGE
    for t_true in np.clip(rng.uniform(lo, hi, (N_RANDOM, 8)), 0.0, 1.0) * max_thrust_n:
        demand = b @ t_true
        if not plain.allocate(demand).saturated:
            continue  # not a repair: steps 1-2 alone
        res = alloc.allocate(demand)
        ref = _least_norm_reference(b, demand, max_thrust_n)
        np.testing.assert_allclose(res.thrust_N, ref, atol=LEAST_NORM_TOL_N)
        checked += 1
        if checked == N_LEAST_NORM:
            break
    assert checked == N_LEAST_NORM


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_plain_shift_is_exact_below_overflow_bound(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Without repair, demands under the overflow bound are reproduced by B⁺ d + shifts."""
    b = matrix(layout, rows)
    plain = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n, exact_repair=False))
    tcap = max_thrust_n / SEED003_SHIFT_OVERFLOW_BOUND[rows]
    for t_true in tcap * rng.integers(0, 2, (N_RANDOM, 8)):
        res = plain.allocate(b @ t_true)
        assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL and not res.saturated


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_infeasible_demands_stay_in_bounds_and_keep_direction(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Large random demands: thrusts in [0, T_max], flagged saturated, direction preserved."""
    b = matrix(layout, rows)
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n))
    scale = INFEASIBLE_SCALE * max_thrust_n * float(np.max(np.abs(b)))
    # Direction is preserved for the attainable part of the demand: project onto range(B).
    projector = b @ np.linalg.pinv(b)
    for demand in scale * rng.normal(size=(N_RANDOM, b.shape[0])):
        res = alloc.allocate(demand)
        assert_within_bounds(res.thrust_N, max_thrust_n)
        assert res.saturated
        target = projector @ demand
        cos = res.achieved @ target / (np.linalg.norm(res.achieved) * np.linalg.norm(target))
        assert 1.0 - cos <= DIRECTION_TOL


@pytest.mark.parametrize("masked", range(8))
def test_mask_is_respected(
    layout: tuple[np.ndarray, np.ndarray],
    masked: int,
    max_thrust_n: float,
    rng: np.random.Generator,
) -> None:
    """A masked thruster gets exactly 0 N; demands feasible without it are still reproduced."""
    b = matrix(layout, "torque")
    mask = np.ones(8, dtype=bool)
    mask[masked] = False
    base = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n))
    alloc = base.with_mask(mask)
    assert alloc is not base and np.all(base.mask)
    assert alloc.uses_null_space_shift
    for t_true in rng.uniform(0.0, max_thrust_n, (N_RANDOM // 5, 8)) * mask:
        res = alloc.allocate(b @ t_true)
        assert res.thrust_N[masked] == 0.0
        assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL
    for demand in 100.0 * rng.normal(size=(N_RANDOM // 5, 3)):
        res = alloc.allocate(demand)
        assert res.thrust_N[masked] == 0.0
        assert_within_bounds(res.thrust_N, max_thrust_n)


def test_lsq_fallback_without_positive_null_vector(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Wrench allocation with thruster 1 masked has no positive null vector: BVLS every call."""
    b = matrix(layout, "wrench")
    mask = np.ones(8, dtype=bool)
    mask[0] = False
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n), mask)
    assert not alloc.uses_null_space_shift and alloc.null_vector is None
    for t_true in rng.uniform(0.0, max_thrust_n, (N_RANDOM // 5, 8)) * mask:
        res = alloc.allocate(b @ t_true)
        assert res.thrust_N[0] == 0.0
        assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL and not res.saturated
    for demand in 100.0 * rng.normal(size=(N_RANDOM // 5, 6)):
        res = alloc.allocate(demand)
        assert res.thrust_N[0] == 0.0
        assert_within_bounds(res.thrust_N, max_thrust_n)
        direct = lsq_linear(b[:, 1:], demand, bounds=(0.0, max_thrust_n), method="bvls")
        assert (
            abs(res.residual_norm - np.linalg.norm(b[:, 1:] @ direct.x - demand)) <= LSQ_MATCH_TOL
        )


def test_torque_only_fallback_when_null_space_is_empty(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float
) -> None:
    """Three independent thrusters (null space {0}) also fall back, and stay in bounds."""
    b = matrix(layout, "torque")
    mask = np.zeros(8, dtype=bool)
    mask[[0, 2, 3]] = True
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n), mask)
    assert not alloc.uses_null_space_shift
    t_true = np.array([3.0, 0.0, 7.0, 11.0, 0.0, 0.0, 0.0, 0.0])
    res = alloc.allocate(b @ t_true)
    np.testing.assert_allclose(res.thrust_N, t_true, atol=FEASIBLE_RESIDUAL_TOL)
    res = alloc.allocate(-(b @ t_true))  # needs negative thrust: bounded, saturated
    assert res.saturated
    assert_within_bounds(res.thrust_N, max_thrust_n)


def test_zero_and_non_finite_demands(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float
) -> None:
    """Zero demand gives zero thrust; NaN demand gives zero thrust flagged saturated."""
    alloc = PseudoInverseAllocator(matrix(layout, "torque"), PseudoInverseParams(max_thrust_n))
    res = alloc.allocate(np.zeros(3))
    np.testing.assert_array_equal(res.thrust_N, np.zeros(8))
    assert not res.saturated
    res = alloc.allocate(np.array([np.nan, 0.0, 0.0]))
    np.testing.assert_array_equal(res.thrust_N, np.zeros(8))
    assert res.saturated and res.residual_norm == np.inf
    with pytest.raises(ValueError):
        res.thrust_N[0] = 1.0  # read-only result


def test_configuration_is_validated(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float
) -> None:
    """Bad thrust level, mask or matrix raise ConfigError."""
    b = matrix(layout, "torque")
    with pytest.raises(ConfigError):
        PseudoInverseParams(0.0)
    with pytest.raises(ConfigError):
        PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n), [True] * 7)
    with pytest.raises(ConfigError):
        PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n), [1] * 8)  # type: ignore[list-item]
    with pytest.raises(ConfigError):
        PseudoInverseAllocator(np.full((3, 8), np.nan), PseudoInverseParams(max_thrust_n))


# --- per-thruster maxima ---------------------------------------------------------------
# Seed 001's opposing valves differ by 2.3/2.35; here every other seed-003 thruster is
# weaker by this factor.
WEAK_FRACTION = 0.8
BIND_TOL = 1e-12  # max_i T_i/T_max,i of a scaled (saturated) result is 1 to round-off


def per_thruster_maxima(max_thrust_n: float) -> tuple[float, ...]:
    """T_max for even thrusters, WEAK_FRACTION × T_max for odd ones (8 thrusters)."""
    return tuple(max_thrust_n * (WEAK_FRACTION if k % 2 else 1.0) for k in range(8))


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_equal_per_thruster_maxima_are_bit_identical_to_one_maximum(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """A tuple of equal maxima gives exactly the thrusts of the single number (every path)."""
    b = matrix(layout, rows)
    one = PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_n))
    each = PseudoInverseAllocator(b, PseudoInverseParams((max_thrust_n,) * 8))
    scale = INFEASIBLE_SCALE * max_thrust_n * float(np.max(np.abs(b)))
    demands = [b @ t for t in max_thrust_n * rng.integers(0, 2, (N_RANDOM // 5, 8))]
    demands += list(scale * rng.normal(size=(N_RANDOM // 5, b.shape[0])))
    demands += list(0.05 * scale * rng.normal(size=(N_RANDOM // 5, b.shape[0])))
    for d in demands:
        r1, r2 = one.allocate(d), each.allocate(d)
        assert np.array_equal(r1.thrust_N, r2.thrust_N) and r1.saturated == r2.saturated


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_per_thruster_maxima_reproduce_attainable_demands(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Demands B·T with T_i ∈ [0, T_max,i] (vertices included) are reproduced within bounds."""
    b = matrix(layout, rows)
    upper = np.array(per_thruster_maxima(max_thrust_n))
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(tuple(upper)))
    samples = np.vstack([rng.uniform(0.0, 1.0, (N_RANDOM, 8)) * upper,
                         rng.integers(0, 2, (N_RANDOM, 8)) * upper])
    for t_true in samples:
        res = alloc.allocate(b @ t_true)
        assert res.residual_norm <= FEASIBLE_RESIDUAL_TOL and not res.saturated
        assert np.all(res.thrust_N >= 0.0) and np.all(res.thrust_N <= upper)


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_per_thruster_scaling_binds_one_thruster_and_keeps_direction(
    layout: tuple[np.ndarray, np.ndarray], rows: str, max_thrust_n: float, rng: np.random.Generator
) -> None:
    """Unattainable demands: one thruster exactly at its own maximum, none above, direction kept."""
    b = matrix(layout, rows)
    upper = np.array(per_thruster_maxima(max_thrust_n))
    alloc = PseudoInverseAllocator(b, PseudoInverseParams(tuple(upper)))
    scale = INFEASIBLE_SCALE * max_thrust_n * float(np.max(np.abs(b)))
    projector = b @ np.linalg.pinv(b)
    for demand in scale * rng.normal(size=(N_RANDOM, b.shape[0])):
        res = alloc.allocate(demand)
        assert res.saturated and np.all(res.thrust_N <= upper)
        assert float(np.max(res.thrust_N / upper)) == pytest.approx(1.0, abs=BIND_TOL)
        target = projector @ demand
        cos = res.achieved @ target / (np.linalg.norm(res.achieved) * np.linalg.norm(target))
        assert 1.0 - cos <= DIRECTION_TOL


def test_per_thruster_maxima_of_the_wrong_length_are_refused(
    layout: tuple[np.ndarray, np.ndarray], max_thrust_n: float
) -> None:
    """Seven maxima for eight thrusters, or a zero maximum, name the key."""
    b = matrix(layout, "torque")
    with pytest.raises(ConfigError) as info:
        PseudoInverseAllocator(b, PseudoInverseParams((max_thrust_n,) * 7))
    assert info.value.key == "upper_N"
    with pytest.raises(ConfigError) as info:
        PseudoInverseParams((max_thrust_n, 0.0))
    assert info.value.key == "max_thrust_N"


@pytest.mark.parametrize("rows", ["torque", "wrench"])
def test_min_fuel_null_rays_match_linprog(
    layout: tuple[np.ndarray, np.ndarray], rows: str
) -> None:
    """Each thruster's least-fuel null ray has the fuel scipy's linprog finds (the reference)."""
    from scipy.optimize import linprog

    from flight_sw.allocation.pseudo_inverse import _min_fuel_null_rays

    b = matrix(layout, rows)
    m, n = b.shape
    rays = _min_fuel_null_rays(b)
    assert rays is not None
    for i in range(n):
        bounds: list[tuple[float, float | None]] = [(0.0, None)] * n
        bounds[i] = (1.0, 1.0)
        ref = linprog(np.ones(n), A_eq=b, b_eq=np.zeros(m), bounds=bounds)
        assert rays[i, i] == 1.0 and np.all(rays[i] >= 0.0)
        assert np.abs(b @ rays[i]).max() <= FEASIBLE_RESIDUAL_TOL
        assert abs(rays[i].sum() - ref.fun) <= FEASIBLE_RESIDUAL_TOL


def test_equal_fuel_rays_go_to_the_lowest_numbered_thrusters() -> None:
    """Columns g, −g, −g: thruster 0 is cancelled by 1 or 2 at equal fuel; 1 is taken,
    whatever the solver's pivoting, and thruster 2's partner is 0."""
    from flight_sw.allocation.pseudo_inverse import _min_fuel_null_rays

    b = np.array([[1.0, -1.0, -1.0], [0.5, -0.5, -0.5]])
    rays = _min_fuel_null_rays(b)
    assert rays is not None
    np.testing.assert_array_equal(rays[0], [1.0, 1.0, 0.0])
    np.testing.assert_array_equal(rays[2], [1.0, 0.0, 1.0])
