"""Bounded pseudo-inverse allocation for on-off thrusters (thrust in [0, T_max,i]).

What it does: maps a torque (m = 3) or wrench (m = 6) demand ``d`` to thrusts ``T`` with
``B T ≈ d`` and ``0 ≤ T_i ≤ T_max,i`` (each thruster its own maximum, e.g. seed 001's
opposing valves of 2.35 N and 2.3 N), in up to three cheap steps:

1. Minimum-norm solution ``T = B⁺ d`` (B⁺ the Moore–Penrose pseudo-inverse of the
   effectiveness matrix restricted to the available thrusters; computed once).
2. Non-negativity by null-space shifts that cost the least propellant: for each thruster
   ``i`` a non-negative null vector ``n_i`` with ``n_i[i] = 1`` and the smallest total
   thrust (``B n_i = 0``, so the achieved demand is unchanged) is found once at
   construction by the linear programme "minimise Σ v subject to B v = 0, v ≥ 0,
   v_i = 1" (HiGHS, :mod:`flight_sw.allocation.linear_program`; each thruster's cost is
   ``1 + 10⁻⁹ j``, so among rays of equal fuel the one on the lowest-numbered thrusters
   is taken, whatever the solver's pivoting); each negative ``T_i`` is lifted to zero by
   ``T ← T + (−T_i) n_i`` (the other components only grow, so one pass suffices). For
   the seed-003 layout ``n_i`` is the opposing thruster of ``i`` (a pure couple), so a
   pure pitch demand fires exactly one couple. A single strictly positive null vector
   ``v`` (found by "maximise t subject to B v = 0, Σ v = 1, v_i ≥ t") must exist: the
   thrusters must positively span the attainable space; it also serves step 3. Steps 1–2
   do not depend on the bounds.
3. Upper bounds: if some ``T_i > T_max,i``:
   a. if the demand is *attainable* — inside the attainable set
      ``A = {B T : 0 ≤ T_i ≤ T_max,i} = Σ_j [0, T_max,j] g_j`` (``g_j`` the columns of
      ``B``), a zonotope — and ``exact_repair`` is on, solve the bounded least-squares
      problem ``min ‖B T − d‖, 0 ≤ T ≤ T_max`` as the box QP ``M = BᵀB + εI``,
      ``c = Bᵀd`` of :func:`flight_sw.allocation.active_set.box_qp` (the exact active-set
      solver the QP allocators use), then solve the least-norm least squares on the active
      set it finds (ε → 0, :func:`flight_sw.allocation.active_set.refine`, as the QP
      allocators do): a zero residual, so an attainable demand is always reproduced
      exactly, by the least-norm thrusts of all that reproduce it (as ε → 0 the
      regularised minimiser tends to the least-norm point of the solution set: the
      Tikhonov limit). The ridge (:data:`LEAST_NORM_RIDGE_RTOL` × the mean diagonal of
      ``BᵀB``, :func:`~flight_sw.allocation.active_set.ridge`) makes ``M`` definite, so
      the primal-dual rounds settle on Cholesky solves. Without it (``M`` only
      semi-definite: rank m < n) they cycled in 295 of 310 repairs in a replay of a
      quickstart run's cycles on its true states (``benchmarks/fsw_cycle.py``'s hot
      replay; runs need far fewer repairs), the primal active-set method finished from
      wherever they stopped (~0.6 ms a call, against ~40 µs now) and the answer depended
      on that path: a minimiser, but not the least-norm one (up to 0.9 N larger in norm;
      tests/ compare with OSQP's least-norm answer). The attainability
      test is one small matrix-vector product against the facet inequalities
      ``n·x ≤ h(n)`` precomputed at construction: a facet normal ``n`` is orthogonal to r − 1
      independent generators (the bounds scale the generators, not their directions,
      so the normals are those of ``B``), with support ``h(n) = Σ_j T_max,j max(n·g_j, 0)``
      (Durham 1994 for equal bounds; the per-generator weight is each segment's length);
   b. otherwise scale the whole vector by ``s = min_{i: T_i > T_max,i} T_max,i / T_i``,
      the largest factor that brings every thruster within its own bound
      (direction-preserving saturation: the achieved demand keeps the direction of the
      attainable part of ``d``; with equal bounds ``s = T_max / max T``), reported as
      ``saturated``.
   Why 3a exists: the single fixed shift direction of step 2 does not reach every
   attainable demand. For the seed-003 layout the shifted pseudo-inverse needs up to
   1.5 T_max on attainable demands (e.g. thrusters 3, 4, 5, 6 and 8 all at T_max need
   1.25 T_max); about 0.6 % (torque) and 2 % (wrench) of demands ``B·U(0, T_max)⁸``
   overflow. Step 3a runs only for those (≈ 40 µs each); unattainable demands,
   the common saturated case during slews, take the cheap step 3b.
   With equal bounds every quantity above is computed exactly as the scalar form did
   (``h = T_max Σ_j max(n·g_j, 0)``, ``s = T_max / max T``), bit for bit: the bounds
   enter as ``T_max,ref × (T_max,j / T_max,ref)`` with ``T_max,ref = max_j T_max,j``, and
   the ratios are exactly 1.

Fallback: when no strictly positive null vector exists (fewer or badly placed available
thrusters, e.g. after masking), steps 1–3 do not apply and every call solves the bounded
least-squares problem as that box QP (≈ 40 µs per call): feasible demands are
reproduced, others get the bounded least-squares optimum (not direction-preserving).
:attr:`PseudoInverseAllocator.uses_null_space_shift` tells which path an instance uses.

Inputs: ``effectiveness`` (m×n, rows as in :mod:`flight_sw.allocation.effectiveness`:
torque rows [N m/N] or wrench rows); ``params.max_thrust_N`` [N], one number or one per
thruster (shape (n,)); availability ``mask`` (n booleans, True = usable; masked thrusters
get exactly 0 N, and their columns are removed before the pseudo-inverse, the null vector
and the attainable set are computed). Output:
:class:`~flight_sw.allocation.base.AllocationResult` (thrust [N], achieved demand,
residual, saturated). Every returned thrust lies in [0, T_max,i]. A non-finite demand
yields all zeros with an infinite residual, flagged saturated; with every thruster masked
the result is all zeros, flagged saturated unless the demand is zero (the base class).

Assumptions: mean thrust over a control period is what the modulators realise
downstream; thrusters are independent; the attainable-set test enumerates
C(n_available, rank − 1) generator subsets once per instance (28 for the 8-thruster torque
case, 70 for its wrench case; a few thousand at most for 16 thrusters).

Sources: pseudo-inverse allocation and its bounded variants: Bordignon 1996, "Constrained
Control Allocation for Systems with Redundant Control Effectors", PhD thesis, Virginia
Tech, ch. 4 (generalised inverses, redistribution); attainable moment set and
direction-preserving scaling: Durham 1993, "Constrained control allocation", JGCD 16(4)
717–725, and Durham 1994, "Attainable moments for the constrained control allocation
problem", JGCD 17(6) 1371–1373; null-space shift for unidirectional thrusters: Wie 2008,
"Space Vehicle Dynamics and Control", 2nd ed., ch. 7; seed 003 (``E⁺ = Eᵀ(EEᵀ)⁻¹`` with
an on-off relay); bounded least squares: Björck 1996, "Numerical Methods for Least
Squares Problems", sec. 5.2, solved as in :mod:`flight_sw.allocation.active_set`.
No scipy.optimize here: importing it cost the flight software's start-up ~0.3 s (issue 23);
tests/ check both problems against scipy's ``linprog`` and ``lsq_linear``.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from dbc import validation as check
from flight_sw.allocation.active_set import FREE, box_qp, refine, ridge
from flight_sw.allocation.authority import positive_null_vector
from flight_sw.allocation.base import RANK_RTOL, BoundSpec, ControlAllocation
from flight_sw.allocation.dense import mat_vec, norm
from flight_sw.allocation.linear_program import solve_lp

# The bounded least squares' ridge ε relative to the mean diagonal of BᵀB (step 3a, the
# fallback): large enough for Cholesky pivots far above PD_PIVOT_RTOL, small enough that
# its active set is the least-norm answer's; its own residual (up to ~1e-7, several times
# the attained tolerance) is removed by the refinement on that active set.
LEAST_NORM_RIDGE_RTOL = 1e-9
# Per thruster number, the extra cost that breaks ties between null rays of equal fuel.
RAY_ORDER_WEIGHT = 1e-9
# Thrust above T_max,i × (1 + THRUST_RTOL) counts as an overflow (round-off slack).
THRUST_RTOL = 1e-12

_SOURCE = "PseudoInverseParams"


@dataclass(frozen=True)
class PseudoInverseParams:
    """Parameters of the bounded pseudo-inverse allocator.

    Attributes:
        max_thrust_N: maximum (on-state) thrust [N] (> 0): one number for every thruster,
            or a tuple with one per thruster.
        exact_repair: solve the bounded least-squares problem when the shifted
            pseudo-inverse overflows on an attainable demand (step 3a); False gives the
            plain pseudo-inverse + shift + scaling behaviour.
    """

    max_thrust_N: BoundSpec
    exact_repair: bool = True

    def __post_init__(self) -> None:
        t = self.max_thrust_N
        if isinstance(t, tuple):
            check.vector(_SOURCE, "max_thrust_N", t, None, 0.0, lo_open=True, unit="N")
        else:
            check.positive(_SOURCE, "max_thrust_N", t, unit="N")
        check.flag(_SOURCE, "exact_repair", self.exact_repair)


def _min_fuel_null_rays(b: np.ndarray) -> np.ndarray | None:
    """Row i: the non-negative null vector with component i = 1 and least sum, or None."""
    m, n = b.shape
    rays = np.zeros((n, n))
    # Ties (layouts with several least-fuel couples, e.g. opposing valve pairs) go to the
    # lowest-numbered thrusters, whatever the solver's pivoting would pick: the cost of
    # thruster j is 1 + RAY_ORDER_WEIGHT × j (a vertex, so the values are the ray's own).
    cost = 1.0 + RAY_ORDER_WEIGHT * np.arange(n)
    for i in range(n):
        lo, hi = np.zeros(n), np.full(n, np.inf)
        lo[i] = hi[i] = 1.0
        x = solve_lp(cost, lo, hi, b, np.zeros(m))
        if x is None:
            return None
        rays[i] = np.maximum(x, 0.0)
        rays[i, i] = 1.0
    return rays


def _attainable_halfspaces(g: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Facet inequalities ``N x ≤ h`` of the zonotope ``Σ_j [0, w_j] g_j`` (G: r×n, rank r).

    Every facet normal is orthogonal to r − 1 independent generators; all such directions
    (both signs) are enumerated; extra non-facet directions only add redundant
    (still valid) supporting half-spaces. ``h = Σ_j w_j max(N g_j, 0)`` (``w``: the
    generators' lengths, the thrust bounds relative to the largest).
    """
    r, n = g.shape
    if r == 1:
        normals = np.array([[1.0], [-1.0]])
    else:
        combos = np.array(list(itertools.combinations(range(n), r - 1)), dtype=int)
        stacks = np.transpose(g[:, combos], (1, 0, 2))  # (K, r, r−1)
        u, s, _ = np.linalg.svd(stacks, full_matrices=True)
        independent = s[:, -1] > RANK_RTOL * s[:, 0]
        normals = u[independent, :, -1]
        normals = np.vstack([normals, -normals])
        normals = np.unique(np.round(normals, 12), axis=0)
    h = (np.maximum(normals @ g, 0.0) * weights).sum(axis=1)
    return normals, h


