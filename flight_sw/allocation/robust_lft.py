"""Robust least-squares allocation under linear-fractional uncertainty (seed 001, Theorem 3).

What it does: the effectiveness matrix is ``B₀ + E F H`` with an unknown full block ``F``,
``FᵀF ≤ I`` (seed 001, sec. 4, Theorem 3). The allocator returns the thrust minimising the
exact worst-case residual

    minimise_{lo ≤ T ≤ hi}  max_{‖F‖≤1} ‖(B₀ + E F H) T − v‖² + ε ‖T‖².

Reformulation (exact): with ``r = B₀T − v`` and ``h = HT`` the inner maximum is the
trust-region value ``max_{‖w‖≤‖h‖} ‖r + E w‖²``; the S-lemma is lossless for one
constraint, giving (see :mod:`flight_sw.allocation.uncertainty`)

    min_{T, 0<τ<1/σ_max(E)²}  f(T, τ) = rᵀ (I − τ EEᵀ)⁻¹ r + ‖H T‖²/τ + ε ‖T‖²,

the Schur complement of Theorem 3's LMI (20) with its ``δ`` = τ (the paper's Lemma 1 is
this bound; for a single full block it is tight, El Ghaoui & Lebret 1997), so Theorem 3 is
solved exactly here, not through an upper bound. ``f`` is jointly convex in ``(T, τ)``
(matrix-fractional plus quadratic-over-linear terms). Special cases: ``EEᵀ = σ² I`` gives
``min (‖r‖ + σ‖HT‖)²`` (El Ghaoui–Lebret's SOCP); in general
``‖r‖ + ‖E‖‖HT‖`` is only an upper bound of the worst case, which the τ form avoids.

How it is solved (exact up to the stopping tolerances below): partial minimisation.
``φ(τ) = min_{lo ≤ T ≤ hi} f(T, τ)`` is convex in τ (partial minimum of a jointly convex
function) with ``φ'(τ) = ∂f/∂τ`` at the inner minimiser ``T(τ)`` (Danskin):

1. inner problem (τ fixed): the box QP ``min TᵀM T − 2cᵀT`` with
   ``M = CᵀDC + HᵀH/τ + εI``, ``c = CᵀD Uᵀv``, ``C = UᵀB₀``, ``D = diag(1/(1 − τ sⱼ))``,
   solved exactly by the dense active-set :func:`~flight_sw.allocation.active_set.box_qp`,
   warm-started from the previous active set;
2. outer problem: ``φ'(τ) = 0`` on ``θ = τ·max s ∈ [LFT_THETA_MIN, LFT_THETA_MAX]`` by
   safeguarded Newton (:func:`~flight_sw.allocation.root_finding.monotone_root`; ``φ''`` from
   the sensitivity of ``T`` on its active set: ``f_ττ − 2 wᵀ M_FF⁻¹ w``), started from the
   previous allocation's θ (cold: :data:`LFT_THETA_START`). It stops when the Newton
   decrement ``φ'²/φ''`` (≈ ``φ(τ) − min φ``) is below :data:`LFT_RTOL` × ``f`` — a global
   criterion, unlike the block-coordinate descent used before, which stopped on a small
   *per-round* decrease and could end far from the optimum (0.2 above a scipy reference
   at ρ = 0.5 with a random H).

3. refinement (ε → 0): the search runs with the ridge ``ε‖T‖²`` (it makes ``M`` definite,
   and the optimum unique), which biases the answer: on seed 001 most demands have an
   exact optimum of 0 (``B₀T = v`` and ``HT = 0`` inside the box), where the ridge left a
   worst case of up to 8e-4 N m. At the final τ, the thrusts are replaced by the
   least-norm minimiser of the unregularised ``f(·, τ)`` on the same active set — the
   weighted least squares ``[D^½C; H/√τ] T ≈ [D^½Uᵀv; 0]`` solved by SVD
   (:func:`~flight_sw.allocation.active_set.refine`, well conditioned where
   the normal equations are not) — kept when they do not raise the unregularised
   objective. Because ``f(T, τ) ≥ max_F ‖(B₀+EFH)T − v‖²`` for every τ, the worst case
   of the refined thrusts is at most the unregularised optimum at the final τ.

What ``regularization`` may be: the ridge is a numerical device, not a design choice, so
it is held to :data:`LFT_REGULARIZATION_RANGE`. Below it, near θ = 1 (where most seed-001
optima lie: the weight ``1/(1 − θ)`` reaches 1e6) the ridge falls under the Cholesky
pivot tolerance of ``M`` and the warm-started box QP can stop on a wrong active set
(0.036 N m above the optimum at ε = 1e-9, and ``regularization = 0`` is refused for the
same reason: ``M`` is then singular wherever ``H`` and ``B₀`` share a null direction,
three of the eight on seed 001); above it, the ridge moves the active set and τ enough
that the refinement on that active set is no longer the exact optimum (2e-4 N m at
3e-6). Inside the range, on 650 seed-001 demands (the Case-1 torques and random ones),
the worst case is within 1e-8 N m (5e-8 relative) of an independent SDP solution of
Theorem 3's LMI (benchmarks/robust_allocation.py; tests/flight_sw/allocation).

The other approximation: θ is held to [:data:`LFT_THETA_MIN`, :data:`LFT_THETA_MAX`] =
[1e-6, 1 − 1e-6]. When the optimum is the "hard case" τ* = 1/max s, or has ``HT = 0``
(τ* → 0), the value returned exceeds the exact one by at most ``|φ'|`` at that end times
1e-6 (convexity): a bound, documented here, not silently exact.

Parameters: ``E = ρ E_shape`` (default ``E_shape = I_m``) and ``H`` (default
``diag(‖B₀ e_j‖)``: the error of each thruster's column scales with its effect); seed 001
sec. 5 uses ``E = diag(0.1, 0.15, 0.1)`` (ρ = 0.1, ``E_shape = diag(1, 1.5, 1)``) and a
3×8 ``H`` (:data:`~flight_sw.allocation.uncertainty.SEED001_LFT_H`). With ρ = 0 this is
the bounded least-squares problem.

Inputs: ``effectiveness`` B₀ (m×n); :class:`RobustLftParams`; ``mask`` (True = usable).
Output: :class:`~flight_sw.allocation.base.AllocationResult` for the nominal matrix
(``achieved = B₀T``); :meth:`RobustLftAllocator.worst_case_residual` gives the exact worst
case. ``saturated``: a nominal residual remains in ``range(B₀,a)`` while a bound is active.

Assumptions: a single unstructured block ``F`` (a block-diagonal ``F`` would make the
S-procedure, and so this value, an upper bound).

Sources: seed 001, sec. 4, Lemma 1, Theorem 3, LMI (20), and sec. 5; El Ghaoui & Lebret
1997, "Robust solutions to least-squares problems with uncertain data", SIAM J. Matrix
Anal. Appl. 18(4) 1035–1064; Boyd & Vandenberghe 2004, "Convex Optimization", sec. 3.1.7
(matrix-fractional function), app. B (S-procedure); Hintermüller, Ito & Kunisch 2003
(primal-dual active set).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from dbc.errors import ConfigError
from flight_sw.allocation.active_set import FREE, bound_active, box_qp, refine, ridge
from flight_sw.allocation.base import (
    RANK_RTOL,
    BoundSpec,
    ControlAllocation,
    check_bound_spec,
    frozen,
)
from flight_sw.allocation.dense import PD_PIVOT_RTOL, spd_solve
from flight_sw.allocation.qp_osqp import DEFAULT_REGULARIZATION
from flight_sw.allocation.root_finding import monotone_root
from flight_sw.allocation.uncertainty import (
    EIG_RTOL,
    SEED001_RHO,
    lft_worst_case_residual,
)

# Stop when a round lowers the objective by less than this fraction of it.
LFT_RTOL = 1e-10
# The ridge ε of the τ search (relative to the mean diagonal of B₀ᵀB₀) the refinement
# makes exact: below, M is numerically singular near θ = 1; above, the ridge moves the
# active set (see the module docstring).
LFT_REGULARIZATION_RANGE = (1e-7, 1e-6)
DEFAULT_MAX_LFT_ITER = 50
# First θ = τ·σ_max(E)² tried when there is no previous allocation to warm-start from.
LFT_THETA_START = 0.5
# The τ search runs on θ = τ·σ_max(E)² in [LFT_THETA_MIN, LFT_THETA_MAX]: near θ = 1 the
# weight 1/(1 − θ) of the worst direction, near θ = 0 the weight 1/τ of ‖HT‖², make the
# T-step ill-conditioned (at θ = 1e-12 the box QP's pivots dropped B₀ altogether and
# returned T = 0). φ is convex, so stopping at an end costs at most |φ'|·(distance to the
# interval's end) of the squared worst case: the "hard case" τ* = 1/σ_max² at the top, an
# optimum with HT = 0 (τ* → 0) at the bottom, where the refinement then solves the
# weighted least squares with weight 1e6 on HT.
LFT_THETA_MIN = 1e-6
LFT_THETA_MAX = 1.0 - 1e-6

_SOURCE = "RobustLftParams"

Matrix = tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class RobustLftParams:
    """Parameters of the linear-fractional robust allocator.

    Attributes:
        upper_N: upper thrust bound [N], one number or one per thruster (seed 001: 2.35).
        lower_N: lower thrust bound [N] (default 0; seed 001: −2.3).
        rho: uncertainty size ρ ≥ 0 scaling ``E = ρ E_shape`` (default 0.1).
        e_shape: ``E_shape`` (m×p rows), None = the m×m identity.
        h_matrix: ``H`` (p'×n rows, over all n thrusters), None = ``diag(‖B₀ e_j‖)``.
        regularization: the τ search's ridge ε relative to the mean diagonal of ``B₀ᵀB₀``,
            within :data:`LFT_REGULARIZATION_RANGE` (refined away: the answer is the
            unregularised optimum).
        max_iter: bound on the τ-search evaluations (inner box QPs) per allocation (≥ 1).
        warm_start: start from the previous call's τ and active set (deterministic).
    """

    upper_N: BoundSpec
    lower_N: BoundSpec = 0.0
    rho: float = SEED001_RHO
    e_shape: Matrix | None = None
    h_matrix: Matrix | None = None
    regularization: float = DEFAULT_REGULARIZATION
    max_iter: int = DEFAULT_MAX_LFT_ITER
    warm_start: bool = True

    def __post_init__(self) -> None:
        check_bound_spec(_SOURCE, "upper_N", self.upper_N)
        check_bound_spec(_SOURCE, "lower_N", self.lower_N)
        check.non_negative(_SOURCE, "rho", self.rho)
        low, high = LFT_REGULARIZATION_RANGE
        if not low <= self.regularization <= high:
            raise ConfigError(
                _SOURCE, "regularization", self.regularization,
                f"a ridge in [{low:g}, {high:g}]: the answer is refined to the unregularised "
                "optimum, which is exact only in that range (below it the S-lemma inner "
                "matrix is numerically singular near the hard case; above it the ridge moves "
                "the active set)",
            )  # fmt: skip
        for key in ("e_shape", "h_matrix"):
            value = getattr(self, key)
            if value is not None and not isinstance(value, tuple):
                raise ConfigError(_SOURCE, key, value, "a tuple of tuples of finite numbers")
            if value is not None:
                check.matrix(_SOURCE, key, value)
        check.integer(_SOURCE, "max_iter", self.max_iter, 1)
        check.flag(_SOURCE, "warm_start", self.warm_start)


class RobustLftAllocator(ControlAllocation):
    """Exact worst-case least squares under ``ΔB = E F H``, ``‖F‖ ≤ 1`` (seed 001, Thm 3)."""

    _source = "RobustLftAllocator"

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: RobustLftParams,
        mask: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        super().__init__(effectiveness, params, mask, params.lower_N, params.upper_N)
        src = self._source
        b = self._b
        m, n = b.shape
        e_shape = np.eye(m) if params.e_shape is None else np.array(params.e_shape, dtype=float)
        if e_shape.shape[0] != m:
            raise ConfigError(src, "e_shape", e_shape.shape, f"{m} rows")
        if params.h_matrix is None:
            h_full = np.diag(np.linalg.norm(b, axis=0))
        else:
            h_full = np.array(params.h_matrix, dtype=float)
            if h_full.shape[1] != n:
                raise ConfigError(src, "h_matrix", h_full.shape, f"{n} columns")
        self._e = frozen(params.rho * e_shape)
        self._h = frozen(h_full)
        b_a = self._b_a
        h_a = h_full[:, self._avail]
        self._h_a = h_a
        s, u = np.linalg.eigh(self._e @ self._e.T)
        s_max = float(np.max(s)) if s.size else 0.0
        self._eig_s = np.where(s > EIG_RTOL * max(s_max, 0.0), s, 0.0)
        self._eig_u = u
        self._uncertain = s_max > 0.0 and bool(np.any(h_a != 0.0))
        k = self._avail.size
        self._eps = ridge(b_a, params.regularization)
        self._definite = self._eps > 0.0
        self._s_max = s_max
        # Eigenbasis data: C = UᵀB₀ (rows along the eigenvectors of EEᵀ), HᵀH, B₀ᵀB₀.
        self._c_mat = u.T @ b_a
        self._hth = h_a.T @ h_a
        self._eye = np.eye(k)
        self._nominal_m = b_a.T @ b_a + self._eps * self._eye
        self._state = np.full(k, FREE, dtype=np.int8)
        self._theta_warm = math.nan

    @property
    def lft_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``(E, H)`` of ``ΔB = E F H`` (read-only; ``E = ρ E_shape``)."""
        return self._e, self._h

    def worst_case_residual(self, thrust_N: np.ndarray, demand: np.ndarray) -> float:
        """``max_{‖F‖≤1} ‖(B₀ + EFH) T − demand‖`` (exact)."""
        return lft_worst_case_residual(self._b, self._e, self._h, thrust_N, demand)

    # --- allocation --------------------------------------------------------------------

    def _inner(self, tau: float, cv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """T-step at fixed τ: the box QP of ``f(·, τ)``; returns ``(T, M, d)``."""
        d = 1.0 / (1.0 - tau * self._eig_s)
        m_mat = self._c_mat.T @ (d[:, None] * self._c_mat) + self._hth / tau + self._eps * self._eye
        c = self._c_mat.T @ (d * cv)
        t, self._state = box_qp(m_mat, c, self._lo_a, self._hi_a, self._state, self._definite)
        return t, m_mat, d

    def _nominal(self, v: np.ndarray) -> np.ndarray:
        """Bounded least squares with B₀ (no uncertainty acts), ε → 0 refined."""
        t, self._state = box_qp(
            self._nominal_m, self._b_a.T @ v, self._lo_a, self._hi_a, self._state, self._definite
        )
        return refine(self._b_a, v, t, self._lo_a, self._hi_a, self._attained_tol**2)

    def _robust(self, v: np.ndarray) -> np.ndarray:
        if not self._uncertain:
            return self._nominal(v)
        cv = self._eig_u.T @ v
        s, s_max = self._eig_s, self._s_max
        best: list[tuple[float, np.ndarray]] = []

        def evaluate(theta: float) -> tuple[float, float, bool]:
            # φ(τ) = min_T f(T, τ) is convex; ψ = φ'(τ) (Danskin), ψ' on T's active set.
            tau = theta / s_max
            t, m_mat, d = self._inner(tau, cv)
            z = self._c_mat @ t - cv
            hv = self._h_a @ t
            h2 = float(hv @ hv)
            obj = float(z @ (d * z)) + h2 / tau + self._eps * float(t @ t)
            if not best or obj < best[0][0]:
                best[:] = [(obj, t)]
            sd2 = s * d * d
            psi = float(z @ (sd2 * z)) - h2 / (tau * tau)
            f_tt = 2.0 * float(z @ (s * sd2 * d * z)) + 2.0 * h2 / tau**3
            idx = np.flatnonzero(self._state == FREE)
            curv = f_tt
            if idx.size:
                w = (
                    self._c_mat.T @ (sd2 * (self._c_mat @ t - cv)) - self._hth @ t / (tau * tau)
                )[idx]
                m_ff = m_mat[np.ix_(idx, idx)].tolist()
                sol = spd_solve(m_ff, list(range(idx.size)), w.tolist(), PD_PIVOT_RTOL, RANK_RTOL)
                curv -= 2.0 * float(w @ np.array(sol))
            # Newton decrement ψ²/ψ' estimates φ(τ) − min φ; ψ' in θ units below.
            done = curv > 0.0 and psi * psi / curv <= LFT_RTOL * obj + self._attained_tol**2
            return psi / s_max, curv / (s_max * s_max), done

        if not self._params.warm_start:
            self._theta_warm = math.nan
            self._state[:] = FREE
        theta0 = self._theta_warm if math.isfinite(self._theta_warm) else LFT_THETA_START
        self._theta_warm = monotone_root(
            evaluate, theta0, LFT_THETA_MIN, LFT_THETA_MAX, self._params.max_iter
        )
        return self._refined(best[0][1], self._theta_warm / s_max, cv)

    def _refined(self, t: np.ndarray, tau: float, cv: np.ndarray) -> np.ndarray:
        """The ε → 0 least-norm minimiser of ``f(·, τ)`` on the active set of ``t``, when it
        does not raise the unregularised ``f(·, τ)`` (step 3 of the module docstring)."""
        root_d = np.sqrt(1.0 / (1.0 - tau * self._eig_s))
        b_w = np.vstack((root_d[:, None] * self._c_mat, self._h_a / math.sqrt(tau)))
        d_w = np.concatenate((root_d * cv, np.zeros(self._h_a.shape[0])))
        return refine(b_w, d_w, t, self._lo_a, self._hi_a, self._attained_tol**2)

    def _solve(self, d: np.ndarray) -> tuple[np.ndarray, bool | None]:
        t_a = self._robust(d)
        return t_a, None if bound_active(t_a, self._lo_a, self._hi_a) else False
