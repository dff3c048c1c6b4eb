"""Bounded pseudo-inverse allocation for on-off thrusters (thrust in [0, T_max]).

What it does: maps a torque (m = 3) or wrench (m = 6) demand ``d`` to thrusts ``T`` with
``B T ≈ d`` and ``0 ≤ T_i ≤ T_max``, in up to three cheap steps:

1. Minimum-norm solution ``T = B⁺ d`` (B⁺ the Moore–Penrose pseudo-inverse of the
   effectiveness matrix restricted to the available thrusters; computed once).
2. Non-negativity by null-space shifts that cost the least propellant: for each thruster
   ``i`` a non-negative null vector ``n_i`` with ``n_i[i] = 1`` and the smallest total
   thrust (``B n_i = 0``, so the achieved demand is unchanged) is found once at construction
   by the linear programme "minimise Σ v subject to B v = 0, v ≥ 0, v_i = 1" (scipy
   ``linprog``); each negative ``T_i`` is lifted to zero by ``T ← T + (−T_i) n_i`` (the
   other components only grow, so one pass suffices). For the seed-003 layout ``n_i`` is the
   opposing thruster of ``i`` (a pure couple), so a pure pitch demand fires exactly one
   couple. A single strictly positive null vector ``v`` (found by "maximise t subject to
   B v = 0, Σ v = 1, v_i ≥ t") must exist: the thrusters must positively span the
   attainable space; it also serves step 3.
3. Upper bound: if ``max T > T_max``:
   a. if the demand is *attainable* (inside the attainable set ``B·[0, T_max]ⁿ``, a
      zonotope whose facet inequalities are precomputed, so the test is one small
      matrix-vector product) and ``exact_repair`` is on, solve the bounded least-squares
      problem ``min ‖B T − d‖, 0 ≤ T ≤ T_max`` (scipy ``lsq_linear``, BVLS), which then has
      a zero residual: an attainable demand is always reproduced exactly;
   b. otherwise scale the whole vector by ``T_max / max T`` (direction-preserving
      saturation: the achieved demand keeps the direction of the attainable part of
      ``d``), reported as ``saturated``.
   Why 3a exists: the single fixed shift direction of step 2 does not reach every
   attainable demand. For the seed-003 layout the shifted pseudo-inverse needs up to
   1.5 T_max on attainable demands (e.g. thrusters 3, 4, 5, 6 and 8 all at T_max need
   1.25 T_max); about 0.6 % (torque) and 2 % (wrench) of demands ``B·U(0, T_max)⁸``
   overflow. Step 3a runs only for those (≈ 60–120 µs each); unattainable demands,
   the common saturated case during slews, take the cheap step 3b.

Fallback: when no strictly positive null vector exists (fewer or badly placed available
thrusters, e.g. after masking), steps 1–3 do not apply and every call solves the bounded
least-squares problem with ``lsq_linear`` (BVLS; ≈ 60–120 µs per call): feasible demands are
reproduced, others get the bounded least-squares optimum (not direction-preserving).
:attr:`PseudoInverseAllocator.uses_null_space_shift` tells which path an instance uses.

Inputs: ``effectiveness`` (m×n, rows as in :mod:`flight_sw.allocation.effectiveness`:
torque rows [N m/N] or wrench rows); ``params.max_thrust_N`` [N]; availability ``mask``
(n booleans, True = usable; masked thrusters get exactly 0 N, and their columns are
removed before the pseudo-inverse, the null vector and the attainable set are computed).
Output: :class:`AllocationResult` (thrust [N], achieved demand, residual, saturated).
Every returned thrust lies in [0, T_max]. A non-finite demand yields all zeros with an
infinite residual, flagged saturated; with every thruster masked the result is all zeros,
flagged saturated unless the demand is zero.

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
an on-off relay); BVLS: Stark & Parker 1995, "Bounded-variable least-squares: an
algorithm and applications", Comput. Stat. 10(2) 129–141.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog, lsq_linear

from dbc.errors import ConfigError
from flight_sw import validation as check
from flight_sw.allocation.base import AllocationResult

MAX_DEMAND_DIM = 6
# Singular values below RANK_RTOL × the largest count as zero (rank of B).
RANK_RTOL = 1e-10
# Smallest component (of a unit-sum null vector) accepted as "strictly positive".
NULL_VECTOR_MIN_COMPONENT = 1e-9
# Thrust above T_max × (1 + THRUST_RTOL) counts as an overflow (round-off slack).
THRUST_RTOL = 1e-12
# A residual below ATTAINED_RTOL × (T_max × largest column norm of B) counts as zero.
ATTAINED_RTOL = 1e-9

_SOURCE = "PseudoInverseAllocator"


@dataclass(frozen=True)
class PseudoInverseParams:
    """Parameters of the bounded pseudo-inverse allocator.

    Attributes:
        max_thrust_N: maximum (on-state) thrust of every thruster [N] (> 0).
        exact_repair: solve the bounded least-squares problem when the shifted
            pseudo-inverse overflows on an attainable demand (step 3a); False gives the
            plain pseudo-inverse + shift + scaling behaviour.
    """

    max_thrust_N: float
    exact_repair: bool = True

    def __post_init__(self) -> None:
        check.positive("PseudoInverseParams", "max_thrust_N", self.max_thrust_N, unit="N")
        check.flag("PseudoInverseParams", "exact_repair", self.exact_repair)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def _positive_null_vector(b: np.ndarray, pinv: np.ndarray) -> np.ndarray | None:
    """A unit-sum v > 0 with B v = 0 maximising min v, or None if there is none."""
    m, n = b.shape
    cost = np.zeros(n + 1)
    cost[-1] = -1.0  # maximise t
    a_eq = np.zeros((m + 1, n + 1))
    a_eq[:m, :n] = b
    a_eq[m, :n] = 1.0
    b_eq = np.zeros(m + 1)
    b_eq[m] = 1.0
    a_ub = np.hstack([-np.eye(n), np.ones((n, 1))])  # t − v_i ≤ 0
    bounds = [(0.0, None)] * n + [(None, None)]
    res = linprog(cost, A_ub=a_ub, b_ub=np.zeros(n), A_eq=a_eq, b_eq=b_eq, bounds=bounds)
    if res.status != 0 or res.x is None:
        return None
    v = np.asarray(res.x[:n], dtype=float)
    v = v - pinv @ (b @ v)  # remove the LP's round-off component outside the null space
    v = v / v.sum()
    if v.min() <= NULL_VECTOR_MIN_COMPONENT:
        return None
    return v


def _min_fuel_null_rays(b: np.ndarray) -> np.ndarray | None:
    """Row i: the non-negative null vector with component i = 1 and least sum, or None."""
    m, n = b.shape
    rays = np.zeros((n, n))
    for i in range(n):
        bounds: list[tuple[float, float | None]] = [(0.0, None)] * n
        bounds[i] = (1.0, 1.0)
        res = linprog(np.ones(n), A_eq=b, b_eq=np.zeros(m), bounds=bounds)
        if res.status != 0 or res.x is None:
            return None
        rays[i] = np.maximum(np.asarray(res.x, dtype=float), 0.0)
        rays[i, i] = 1.0
    return rays


def _attainable_halfspaces(g: np.ndarray, max_thrust_N: float) -> tuple[np.ndarray, np.ndarray]:
    """Facet inequalities ``N x ≤ h`` of the zonotope ``G·[0, T_max]ⁿ`` (G: r×n, rank r).

    Every facet normal is orthogonal to r − 1 independent generators; all such directions
    (both signs) are enumerated; extra non-facet directions only add redundant
    (still valid) supporting half-spaces.
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
    h = max_thrust_N * np.maximum(normals @ g, 0.0).sum(axis=1)
    return normals, h


