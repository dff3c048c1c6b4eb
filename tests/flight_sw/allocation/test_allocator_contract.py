"""Contract of every Allocator implementation: bounds, masks, achieved = B T, residual."""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable

import numpy as np
import pytest

from flight_sw import allocation
from flight_sw.allocation.base import ControlAllocation
from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator

T_MAX_N = 5.0
N_DEMANDS = 12
ACHIEVED_TOL = 1e-12
MASKED_THRUSTER = 3
# Non-uniform layouts: every other thruster's maximum is this fraction of T_MAX_N.
WEAK_THRUSTER_FRACTION = 0.8

Upper = float | tuple[float, ...]
FACTORIES: dict[str, Callable[[np.ndarray, Upper], ControlAllocation]] = {
    "pseudo_inverse": lambda b, u: PseudoInverseAllocator(b, PseudoInverseParams(u)),
    "qp_osqp": lambda b, u: BoundedQpAllocator(b, BoundedQpParams(u)),
    "robust_polyhedral": lambda b, u: RobustPolyhedralAllocator(b, RobustParams(u)),
    "robust_polytopic": lambda b, u: RobustPolytopicAllocator(b, RobustParams(u)),
    "robust_lft": lambda b, u: RobustLftAllocator(b, RobustLftParams(u)),
}


def _upper(n: int, bounds: str) -> Upper:
    """T_MAX_N for every thruster, or alternately T_MAX_N and a weaker maximum."""
    if bounds == "uniform":
        return T_MAX_N
    return tuple(T_MAX_N * (WEAK_THRUSTER_FRACTION if k % 2 else 1.0) for k in range(n))


def _leaf_strategies() -> set[type]:
    """Every ControlAllocation subclass of flight_sw.allocation that nothing extends."""
    for info in pkgutil.iter_modules(allocation.__path__):
        importlib.import_module(f"{allocation.__name__}.{info.name}")
    found: set[type] = set()
    todo: list[type] = [ControlAllocation]
    while todo:
        cls = todo.pop()
        subs = cls.__subclasses__()
        if not subs and cls is not ControlAllocation:
            found.add(cls)
        todo += subs
    return {c for c in found if c.__module__.startswith(allocation.__name__)}


def test_every_strategy_is_under_contract() -> None:
    """Each allocation strategy of the package has a factory here (the contract runs on it)."""
    covered = {type(f(np.eye(3), T_MAX_N)) for f in FACTORIES.values()}
    assert _leaf_strategies() == covered


@pytest.mark.parametrize("kind", sorted(FACTORIES))
@pytest.mark.parametrize("which", ["b8", "b16"])
@pytest.mark.parametrize("bounds", ["uniform", "per_thruster"])
def test_allocator_contract(
    kind: str, which: str, bounds: str, request: pytest.FixtureRequest
) -> None:
    """Bounds respected, masked thrusters exactly 0, achieved == B T, residual consistent."""
    b: np.ndarray = request.getfixturevalue(which)
    rng = np.random.default_rng(7)
    upper = np.broadcast_to(np.array(_upper(b.shape[1], bounds)), (b.shape[1],))
    alloc = FACTORIES[kind](b, _upper(b.shape[1], bounds))
    mask = np.ones(b.shape[1], dtype=bool)
    mask[MASKED_THRUSTER] = False
    masked = alloc.with_mask(mask)
    assert type(masked) is type(alloc) and masked.params is alloc.params
    np.testing.assert_array_equal(masked.bounds_N[1], upper)
    scale = float(np.abs(b).max()) * T_MAX_N
    demands = [rng.normal(size=b.shape[0]) * scale * s for s in (0.1, 1.0, 10.0) for _ in range(4)]
    for instance, msk in ((alloc, None), (masked, mask)):
        for d in demands[:N_DEMANDS]:
            res = instance.allocate(d)
            t = res.thrust_N
            assert t.shape == (b.shape[1],) and not t.flags.writeable
            assert np.all(t >= 0.0) and np.all(t <= upper)
            if msk is not None:
                assert t[MASKED_THRUSTER] == 0.0
            assert np.allclose(res.achieved, b @ t, rtol=0.0, atol=ACHIEVED_TOL)
            assert res.residual_norm == pytest.approx(float(np.linalg.norm(d - res.achieved)))
            assert isinstance(res.saturated, bool)
    zero = alloc.allocate(np.zeros(b.shape[0]))
    assert zero.residual_norm <= ACHIEVED_TOL and not zero.saturated
    bad = alloc.allocate(np.full(b.shape[0], np.nan))
    assert np.all(bad.thrust_N == 0.0) and bad.saturated and bad.residual_norm == np.inf


@pytest.mark.parametrize("kind", sorted(FACTORIES))
@pytest.mark.parametrize("which", ["b8", "b16"])
def test_warm_up_leaves_results_unchanged(
    kind: str, which: str, request: pytest.FixtureRequest
) -> None:
    """A warmed-up allocator (and a masked one) returns bit-identical thrusts to a cold one."""
    b: np.ndarray = request.getfixturevalue(which)
    rng = np.random.default_rng(11)
    scale = float(np.abs(b).max()) * T_MAX_N
    demands = [rng.normal(size=b.shape[0]) * scale * s for s in (0.1, 1.0, 10.0) for _ in range(3)]
    mask = np.ones(b.shape[1], dtype=bool)
    mask[MASKED_THRUSTER] = False
    for m in (None, mask):
        cold = FACTORIES[kind](b, T_MAX_N)
        warm = FACTORIES[kind](b, T_MAX_N)
        if m is not None:
            cold, warm = cold.with_mask(m), warm.with_mask(m)
        warm.warm_up()
        for d in demands:
            assert np.array_equal(warm.allocate(d).thrust_N, cold.allocate(d).thrust_N)
