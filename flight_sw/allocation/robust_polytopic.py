"""Robust least-squares allocation over a polytopic uncertainty set (seed 001, Theorem 2).

What it does: the effectiveness matrix is only known to lie in the polytope
``B(δ) = B₀ + Σᵢ δᵢ Bᵢ``, ``δᵢ ≥ 0``, ``Σ δᵢ = 1`` (seed 001, sec. 4, set ``Δ_P``), i.e. the
convex hull of the vertices ``B₀ + Bᵢ``. The allocator returns the thrust minimising the
worst-case residual (the "SRLSCA" problem of sec. 4)

    minimise_{lo ≤ T ≤ hi}  max_{δ ∈ Δ_P} ‖B(δ) T − v‖² + ε ‖T‖²
      = minimise_{lo ≤ T ≤ hi}  max_k ‖B_k T − v‖² + ε ‖T‖²          (B_k the vertices)

(the residual is convex in δ, so the maximum over the polytope sits at a vertex). This is
Theorem 2's programme: LMI (19), ``[[−I, (B₀+Bᵢ)T − v], [·ᵀ, −λ]] < 0`` for every vertex
``i``, is by a Schur complement ``‖(B₀+Bᵢ)T − v‖² < λ``, and its bound LMIs are
``lo ≤ T ≤ hi``; we solve the same problem exactly (no LMI solver) with
:class:`flight_sw.allocation.vertex_minimax.VertexMinimaxSolver`: a one-dimensional
Lagrange dual solved by safeguarded Newton when every vertex is a multiple of one matrix
(the paper's structure), sequential quadratic programming on OSQP otherwise (see that
module). The base :class:`~flight_sw.allocation.base.ControlAllocation` holds the
nominal matrix, the per-thruster bounds and the mask.

ε = ``regularization`` × mean diagonal of ``mean_k B_kᵀ B_k`` makes the optimum unique.
With ρ = 0 (a single vertex ``B₀``) it is the bounded least-squares problem of
:mod:`flight_sw.allocation.qp_osqp`.

Uncertainty structure: ``Bᵢ = ρ Sᵢ``. By default ``Sᵢ = wᵢ B₀`` with the weights of seed 001
sec. 5 (1, 1, 2, 2: ``B₁ = B₂ = 0.1 B``, ``B₃ = B₄ = 0.2 B`` at ρ = 0.1); any q×m×n stack of
shapes ``Sᵢ`` (over all n thrusters) may be passed instead (``basis`` argument).

Inputs: ``effectiveness`` B₀ (m×n); :class:`RobustParams` (bounds [N], ρ, weights);
``mask`` (True = usable; masked thrusters are 0 and their columns dropped).
Output: :class:`~flight_sw.allocation.base.AllocationResult` for the *nominal* matrix:
``achieved = B₀ T`` and its residual; ``saturated`` when a nominal residual remains in
``range(B₀,a)`` while a bound is active. :meth:`worst_case_residual` gives the robust one.

Assumptions: the true matrix lies in the polytope; demand and thrust as in
:mod:`flight_sw.allocation.qp_osqp`.

Sources: seed 001, sec. 4 (eq. 13, set ``Δ_P``, Theorem 2, LMI (19)) and sec. 5; El Ghaoui
& Lebret 1997, "Robust solutions to least-squares problems with uncertain data", SIAM
J. Matrix Anal. Appl. 18(4) 1035–1064; Sion 1958 (minimax theorem); Han 1981, "Variable
metric methods for minimizing a
class of nondifferentiable functions", Math. Prog. 20, 1–13 (SQP for minimax); Stellato
et al. 2020 (OSQP).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.allocation.active_set import bound_active
from flight_sw.allocation.base import BoundSpec, ControlAllocation, check_bound_spec, frozen
from flight_sw.allocation.qp_osqp import DEFAULT_REGULARIZATION
from flight_sw.allocation.uncertainty import (
    SEED001_BASIS_WEIGHTS,
    SEED001_RHO,
    polytopic_vertices,
    relative_basis,
    vertex_worst_case_residual,
)
from flight_sw.allocation.vertex_minimax import VertexMinimaxSolver

DEFAULT_MAX_SQP_ITER = 30
MAX_BASIS_WEIGHTS = 16

_SOURCE = "RobustParams"


@dataclass(frozen=True)
class RobustParams:
    """Parameters of the vertex-set robust allocators (polytopic and polyhedral).

    Attributes:
        upper_N: upper thrust bound [N], one number or one per thruster (seed 001: 2.35).
        lower_N: lower thrust bound [N] (default 0; seed 001: −2.3).
        rho: uncertainty size ρ ≥ 0 (dimensionless, default 0.1 as in seed 001 sec. 5).
        basis_weights: ``wᵢ`` of the default shapes ``Sᵢ = wᵢ B₀`` (default 1, 1, 2, 2).
        regularization: ε relative to the mean diagonal of ``mean_k B_kᵀB_k`` (≥ 0).
        max_sqp_iter: bound on the SQP iterations per allocation (≥ 1; general path).
        warm_start: start from the previous call's λ and active set (scalar path) and
            warm-start OSQP from the previous subproblem (general path).
    """

    upper_N: BoundSpec
    lower_N: BoundSpec = 0.0
    rho: float = SEED001_RHO
    basis_weights: tuple[float, ...] = SEED001_BASIS_WEIGHTS
    regularization: float = DEFAULT_REGULARIZATION
    max_sqp_iter: int = DEFAULT_MAX_SQP_ITER
    warm_start: bool = True

    def __post_init__(self) -> None:
        check_bound_spec(_SOURCE, "upper_N", self.upper_N)
        check_bound_spec(_SOURCE, "lower_N", self.lower_N)
        check.non_negative(_SOURCE, "rho", self.rho)
        check.non_negative(_SOURCE, "regularization", self.regularization)
        w = self.basis_weights
        ok = isinstance(w, tuple) and len(w) <= MAX_BASIS_WEIGHTS
        if ok and w:
            check.vector(_SOURCE, "basis_weights", w, None)
        if not ok:
            raise ConfigError(_SOURCE, "basis_weights", w, "a tuple of up to 16 finite numbers")
        check.integer(_SOURCE, "max_sqp_iter", self.max_sqp_iter, 1)
        check.flag(_SOURCE, "warm_start", self.warm_start)


class VertexRobustAllocator(ControlAllocation):
    """Shared machinery of the vertex-set robust allocators (see the subclasses)."""

    _source = "VertexRobustAllocator"

    @staticmethod
    def _vertices(b0: np.ndarray, basis: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: RobustParams,
        mask: Sequence[bool] | np.ndarray | None = None,
        basis: np.ndarray | None = None,
    ) -> None:
        super().__init__(effectiveness, params, mask, params.lower_N, params.upper_N)
        b = self._b
        m, n = b.shape
        if basis is None:
            shapes = relative_basis(b, 1.0, params.basis_weights)
        else:
            shapes = np.array(basis, dtype=float)
            if shapes.ndim != 3 or shapes.shape[1:] != (m, n) or not np.all(np.isfinite(shapes)):
                raise ConfigError(self._source, "basis", shapes.shape,
                                  f"a finite q×{m}×{n} stack")
        shapes = shapes.reshape(-1, m, n)
        self._shapes = frozen(shapes)
        self._vertices_full = frozen(self._vertices(b, params.rho * shapes))
        self._solver: VertexMinimaxSolver | None = None
        if self._avail.size:
            self._solver = VertexMinimaxSolver(
                self._vertices_full[:, :, self._avail],
                self._lo_a,
                self._hi_a,
                params.regularization,
                params.max_sqp_iter,
                params.warm_start,
                self._attained_tol**2,
            )

    @property
    def vertices(self) -> np.ndarray:
        """The distinct vertex matrices of the uncertainty set, K×m×n (read-only)."""
        return self._vertices_full

    def worst_case_residual(self, thrust_N: np.ndarray, demand: np.ndarray) -> float:
        """``max_k ‖B_k T − demand‖`` over the vertices (exact worst case over the set)."""
        return vertex_worst_case_residual(self._vertices_full, thrust_N, demand)

    def _rebuild_args(self) -> tuple[Any, ...]:
        return (self._shapes,)

    def _solve(self, d: np.ndarray) -> tuple[np.ndarray, bool | None]:
        assert self._solver is not None
        t_a = self._solver.solve(d)
        return t_a, None if bound_active(t_a, self._lo_a, self._hi_a) else False


class RobustPolytopicAllocator(VertexRobustAllocator):
    """Worst-case least squares over the polytope ``conv{B₀ + ρSᵢ}`` (seed 001, Theorem 2)."""

    _source = "RobustPolytopicAllocator"

    @staticmethod
    def _vertices(b0: np.ndarray, basis: np.ndarray) -> np.ndarray:
        return polytopic_vertices(b0, basis)
