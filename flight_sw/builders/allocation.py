"""Builders of the allocation strategies: ``[flight_sw.allocator]``.

What it does: one builder per ``kind`` (:data:`ALLOCATORS`): the bounded pseudo-inverse
(seeds 003/000), the bounded QP on OSQP (seed 000 eqs. 27–32) and the three robust
allocators of seed 001 (Theorems 1–3). Every one gets the effectiveness rows the
vehicle's controllers demand (torque, or the wrench in 6 DoF) and each thruster's own
maximum thrust [N] as its upper bound (a vector, shape (n,)). Each builder imports its
strategy's module when it is chosen: the flight software's start-up loads only what its
configuration uses (OSQP, scipy.sparse and the robust set-up cost ~0.3 s to import).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING

from dbc.schema import Table
from flight_sw.allocation.base import Allocator
from flight_sw.builders.vehicle import Vehicle, matrix, upper_N

if TYPE_CHECKING:
    from flight_sw.allocation.robust_polytopic import RobustParams


def _pseudo_inverse(t: Table, v: Vehicle) -> Allocator:
    """Seeds 003/000 baseline; each thruster bounded by its own maximum thrust."""
    from flight_sw.allocation.pseudo_inverse import PseudoInverseAllocator, PseudoInverseParams

    b = v.effectiveness[v.demand_rows]
    return PseudoInverseAllocator(b, PseudoInverseParams(max_thrust_N=upper_N(v)))


def _qp_osqp(t: Table, v: Vehicle) -> Allocator:
    """Seed 000 eqs. 27-32: bounded least-shift allocation, an OSQP QP."""
    from flight_sw.allocation.qp_osqp import BoundedQpAllocator, BoundedQpParams

    d = BoundedQpParams(upper_N=1.0)
    m = v.demand_rows.stop - v.demand_rows.start
    weights = t.vector("demand_weights", m) if t.has("demand_weights") else None
    params = BoundedQpParams(
        upper_N=upper_N(v),
        regularization=t.number("regularization", d.regularization, lo=0.0, lo_open=True),
        demand_weights=weights,
    )
    return BoundedQpAllocator(v.effectiveness[v.demand_rows], params)


def _robust_params(t: Table, v: Vehicle) -> RobustParams:
    from flight_sw.allocation.robust_polytopic import RobustParams

    d = RobustParams(upper_N=1.0)
    weights = t.raw("basis_weights", list(d.basis_weights))
    if not (
        isinstance(weights, list)
        and weights
        and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in weights)
    ):
        raise t.error("basis_weights", weights, "a non-empty list of numbers")
    return RobustParams(
        upper_N=upper_N(v),
        rho=t.number("rho", d.rho, lo=0.0),
        basis_weights=tuple(float(x) for x in weights),
    )


def _robust_polyhedral(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 1: ΔB = Σ δ_i ρ w_i B, |δ_i| ≤ 1 (the §5 example by default)."""
    from flight_sw.allocation.robust_polyhedral import RobustPolyhedralAllocator

    return RobustPolyhedralAllocator(v.effectiveness[v.demand_rows], _robust_params(t, v))


def _robust_polytopic(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 2: ΔB in the convex hull of ±ρ w_i B."""
    from flight_sw.allocation.robust_polytopic import RobustPolytopicAllocator

    return RobustPolytopicAllocator(v.effectiveness[v.demand_rows], _robust_params(t, v))


def _robust_lft(t: Table, v: Vehicle) -> Allocator:
    """Seed 001 Theorem 3: ΔB = E F H, ‖F‖ ≤ 1 (E = ρ e_shape; H from the table or B)."""
    from flight_sw.allocation.robust_lft import RobustLftAllocator, RobustLftParams

    d = RobustLftParams(upper_N=1.0)
    m = v.demand_rows.stop - v.demand_rows.start
    e_shape = matrix(t, "e_shape", m, m) if t.has("e_shape") else None
    h = t.raw("h_matrix", None)
    h_matrix = None
    if h is not None:
        rows = len(h) if isinstance(h, list) else 0
        h_matrix = matrix(t, "h_matrix", rows, len(v.r_thr_B_m))
    return RobustLftAllocator(
        v.effectiveness[v.demand_rows],
        RobustLftParams(
            upper_N=upper_N(v),
            rho=t.number("rho", d.rho, lo=0.0),
            e_shape=None if e_shape is None else tuple(tuple(map(float, r)) for r in e_shape),
            h_matrix=None if h_matrix is None else tuple(tuple(map(float, r)) for r in h_matrix),
        ),
    )


ALLOCATORS: Mapping[str, Callable[[Table, Vehicle], Allocator]] = MappingProxyType({
    "pseudo_inverse": _pseudo_inverse,
    "qp_osqp": _qp_osqp,
    "robust_polyhedral": _robust_polyhedral,
    "robust_polytopic": _robust_polytopic,
    "robust_lft": _robust_lft,
})
