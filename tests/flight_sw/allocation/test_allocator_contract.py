"""Contract of every Allocator implementation: bounds, masks, achieved = B T, residual."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams
from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams
from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams
from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator
from flight_sw.allocation.robust_polytopic import RobustParams, RobustPolytopicAllocator

T_MAX_N = 5.0
N_DEMANDS = 12
ACHIEVED_TOL = 1e-12
MASKED_THRUSTER = 3

FACTORIES: dict[str, Callable[[np.ndarray], object]] = {
    "pseudo_inverse": lambda b: PseudoInverseAllocator(b, PseudoInverseParams(T_MAX_N)),
    "qp_osqp": lambda b: BoundedQpAllocator(b, BoundedQpParams(T_MAX_N)),
    "robust_polyhedral": lambda b: RobustPolyhedralAllocator(b, RobustParams(T_MAX_N)),
    "robust_polytopic": lambda b: RobustPolytopicAllocator(b, RobustParams(T_MAX_N)),
    "robust_lft": lambda b: RobustLftAllocator(b, RobustLftParams(T_MAX_N)),
}


@pytest.mark.parametrize("kind", sorted(FACTORIES))
@pytest.mark.parametrize("which", ["b8", "b16"])
def test_allocator_contract(kind: str, which: str, request: pytest.FixtureRequest) -> None:
    """Bounds respected, masked thrusters exactly 0, achieved == B T, residual consistent."""
    b: np.ndarray = request.getfixturevalue(which)
    rng = np.random.default_rng(7)
    alloc = FACTORIES[kind](b)
    mask = np.ones(b.shape[1], dtype=bool)
    mask[MASKED_THRUSTER] = False
    masked = alloc.with_mask(mask)  # type: ignore[attr-defined]
    scale = float(np.abs(b).max()) * T_MAX_N
    demands = [rng.normal(size=b.shape[0]) * scale * s for s in (0.1, 1.0, 10.0) for _ in range(4)]
    for instance, msk in ((alloc, None), (masked, mask)):
        for d in demands[:N_DEMANDS]:
            res = instance.allocate(d)  # type: ignore[attr-defined]
            t = res.thrust_N
            assert t.shape == (b.shape[1],) and not t.flags.writeable
            assert np.all(t >= 0.0) and np.all(t <= T_MAX_N)
            if msk is not None:
                assert t[MASKED_THRUSTER] == 0.0
            assert np.allclose(res.achieved, b @ t, rtol=0.0, atol=ACHIEVED_TOL)
            assert res.residual_norm == pytest.approx(float(np.linalg.norm(d - res.achieved)))
            assert isinstance(res.saturated, bool)
    zero = alloc.allocate(np.zeros(b.shape[0]))  # type: ignore[attr-defined]
    assert zero.residual_norm <= ACHIEVED_TOL and not zero.saturated
    bad = alloc.allocate(np.full(b.shape[0], np.nan))  # type: ignore[attr-defined]
    assert np.all(bad.thrust_N == 0.0) and bad.saturated and bad.residual_norm == np.inf
