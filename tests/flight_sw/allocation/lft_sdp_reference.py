"""Reference for the LFT allocator: seed 001 Theorem 3 as the semidefinite programme it is.

The exact worst-case bounded least squares under ``ΔB = E F H``, ``‖F‖ ≤ 1``:

    minimise t  over (T, t, λ ≥ 0)  subject to  lo ≤ T ≤ hi  and
    [[t,  rᵀ,            (HT)ᵀ],
     [r,  tI − λEEᵀ,     0    ],
     [HT, 0,             λI   ]] ⪰ 0,      r = B₀T − v,

whose optimal ``t`` is ``min_T max_{‖F‖≤1} ‖(B₀ + EFH)T − v‖`` (Schur complement of
``‖r + EFHT‖ ≤ t`` and Petersen's lemma, lossless for one full block; seed 001 LMI (20),
El Ghaoui & Lebret 1997). Solved by cvxpy with Clarabel (interior point); nothing here
is shared with the allocator, which solves the same problem by an active-set τ search.
"""

from __future__ import annotations

import cvxpy as cp
import numpy as np

REFERENCE_SOLVER = "CLARABEL"


class LftSdpReference:
    """``optimum(v)``: the exact robust residual for ``B₀``, ``E``, ``H`` and the box."""

    def __init__(self, b0: np.ndarray, e: np.ndarray, h: np.ndarray, lo: float, hi: float):
        m, n = b0.shape
        q = h.shape[0]
        self._thrust = cp.Variable(n)
        self._t = cp.Variable()
        lam = cp.Variable(nonneg=True)
        self._v = cp.Parameter(m)
        r = cp.reshape(b0 @ self._thrust - self._v, (m, 1), order="C")
        hv = cp.reshape(h @ self._thrust, (q, 1), order="C")
        t11 = cp.reshape(self._t, (1, 1), order="C")
        lmi = cp.bmat([
            [t11, r.T, hv.T],
            [r, self._t * np.eye(m) - lam * (e @ e.T), np.zeros((m, q))],
            [hv, np.zeros((q, m)), lam * np.eye(q)],
        ])  # fmt: skip
        constraints = [(lmi + lmi.T) / 2 >> 0, self._thrust >= lo, self._thrust <= hi]
        self._problem = cp.Problem(cp.Minimize(self._t), constraints)

    def optimum(self, v: np.ndarray) -> float:
        """``min_{lo ≤ T ≤ hi} max_{‖F‖≤1} ‖(B₀ + EFH)T − v‖`` (solver accuracy ~1e-8)."""
        self._v.value = np.asarray(v, dtype=float)
        self._problem.solve(solver=REFERENCE_SOLVER)
        if self._problem.status != cp.OPTIMAL:
            raise RuntimeError(f"reference SDP not solved: {self._problem.status}")
        return max(float(self._t.value), 0.0)
