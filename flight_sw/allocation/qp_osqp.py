"""Bounded optimal allocation: weighted least squares with thrust bounds, solved by OSQP.

What it does: maps a torque (m = 3) or wrench (m = 6) demand ``d`` to thrusts ``T`` solving
the quadratic programme

    minimise   ½ (B T − d)ᵀ W (B T − d) + ½ ε ‖T‖²
    subject to lo ≤ T ≤ hi                                   (masked thrusters: T = 0)

with ``W = diag(demand_weights)`` and ``ε = regularization × mean diag(Bᵀ W B)`` (a small,
scale-free regulariser that makes the optimum unique and picks the least-norm thrust among
the least-squares optima). It is the null-space improved pseudo-inverse of seed 000,
sec. IV: eq. 28 gives the pseudo-inverse ``T₀ = Bᵀ(BBᵀ)⁻¹d``; eq. 29 adds a null-space
shift ``ζ`` (``Bζ = 0``) and eqs. 30–32 choose the shift of least size ``Σ⟨ζᵢ|ζᵢ⟩`` that
brings every thrust into its range, solved there with the simplex method. Because
``T₀ ⟂ null(B)``, ``‖T‖² = ‖T₀‖² + ‖ζ‖²``: for an attainable demand the ε → 0 limit of the QP
above *is* eq. 30's least-shift solution (exact reproduction, least thrust norm), and for
an unattainable demand (where eq. 30 has no feasible shift) it degrades gracefully to the
bounded weighted least-squares optimum instead of failing.

How it is solved (deterministic, allocation-free per call after set-up):

1. Set-up, once per availability mask: OSQP on ``x = (T_a, s)``, the available thrusts
   and the demand error ``s = B_a T_a − d``: ``P = blkdiag(ε I, W)``, ``q = 0``, constraint
   rows ``[B_a, −I] x = d`` and ``lo ≤ T_a ≤ hi``; this keeps ``P`` well conditioned.
   Each call only updates the bound vectors ``l``, ``u`` (the demand) and solves,
   warm-started from the previous solution (``warm_start``), with loose tolerances
   (:data:`OSQP_STAGE_ONE_EPS`), no polishing and at most :data:`OSQP_STAGE_ONE_MAX_ITER`
   iterations (step-size adaptation counted in iterations, no time limit): it only has to
   guess the active set. :func:`box_qp` (dense primal-dual active set, exact to round-off,
   with a finite primal active-set fallback) then solves the same ε-regularised QP exactly
   from that guess. (Before, OSQP ran to 1e-9 with polishing: some calls took thousands of
   iterations, the 1.3 ms p99.) A given call sequence gives bit-identical results.
2. Active-set refinement: the bounds found active (``T_i`` within :data:`ACTIVE_RTOL` of a
   bound) are fixed and the free thrusters take the least-norm weighted least-squares
   solution ``T_F = (W^½ B_F)⁺ W^½ (d − B_A T_A)``; it is accepted when it stays within the
   bounds and does not increase the weighted residual. This is the ε → 0 limit on that
   active set: attainable demands are reproduced to round-off, and the result depends only
   on the active set and ``d`` (not on the warm-start history) whenever it is accepted.

Inputs: ``effectiveness`` (m×n, rows as in :mod:`flight_sw.allocation.effectiveness`);
``params`` (:class:`BoundedQpParams`: thrust bounds ``lower_N``/``upper_N`` [N], scalar or
per thruster, e.g. [0, T_max] for on-off thrusters or the signed [−2.3, 2.35] N of
seed 001); availability ``mask`` (True = usable).
Output: :class:`~flight_sw.allocation.base.AllocationResult`: thrust [N] within the
bounds, masked thrusters exactly 0, ``achieved = B T``, the residual norm, and
``saturated`` when a residual remains inside the attainable subspace ``range(B_a)`` (the
bounds were active and cost accuracy; a residual only along directions no thruster can
produce is not saturation). A non-finite demand gives all zeros, an infinite residual,
saturated.

Assumptions: mean thrust over a control period is realised downstream (modulators);
thrusters are independent; ``lo ≤ hi`` per thruster.

The base (:class:`~flight_sw.allocation.base.ControlAllocation`) holds the matrix, the
per-thruster bounds and the mask; the exact stages are :mod:`flight_sw.allocation.active_set`'s.

Sources: seed 000 (dual-quaternion 6-DoF control), sec. IV, eqs. 27–32 (pseudo-inverse,
null-space shift, least-shift programme); OSQP: Stellato et al. 2020, "OSQP: an operator
splitting solver for quadratic programs", Math. Prog. Comp. 12, 637–672; least-norm
solution of the free set: Björck 1996, "Numerical Methods for Least Squares Problems",
sec. 5.2 (active-set methods for bounded least squares); Hintermüller, Ito & Kunisch 2003,
SIAM J. Optim. 13(3) 865–888 (primal-dual active set); Nocedal & Wright 2006, alg. 16.3.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import osqp
import scipy.sparse as sp

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.allocation.active_set import (
    ACTIVE_RTOL,
    AT_LOWER,
    AT_UPPER,
    FREE,
    box_qp,
    refine,
    ridge,
)
from flight_sw.allocation.base import (
    MAX_DEMAND_DIM,
    BoundSpec,
    ControlAllocation,
    check_bound_spec,
)
from flight_sw.allocation.osqp_lean import LeanOsqp, osqp_settings

DEFAULT_REGULARIZATION = 1e-6

_SOURCE = "BoundedQpParams"


@dataclass(frozen=True)
class BoundedQpParams:
    """Parameters of the OSQP bounded least-squares allocator.

    Attributes:
        upper_N: upper thrust bound [N], one number for all thrusters or one per thruster.
        lower_N: lower thrust bound [N] (default 0: on-off thrusters; negative for
            bidirectional ones, e.g. −2.3 N in seed 001).
        regularization: ε relative to the mean diagonal of ``BᵀWB`` (≥ 0, default 1e-6);
            picks the least-norm thrust among equally good ones.
        demand_weights: per-row weights ``W`` of the demand error (m positive numbers),
            None = all 1.
        warm_start: warm-start OSQP from the previous call's solution.
    """

    upper_N: BoundSpec
    lower_N: BoundSpec = 0.0
    regularization: float = DEFAULT_REGULARIZATION
    demand_weights: tuple[float, ...] | None = None
    warm_start: bool = True

    def __post_init__(self) -> None:
        check_bound_spec(_SOURCE, "upper_N", self.upper_N)
        check_bound_spec(_SOURCE, "lower_N", self.lower_N)
        check.non_negative(_SOURCE, "regularization", self.regularization)
        w = self.demand_weights
        if w is not None:
            check.vector(_SOURCE, "demand_weights", w, None, 0.0, lo_open=True)
            if not (isinstance(w, tuple) and len(w) <= MAX_DEMAND_DIM):
                raise ConfigError(_SOURCE, "demand_weights", w, "a tuple of 1..6 numbers > 0")
        check.flag(_SOURCE, "warm_start", self.warm_start)


class BoundedQpAllocator(ControlAllocation):
    """Bounded weighted least-squares allocator on OSQP (a ``ControlAllocation``)."""

    _source = "BoundedQpAllocator"

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: BoundedQpParams,
        mask: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        super().__init__(effectiveness, params, mask, params.lower_N, params.upper_N)
        m = self._b.shape[0]
        if params.demand_weights is None:
            w = np.ones(m)
        else:
            w = np.array(params.demand_weights, dtype=float)
            if w.shape != (m,):
                raise ConfigError(self._source, "demand_weights", params.demand_weights,
                                  f"{m} numbers")
        b_a = self._b_a
        self._sqrt_w = np.sqrt(w)
        self._b_w = self._sqrt_w[:, None] * b_a
        k = self._avail.size
        self._osqp: Any = None
        if k:
            eps = ridge(self._b_w, params.regularization)
            p = sp.block_diag([eps * sp.identity(k), sp.diags(w)], format="csc")
            a = sp.bmat(
                [[sp.csc_matrix(b_a), -sp.identity(m)], [sp.identity(k), None]], format="csc"
            )
            self._l = np.concatenate([np.zeros(m), self._lo_a])
            self._u = np.concatenate([np.zeros(m), self._hi_a])
            problem = osqp.OSQP()
            problem.setup(
                p,
                np.zeros(k + m),
                a,
                self._l,
                self._u,
                **osqp_settings(params.warm_start, stage_one=True),
            )
            self._osqp = LeanOsqp(problem)
            self._m_mat = self._b_w.T @ self._b_w + eps * np.eye(k)
            self._m_list = self._m_mat.tolist()
            self._definite = eps > 0.0
        # the previous call's exact active set: the warm start of box_qp when OSQP stopped
        # at its iteration cap without converging (its guess is then often far off)
        self._state_prev: np.ndarray | None = None

    def _solve(self, d: np.ndarray) -> tuple[np.ndarray, bool | None]:
        m = d.shape[0]
        self._l[:m] = d
        self._u[:m] = d
        self._osqp.update(l=self._l, u=self._u)
        res = self._osqp.solve()
        converged = res.solved
        x = res.x
        k = self._avail.size
        t_qp = x[:k] if x.shape == (k + m,) and np.all(np.isfinite(x)) else np.zeros(k)
        t_qp = np.minimum(np.maximum(t_qp, self._lo_a), self._hi_a)
        d_w = self._sqrt_w * d
        # Exact dense active-set solve of the same QP, warm-started from OSQP's active set.
        tol = ACTIVE_RTOL * (self._hi_a - self._lo_a)
        state = np.where(
            t_qp <= self._lo_a + tol, AT_LOWER, np.where(t_qp >= self._hi_a - tol, AT_UPPER, FREE)
        ).astype(np.int8)
        if not converged and self._state_prev is not None and self._params.warm_start:
            state = self._state_prev
        t_qp, final_state = box_qp(
            self._m_mat, self._b_w.T @ d_w, self._lo_a, self._hi_a, state, self._definite,
            self._m_list,
        )
        self._state_prev = final_state
        t = refine(self._b_w, d_w, t_qp, self._lo_a, self._hi_a, self._attained_tol**2)
        return t, None
