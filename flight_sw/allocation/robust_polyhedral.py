"""Robust least-squares allocation over a regular polyhedral uncertainty set (seed 001, Thm 1).

What it does: the effectiveness matrix is only known to be ``B(δ) = B₀ + Σᵢ δᵢ Bᵢ``
(seed 001, eq. 13) with every ``δᵢ ∈ [−1, 1]`` independently (the "regular polyhedral" set
``Δ_I`` of sec. 4). The allocator returns the thrust minimising the worst-case residual

    minimise_{lo ≤ T ≤ hi}  max_{δ ∈ Δ_I} ‖B(δ) T − v‖² + ε ‖T‖²
      = minimise_{lo ≤ T ≤ hi}  max_{δ ∈ Δ_E} ‖B(δ) T − v‖² + ε ‖T‖²,

``Δ_E = {−1, 1}^q`` the 2^q corners: the residual is convex in δ, so its maximum over the
box is at a corner. This is Theorem 1 exactly: its LMI (14) is imposed "for ∀δ ∈ Δ_E" and,
by a Schur complement, reads ``‖B(δ)T − v‖² < λ``; (15)–(16) are the thrust bounds. The box
is a polytope with the corner matrices as vertices, so the same exact solver as the
polytopic case is used (:class:`flight_sw.allocation.robust_polytopic.VertexMinimaxSolver`;
see that module for the iterations, their stopping rules and determinism). Repeated
corner matrices are merged; with the paper's ``Bᵢ ∝ B₀`` every corner is ``(1 + c)B₀``
and only the extreme multiples ``(1 ± ρΣwᵢ)B₀`` matter, so the exact one-dimensional
dual path applies (a dense box QP per step, no OSQP); other bases take the SQP path.

Uncertainty structure: ``Bᵢ = ρ Sᵢ``; by default ``Sᵢ = wᵢ B₀`` with seed 001 sec. 5's
weights (1, 1, 2, 2: ``B₁ = B₂ = 0.1 B``, ``B₃ = B₄ = 0.2 B``, ``δᵢ ∈ [−1, 1]`` at ρ = 0.1), or
any q×m×n stack of shapes passed as ``basis`` (q ≤ :data:`MAX_POLYHEDRAL_BASIS`, since the
corners number 2^q).

Inputs/outputs: as :class:`flight_sw.allocation.robust_polytopic.RobustPolytopicAllocator`
(parameters :class:`~flight_sw.allocation.robust_polytopic.RobustParams`; nominal
``achieved = B₀ T``; :meth:`worst_case_residual` over the corners).

Assumptions: independent bounded uncertain parameters entering linearly.

Sources: seed 001, sec. 4 (eq. 13, set ``Δ_I``, Theorem 1, LMIs (14)–(16)) and sec. 5;
Boyd et al. 1994, "Linear Matrix Inequalities in System and Control Theory", SIAM,
sec. 2.6 (vertex conditions for polytopic LMIs); El Ghaoui & Lebret 1997, SIAM J. Matrix
Anal. Appl. 18(4) 1035–1064.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dbc.errors import ConfigError
from flight_sw.allocation.robust_polytopic import RobustParams, VertexRobustAllocator
from flight_sw.allocation.uncertainty import MAX_POLYHEDRAL_BASIS, polyhedral_vertices


class RobustPolyhedralAllocator(VertexRobustAllocator):
    """Worst-case least squares over ``B₀ + Σ δᵢ ρSᵢ``, ``|δᵢ| ≤ 1`` (seed 001, Theorem 1)."""

    _source = "RobustPolyhedralAllocator"

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: RobustParams,
        mask: Sequence[bool] | np.ndarray | None = None,
        basis: np.ndarray | None = None,
    ) -> None:
        q = len(params.basis_weights) if basis is None else np.asarray(basis).shape[0]
        if q > MAX_POLYHEDRAL_BASIS:
            raise ConfigError(self._source, "basis", q, f"at most {MAX_POLYHEDRAL_BASIS} matrices")
        super().__init__(effectiveness, params, mask, basis)

    @staticmethod
    def _vertices(b0: np.ndarray, basis: np.ndarray) -> np.ndarray:
        return polyhedral_vertices(b0, basis)