class PseudoInverseAllocator(ControlAllocation):
    """Bounded pseudo-inverse allocator with null-space shift (a ``ControlAllocation``)."""

    _source = "PseudoInverseAllocator"
    _stateless = True  # no warm start: every solve starts from the same state

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: PseudoInverseParams,
        mask: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        super().__init__(effectiveness, params, mask, 0.0, params.max_thrust_N)
        m = self._b.shape[0]
        b_a = self._b_a
        u_a = self._hi_a
        self._pinv = np.linalg.pinv(b_a, rcond=RANK_RTOL) if self._avail.size else np.zeros((0, m))
        self._pinv_rows: list[list[float]] = self._pinv.tolist()  # per-cycle: dense.mat_vec
        self._b_a_rows: list[list[float]] = b_a.tolist()
        self._b_a_T_rows: list[list[float]] = b_a.T.tolist()
        rank = self._range_T.shape[0]
        self._null_v = positive_null_vector(b_a, self._pinv) if rank else None
        self._rays = _min_fuel_null_rays(b_a) if self._null_v is not None else None
        # Per-call helpers: −1/v for the shift, the overflow thresholds, and the attainable-set
        # inequalities mapped to demand space, ``normals·U_rᵀ d ≤ h + tol``.
        self._neg_inv_v = None if self._null_v is None else -1.0 / self._null_v
        self._overflow_N = u_a * (1.0 + THRUST_RTOL)
        # the same as lists, for the per-cycle arithmetic on floats (_solve)
        self._ray_rows = None if self._rays is None else self._rays.tolist()
        self._neg_inv_v_list = [] if self._neg_inv_v is None else self._neg_inv_v.tolist()
        self._null_v_list = [] if self._null_v is None else self._null_v.tolist()
        self._overflow_list = self._overflow_N.tolist()
        # BᵀB + εI of the bounded least squares (array and lists, as the QP allocators keep
        # M): the ridge makes the answer the least-norm one and M definite (docstring, 3a)
        eps = ridge(b_a, LEAST_NORM_RIDGE_RTOL)
        self._m_mat = b_a.T @ b_a + eps * np.eye(b_a.shape[1])
        self._definite = eps > 0.0
        self._m_list = self._m_mat.tolist()
        self._free = np.full(u_a.size, FREE, dtype=np.int8)
        self._halfspaces: tuple[list[list[float]], list[float]] | None = None
        if self._null_v is not None and params.exact_repair and rank:
            u_ref = float(np.max(u_a))
            normals, h = _attainable_halfspaces(self._range_T @ b_a, u_a / u_ref)
            self._halfspaces = ((normals @ self._range_T).tolist(),
                                (u_ref * h + self._attained_tol).tolist())

    # --- introspection -----------------------------------------------------------------

    @property
    def uses_null_space_shift(self) -> bool:
        """True on the pseudo-inverse + null-space shift path, False on the BVLS fallback."""
        return self._null_v is not None

    @property
    def null_vector(self) -> np.ndarray | None:
        """The unit-sum positive null vector over all n thrusters (0 where masked), or None."""
        if self._null_v is None:
            return None
        v = np.zeros(self._b.shape[1])
        v[self._avail] = self._null_v
        return v

    # --- allocation --------------------------------------------------------------------

    def _attainable(self, d: np.ndarray) -> bool:
        if self._halfspaces is None:
            return False
        normals_d, h_tol = self._halfspaces
        return all(x <= h for x, h in zip(mat_vec(normals_d, d.tolist()), h_tol, strict=True))

    def _bounded_lsq(self, d: np.ndarray) -> np.ndarray:
        """``argmin ‖B T − d‖²`` over ``0 ≤ T ≤ T_max`` (least-norm where not unique: the
        ridge of ``M``)."""
        q = np.array(mat_vec(self._b_a_T_rows, d.tolist()))
        x, _ = box_qp(self._m_mat, q, self._lo_a, self._hi_a, self._free, self._definite,
                      self._m_list)
        # ε → 0 on the ridge's active set: the refinement makes the repair exact (the
        # ridge's answer alone misses an attainable demand by up to ~1e-7)
        return refine(self._b_a, d, x, self._lo_a, self._hi_a, self._attained_tol**2)

    def _in_range_residual(self, d: np.ndarray, t_a: np.ndarray) -> float:
        achieved = mat_vec(self._b_a_rows, t_a.tolist())
        r = [d_i - a_i for d_i, a_i in zip(d.tolist(), achieved, strict=True)]
        return norm(mat_vec(self._range_T_rows, r))

    def _solve(self, d: np.ndarray) -> tuple[np.ndarray, bool | None]:
        u_a = self._hi_a
        saturated = False
        neg_inv_v = self._neg_inv_v
        if neg_inv_v is None or self._null_v is None:
            t_a = self._bounded_lsq(d)
            saturated = self._in_range_residual(d, t_a) > self._attained_tol
        else:
            # on floats: elementwise, the same operations in the same order as on arrays
            t = mat_vec(self._pinv_rows, d.tolist())
            if self._ray_rows is not None:
                rays = self._ray_rows
                for i in [k for k, x in enumerate(t) if x < 0.0]:
                    ti = t[i]
                    if ti < 0.0:
                        t = [x - ti * r for x, r in zip(t, rays[i], strict=True)]
            else:
                alpha = max(x * w for x, w in zip(t, self._neg_inv_v_list, strict=True))
                if alpha > 0.0:
                    t = [x + alpha * v for x, v in zip(t, self._null_v_list, strict=True)]
            t_a = np.array(t)
            if any(x > o for x, o in zip(t, self._overflow_list, strict=True)):
                repaired = None
                if self._attainable(d):
                    candidate = self._bounded_lsq(d)
                    if self._in_range_residual(d, candidate) <= self._attained_tol:
                        repaired = candidate
                if repaired is None:
                    # min over the overflowing thrusters of T_max,i/T_i (the others give ≥ it)
                    t_a *= float((u_a / np.maximum(t_a, u_a)).min())
                    saturated = True
                else:
                    t_a = repaired
        np.maximum(t_a, 0.0, out=t_a)
        np.minimum(t_a, u_a, out=t_a)
        return t_a, saturated