class PseudoInverseAllocator:
    """Bounded pseudo-inverse allocator with null-space shift (implements ``Allocator``)."""

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: PseudoInverseParams,
        mask: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        b = np.array(effectiveness, dtype=float)
        if b.ndim != 2 or not (1 <= b.shape[0] <= MAX_DEMAND_DIM) or b.shape[1] == 0:
            raise ConfigError(_SOURCE, "effectiveness", b.shape, "an m×n array, 1 <= m <= 6")
        if not np.all(np.isfinite(b)):
            raise ConfigError(_SOURCE, "effectiveness", "non-finite", "finite values")
        m, n = b.shape
        if mask is None:
            mask_arr = np.ones(n, dtype=bool)
        else:
            raw = np.asarray(mask)
            if raw.shape != (n,) or raw.dtype != bool:
                raise ConfigError(_SOURCE, "mask", mask, f"{n} booleans (True = usable)")
            mask_arr = raw.copy()
        self._b = b
        self._b.setflags(write=False)
        self._params = params
        self._mask = _frozen(mask_arr)
        self._avail = np.flatnonzero(mask_arr)
        self._tmax = float(params.max_thrust_N)
        b_a = b[:, self._avail]
        self._b_a = b_a
        self._pinv = np.linalg.pinv(b_a, rcond=RANK_RTOL) if self._avail.size else np.zeros((0, m))
        if self._avail.size:
            u, s, _ = np.linalg.svd(b_a, full_matrices=False)
            rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0
        else:
            u, rank = np.zeros((m, 0)), 0
        self._range_basis_T = u[:, :rank].T.copy()  # rows: orthonormal basis of range(B_a)
        col_norm = float(np.max(np.linalg.norm(b_a, axis=0))) if self._avail.size else 0.0
        self._attained_tol = ATTAINED_RTOL * max(self._tmax * col_norm, 1.0)
        self._null_v = _positive_null_vector(b_a, self._pinv) if rank else None
        self._rays = _min_fuel_null_rays(b_a) if self._null_v is not None else None
        # Per-call helpers: −1/v for the shift, the overflow threshold, and the attainable-set
        # inequalities mapped to demand space, ``normals·U_rᵀ d ≤ h + tol``.
        self._neg_inv_v = None if self._null_v is None else -1.0 / self._null_v
        self._overflow_N = self._tmax * (1.0 + THRUST_RTOL)
        self._all_available = bool(mask_arr.all())
        self._halfspaces: tuple[np.ndarray, np.ndarray] | None = None
        if self._null_v is not None and params.exact_repair and rank:
            normals, h = _attainable_halfspaces(self._range_basis_T @ b_a, self._tmax)
            self._halfspaces = (normals @ self._range_basis_T, h + self._attained_tol)

    # --- introspection -----------------------------------------------------------------

    @property
    def params(self) -> PseudoInverseParams:
        """The parameters this allocator was built with."""
        return self._params

    @property
    def mask(self) -> np.ndarray:
        """The availability mask (read-only; True = usable)."""
        return self._mask

    @property
    def effectiveness(self) -> np.ndarray:
        """The full m×n effectiveness matrix (read-only, masked columns included)."""
        return self._b

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

    def with_mask(self, mask: Sequence[bool] | np.ndarray) -> PseudoInverseAllocator:
        """A new allocator for the same thrusters with availability ``mask``."""
        return PseudoInverseAllocator(self._b, self._params, mask)

    # --- allocation --------------------------------------------------------------------

    def _attainable(self, d: np.ndarray) -> bool:
        if self._halfspaces is None:
            return False
        normals_d, h_tol = self._halfspaces
        return bool((normals_d @ d <= h_tol).all())

    def _bounded_lsq(self, d: np.ndarray) -> np.ndarray:
        res = lsq_linear(self._b_a, d, bounds=(0.0, self._tmax), method="bvls")
        return np.asarray(res.x, dtype=float)

    def _in_range_residual(self, d: np.ndarray, t_a: np.ndarray) -> float:
        return float(np.linalg.norm(self._range_basis_T @ (d - self._b_a @ t_a)))

    def allocate(self, demand: np.ndarray) -> AllocationResult:
        """Thrusts [N] for the torque/wrench ``demand`` (see the module docstring)."""
        d = np.asarray(demand, dtype=float)
        m, n = self._b.shape
        if d.shape != (m,):
            raise ValueError(f"demand has shape {d.shape}, expected ({m},)")
        finite = all(map(math.isfinite, d.tolist()))
        if not finite or self._avail.size == 0:
            residual = float(np.linalg.norm(d)) if finite else math.inf
            return AllocationResult(
                _frozen(np.zeros(n)), _frozen(np.zeros(m)), residual, residual > 0.0
            )
        tmax = self._tmax
        saturated = False
        neg_inv_v = self._neg_inv_v
        if neg_inv_v is None or self._null_v is None:
            t_a = self._bounded_lsq(d)
            saturated = self._in_range_residual(d, t_a) > self._attained_tol
        else:
            t_a = self._pinv @ d
            if self._rays is not None:
                rays = self._rays
                for i in np.flatnonzero(t_a < 0.0).tolist():
                    ti = t_a[i]
                    if ti < 0.0:
                        t_a -= ti * rays[i]
            else:
                alpha = float((t_a * neg_inv_v).max())
                if alpha > 0.0:
                    t_a += alpha * self._null_v
            peak = float(t_a.max())
            if peak > self._overflow_N:
                repaired = None
                if self._attainable(d):
                    candidate = self._bounded_lsq(d)
                    if self._in_range_residual(d, candidate) <= self._attained_tol:
                        repaired = candidate
                if repaired is None:
                    t_a *= tmax / peak
                    saturated = True
                else:
                    t_a = repaired
        np.maximum(t_a, 0.0, out=t_a)
        np.minimum(t_a, tmax, out=t_a)
        if self._all_available:
            thrust = t_a
        else:
            thrust = np.zeros(n)
            thrust[self._avail] = t_a
        achieved = self._b @ thrust
        r = d - achieved
        return AllocationResult(
            _frozen(thrust), _frozen(achieved), math.sqrt(float(r @ r)), saturated
        )
