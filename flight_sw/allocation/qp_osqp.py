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

The module also hosts the dense solvers the robust allocators share: :func:`box_qp` and
the safeguarded Newton root finder :func:`monotone_root`.

Sources: seed 000 (dual-quaternion 6-DoF control), sec. IV, eqs. 27–32 (pseudo-inverse,
null-space shift, least-shift programme); OSQP: Stellato et al. 2020, "OSQP: an operator
splitting solver for quadratic programs", Math. Prog. Comp. 12, 637–672; least-norm
solution of the free set: Björck 1996, "Numerical Methods for Least Squares Problems",
sec. 5.2 (active-set methods for bounded least squares); Hintermüller, Ito & Kunisch 2003,
SIAM J. Optim. 13(3) 865–888 (primal-dual active set); Nocedal & Wright 2006, alg. 16.3.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import osqp
import scipy.sparse as sp

from dbc.errors import ConfigError
from flight_sw import validation as check
from flight_sw.allocation import dense
from flight_sw.allocation.base import AllocationResult
from flight_sw.allocation.dense import AT_LOWER, AT_UPPER, FREE  # active-set states of box_qp
from flight_sw.allocation.osqp_lean import LeanOsqp

MAX_DEMAND_DIM = 6
# Singular values below RANK_RTOL × the largest count as zero (rank, least-norm solutions).
RANK_RTOL = 1e-10
# A residual below ATTAINED_RTOL × max(1, bound range × largest column norm) counts as zero.
ATTAINED_RTOL = 1e-9
# A thrust within ACTIVE_RTOL × (hi − lo) of a bound is taken as sitting on it.
ACTIVE_RTOL = 1e-6
# Relative slack on the weighted residual when accepting the refined solution.
REFINE_RTOL = 1e-9
DEFAULT_REGULARIZATION = 1e-6
# OSQP settings: tight tolerances, bounded iterations, iteration-counted rho adaptation,
# no time limit (OSQP 1.x has no "off" value; 1e10 s is its default, i.e. never reached).
OSQP_EPS_ABS = 1e-9
OSQP_EPS_REL = 1e-9
OSQP_MAX_ITER = 4000
OSQP_CHECK_TERMINATION = 10
OSQP_ADAPTIVE_RHO_ITERATIONS = 1  # OSQP 1.x: adapt rho every `interval` iterations
OSQP_ADAPTIVE_RHO_INTERVAL = 25
OSQP_TIME_LIMIT_OFF_S = 1e10
# BoundedQpAllocator only needs OSQP's active set (box_qp then solves exactly): loose
# tolerances, no polishing, and a low iteration bound keep its worst case short.
OSQP_STAGE_ONE_EPS = 1e-4
OSQP_STAGE_ONE_MAX_ITER = 60

_SOURCE = "BoundedQpParams"

BoundSpec = float | tuple[float, ...]


def osqp_settings(warm_start: bool, stage_one: bool = False) -> dict[str, Any]:
    """OSQP settings (silent, deterministic); ``stage_one``: the loose active-set guess."""
    return {
        "verbose": False,
        "polishing": not stage_one,
        "warm_starting": warm_start,
        "eps_abs": OSQP_STAGE_ONE_EPS if stage_one else OSQP_EPS_ABS,
        "eps_rel": OSQP_STAGE_ONE_EPS if stage_one else OSQP_EPS_REL,
        "max_iter": OSQP_STAGE_ONE_MAX_ITER if stage_one else OSQP_MAX_ITER,
        "check_termination": OSQP_CHECK_TERMINATION,
        "adaptive_rho": OSQP_ADAPTIVE_RHO_ITERATIONS,
        "adaptive_rho_interval": OSQP_ADAPTIVE_RHO_INTERVAL,
        "time_limit": OSQP_TIME_LIMIT_OFF_S,
    }


def check_bound_spec(source: str, key: str, value: object) -> None:
    """Raise ConfigError unless ``value`` is a finite number or a non-empty tuple of them."""
    if isinstance(value, tuple):
        check.vector(source, key, value, None)
    else:
        check.number(source, key, value)


def thrust_bounds(
    source: str, lower_N: BoundSpec, upper_N: BoundSpec, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per-thruster bound arrays (n,) from scalar or per-thruster specs; checks lo ≤ hi."""
    out = []
    for key, spec in (("lower_N", lower_N), ("upper_N", upper_N)):
        arr = np.array(spec, dtype=float).reshape(-1)
        if arr.size == 1:
            arr = np.full(n, float(arr[0]))
        if arr.shape != (n,):
            raise ConfigError(source, key, spec, f"a number or {n} numbers")
        out.append(arr)
    lo, hi = out
    bad = np.flatnonzero(lo > hi)
    if bad.size:
        i = int(bad[0])
        raise ConfigError(source, f"lower_N[{i}]", float(lo[i]), f"<= upper_N[{i}]")
    return lo, hi


def check_effectiveness(source: str, effectiveness: np.ndarray) -> np.ndarray:
    """A float copy of the m×n effectiveness matrix (1 <= m <= 6, finite), read-only."""
    b = np.array(effectiveness, dtype=float)
    if b.ndim != 2 or not (1 <= b.shape[0] <= MAX_DEMAND_DIM) or b.shape[1] == 0:
        raise ConfigError(source, "effectiveness", b.shape, "an m×n array, 1 <= m <= 6")
    if not np.all(np.isfinite(b)):
        raise ConfigError(source, "effectiveness", "non-finite", "finite values")
    b.setflags(write=False)
    return b


def parse_mask(source: str, mask: Sequence[bool] | np.ndarray | None, n: int) -> np.ndarray:
    """The availability mask as a read-only bool array (n,); None means all usable."""
    if mask is None:
        arr = np.ones(n, dtype=bool)
    else:
        raw = np.asarray(mask)
        if raw.shape != (n,) or raw.dtype != bool:
            raise ConfigError(source, "mask", mask, f"{n} booleans (True = usable)")
        arr = raw.copy()
    arr.setflags(write=False)
    return arr


def frozen(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only."""
    a.setflags(write=False)
    return a


def range_basis_T(b_a: np.ndarray) -> np.ndarray:
    """Rows: an orthonormal basis of range(b_a) (rank × m; 0 × m if b_a has no rank)."""
    m = b_a.shape[0]
    if b_a.size == 0:
        return np.zeros((0, m))
    u, s, _ = np.linalg.svd(b_a, full_matrices=False)
    rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0
    return u[:, :rank].T.copy()


def attained_tolerance(b_a: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Residual [demand units] below which a demand counts as reproduced."""
    col = float(np.max(np.linalg.norm(b_a, axis=0))) if b_a.size else 0.0
    span = float(np.max(np.maximum(np.abs(lo), np.abs(hi)))) if lo.size else 0.0
    return ATTAINED_RTOL * max(1.0, col * span)


def trivial_result(d: np.ndarray, n: int) -> AllocationResult:
    """All-zero thrust for a non-finite demand (infinite residual) or no usable thruster."""
    finite = bool(np.all(np.isfinite(d)))
    residual = float(np.linalg.norm(d)) if finite else math.inf
    m = d.shape[0]
    return AllocationResult(frozen(np.zeros(n)), frozen(np.zeros(m)), residual, residual > 0.0)


def check_demand(d: object, m: int) -> np.ndarray:
    """The demand as a float array of shape (m,); ValueError otherwise."""
    arr = np.asarray(d, dtype=float)
    if arr.shape != (m,):
        raise ValueError(f"demand has shape {arr.shape}, expected ({m},)")
    return arr


def refine_on_active_set(
    b_w: np.ndarray,
    d_w: np.ndarray,
    t: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
) -> np.ndarray | None:
    """The ε → 0 least-squares solution on the active set of ``t``, or None if it leaves the box.

    ``b_w = W^½ B_a`` and ``d_w = W^½ d``; bounds within ACTIVE_RTOL·(hi − lo) of ``t`` are
    held, the free thrusters get ``(b_w,F)⁺ (d_w − b_w,A t_A)``; free ones that leave the box
    are then held at the violated bound and the step repeated (at most n times). Solved by
    :func:`flight_sw.allocation.dense.refine_active_set` (normal equations, Cholesky) when
    every step is well conditioned, here with LAPACK's lstsq otherwise.
    """
    done, fast = dense.refine_active_set(b_w.tolist(), d_w.tolist(), t.tolist(), lo.tolist(),
                                         hi.tolist(), ACTIVE_RTOL)
    if done:  # the Cholesky form answered (flight_sw/allocation/dense.py)
        return None if fast is None else np.array(fast)
    return refine_lstsq(b_w, d_w, t, lo, hi)


def refine_lstsq(
    b_w: np.ndarray, d_w: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray | None:
    """:func:`refine_on_active_set` with LAPACK's least-norm lstsq at every step."""
    tol = ACTIVE_RTOL * (hi - lo)
    at_lo = t <= lo + tol
    at_hi = (t >= hi - tol) & ~at_lo
    for _ in range(t.size + 1):
        free = ~(at_lo | at_hi)
        out = np.where(at_lo, lo, np.where(at_hi, hi, 0.0))
        if not free.any():
            return out
        sol, *_ = np.linalg.lstsq(b_w[:, free], d_w - b_w @ out, rcond=RANK_RTOL)
        lo_f, hi_f, tol_f = lo[free], hi[free], tol[free]
        below, above = sol < lo_f - tol_f, sol > hi_f + tol_f
        if not (below.any() or above.any()):
            out[free] = np.minimum(np.maximum(sol, lo_f), hi_f)
            return out
        # Hold the violated bounds too and solve again (an active-set step).
        idx = np.flatnonzero(free)
        at_lo[idx[below]] = True
        at_hi[idx[above]] = True
    return None


# --- dense solvers shared by the robust allocators ---------------------------------------
# Primal-dual active-set rounds of box_qp before its primal active-set fallback.
MAX_PDAS_ITER = 12
# Bound on the primal active-set iterations of the fallback, per variable.
PRIMAL_ITER_PER_VAR = 8
# A free variable must leave its box by more than this × (hi − lo) to be put on the bound.
BOX_XTOL = 1e-12
# Multiplier signs within this × (|c| + |M||x|) of zero count as correct (round-off).
BOX_GTOL = 1e-13
# Root finder: give up after this many evaluations or when the bracket shrinks below
# ROOT_XTOL × its initial width (no time limit: deterministic).
MAX_ROOT_ITER = 60
ROOT_XTOL = 1e-15
# A Newton step longer than this fraction of the previous step is replaced by bisection.
NEWTON_SHRINK = 0.5
# Bisect geometrically when the bracket spans more than this ratio (root near 0).
GEOMETRIC_BISECTION_RATIO = 4.0



def _free_solve(
    m_mat: np.ndarray, c: np.ndarray, x_fixed: np.ndarray, free: np.ndarray, definite: bool
) -> np.ndarray:
    """``x`` with the non-free entries of ``x_fixed`` and ``M_FF x_F = c_F − M_FA x_A``."""
    x = x_fixed.copy()
    idx = np.flatnonzero(free)
    if idx.size == 0:
        return x
    rhs = c[idx] - m_mat[idx] @ np.where(free, 0.0, x_fixed)
    m_ff = m_mat[np.ix_(idx, idx)]
    sol: np.ndarray | None = None
    if definite:
        try:
            sol = np.linalg.solve(m_ff, rhs)
        except np.linalg.LinAlgError:
            sol = None
    if sol is None or not np.all(np.isfinite(sol)):
        sol = np.linalg.lstsq(m_ff, rhs, rcond=RANK_RTOL)[0]  # least-norm (singular M_FF)
    x[idx] = sol
    return x


def box_qp(
    m_mat: np.ndarray,
    c: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    state: np.ndarray,
    definite: bool,
    m_list: list[list[float]] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``argmin_{lo ≤ x ≤ hi} ½ xᵀMx − cᵀx`` (dense, exact up to round-off) and its active set.

    ``M`` symmetric positive semi-definite (``definite``: positive definite, e.g. a ridge
    term; otherwise the least-norm solution on the free set is taken). ``state`` is the
    initial guess of the active set (:data:`AT_LOWER`, :data:`FREE`, :data:`AT_UPPER` per
    variable; pass the previous answer's to warm-start). Method: primal-dual active-set
    rounds (Hintermüller, Ito & Kunisch 2003, SIAM J. Optim. 13(3) 865–888), which end when
    the set repeats (then the KKT conditions hold); should they not settle within
    :data:`MAX_PDAS_ITER` rounds, the primal active-set method (Nocedal & Wright 2006,
    alg. 16.3), finite for a convex QP, finishes from the clipped iterate. The rounds run in
    :func:`flight_sw.allocation.dense.box_qp_pdas` (Cholesky on Python floats) when ``M`` is
    definite, here on numpy otherwise or when a free-set matrix is singular; ``m_list``:
    ``M`` as nested lists, when the caller keeps it (``M.tolist()`` otherwise).
    """
    if definite:  # the Cholesky form (flight_sw/allocation/dense.py) unless M_FF is singular
        fast = dense.box_qp_pdas(m_mat.tolist() if m_list is None else m_list, c.tolist(),
                                 lo.tolist(), hi.tolist(), state.tolist(), MAX_PDAS_ITER,
                                 BOX_XTOL)
        if fast is not None:
            x_f, st_f, settled = fast
            x = np.array(x_f)
            if settled:
                return x, np.array(st_f, dtype=np.int8)
            return _primal_active_set(m_mat, c, lo, hi, np.minimum(np.maximum(x, lo), hi),
                                      definite)
    return box_qp_numpy(m_mat, c, lo, hi, state, definite)


def box_qp_numpy(
    m_mat: np.ndarray,
    c: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    state: np.ndarray,
    definite: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`box_qp` with numpy and LAPACK throughout (least-norm on singular free sets)."""
    fixed = lo >= hi
    st = np.where(fixed, AT_LOWER, state).astype(np.int8)
    xtol = BOX_XTOL * (hi - lo)
    x = np.minimum(np.maximum(np.zeros_like(c), lo), hi)
    for _ in range(MAX_PDAS_ITER):
        free = st == FREE
        x_bound = np.where(st == AT_LOWER, lo, np.where(st == AT_UPPER, hi, 0.0))
        x = _free_solve(m_mat, c, x_bound, free, definite)
        g = m_mat @ x - c
        new = np.full(st.shape, FREE, dtype=np.int8)
        new[(free & (x > hi + xtol)) | ((st == AT_UPPER) & (g <= 0.0))] = AT_UPPER
        new[(free & (x < lo - xtol)) | ((st == AT_LOWER) & (g >= 0.0)) | fixed] = AT_LOWER
        if np.array_equal(new, st):
            return np.minimum(np.maximum(x, lo), hi), st
        st = new
    return _primal_active_set(m_mat, c, lo, hi, np.minimum(np.maximum(x, lo), hi), definite)


def _primal_active_set(
    m_mat: np.ndarray,
    c: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    x: np.ndarray,
    definite: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Primal active-set method for the box QP of :func:`box_qp` from a feasible ``x``."""
    st = np.where(x <= lo, AT_LOWER, np.where(x >= hi, AT_UPPER, FREE)).astype(np.int8)
    for _ in range(PRIMAL_ITER_PER_VAR * x.size + 1):
        free = st == FREE
        step = _free_solve(m_mat, c, x, free, definite) - x
        with np.errstate(divide="ignore", invalid="ignore"):
            to_hi = np.where(step > 0.0, (hi - x) / step, 1.0)
            ratio = np.where(step < 0.0, (lo - x) / step, to_hi)
        ratio = np.where(free, ratio, 1.0)
        alpha = float(min(1.0, float(np.min(ratio))))
        x = np.minimum(np.maximum(x + alpha * step, lo), hi)
        if alpha < 1.0:
            block = free & (ratio <= alpha)
            st[block & (step < 0.0)] = AT_LOWER
            st[block & (step > 0.0)] = AT_UPPER
            continue
        g = m_mat @ x - c
        gtol = BOX_GTOL * (float(np.max(np.abs(c))) + float(np.max(np.abs(m_mat @ x))) + 1.0)
        wrong = np.where(st == AT_LOWER, -g, np.where(st == AT_UPPER, g, 0.0))
        wrong = np.where(lo >= hi, 0.0, wrong)
        worst = int(np.argmax(wrong))
        if wrong[worst] <= gtol:
            break
        st[worst] = FREE
    return x, st


def monotone_root(
    evaluate: Callable[[float], tuple[float, float, bool]],
    x0: float,
    a: float,
    b: float,
    max_iter: int = MAX_ROOT_ITER,
) -> float:
    """The last point evaluated by a safeguarded Newton search for ``ψ(x) = 0`` on ``[a, b]``.

    ``evaluate(x)`` returns ``(ψ(x), ψ'(x), done)`` for an increasing ``ψ`` (``ψ'`` may be
    0 or non-finite when unknown); ``done`` ends the search (the caller's own certificate).
    Newton steps that leave the current sign-change bracket are replaced by bisection
    (geometric when the bracket spans more than :data:`GEOMETRIC_BISECTION_RATIO`). It
    also stops when ψ keeps its sign at an end of ``[a, b]`` (the root lies at or beyond
    that end), or after ``max_iter`` evaluations or when the bracket is narrower
    than :data:`ROOT_XTOL` × ``(b − a)``. Deterministic (no time limit).
    """
    lo, hi, lo_seen, hi_seen = a, b, False, False
    x = min(max(x0, a), b)
    width = b - a
    last_step = math.inf
    for _ in range(max_iter):
        psi, dpsi, done = evaluate(x)
        if done or psi == 0.0:
            return x
        if psi < 0.0:
            lo, lo_seen = x, True
            if x >= b:
                return x
        else:
            hi, hi_seen = x, True
            if x <= a:
                return x
        if hi - lo <= ROOT_XTOL * width:
            return x
        cand = x - psi / dpsi if math.isfinite(dpsi) and dpsi > 0.0 else math.nan
        slow = abs(cand - x) > NEWTON_SHRINK * last_step  # not converging: bisect (rtsafe)
        if not lo < cand < hi or slow:
            if cand >= hi and not hi_seen:
                cand = hi
            elif cand <= lo and not lo_seen:
                cand = lo
            elif lo > 0.0 and hi > GEOMETRIC_BISECTION_RATIO * lo:
                cand = math.sqrt(lo * hi)
            else:
                cand = 0.5 * (lo + hi)
        last_step = abs(cand - x)
        x = cand
    return x


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


class BoundedQpAllocator:
    """Bounded weighted least-squares allocator on OSQP (implements ``Allocator``)."""

    def __init__(
        self,
        effectiveness: np.ndarray,
        params: BoundedQpParams,
        mask: Sequence[bool] | np.ndarray | None = None,
    ) -> None:
        src = "BoundedQpAllocator"
        b = check_effectiveness(src, effectiveness)
        m, n = b.shape
        lo, hi = thrust_bounds(src, params.lower_N, params.upper_N, n)
        if params.demand_weights is None:
            w = np.ones(m)
        else:
            w = np.array(params.demand_weights, dtype=float)
            if w.shape != (m,):
                raise ConfigError(src, "demand_weights", params.demand_weights, f"{m} numbers")
        self._b = b
        self._params = params
        self._mask = parse_mask(src, mask, n)
        self._avail = np.flatnonzero(self._mask)
        self._all_available = bool(self._mask.all())
        self._lo = frozen(lo)
        self._hi = frozen(hi)
        self._lo_a = lo[self._avail]
        self._hi_a = hi[self._avail]
        b_a = b[:, self._avail]
        self._b_a = b_a
        self._sqrt_w = np.sqrt(w)
        self._b_w = self._sqrt_w[:, None] * b_a
        self._range_T = range_basis_T(b_a)
        self._attained_tol = attained_tolerance(b_a, self._lo_a, self._hi_a)
        k = self._avail.size
        self._osqp: Any = None
        if k:
            gram_diag = np.sum(self._b_w * self._b_w, axis=0)
            eps = params.regularization * float(np.mean(gram_diag))
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

    # --- introspection -----------------------------------------------------------------

    @property
    def params(self) -> BoundedQpParams:
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
    def bounds_N(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-thruster (lower, upper) thrust bounds [N] (read-only; masked ones still listed)."""
        return self._lo, self._hi

    def with_mask(self, mask: Sequence[bool] | np.ndarray) -> BoundedQpAllocator:
        """A new allocator for the same thrusters with availability ``mask``."""
        return BoundedQpAllocator(self._b, self._params, mask)

    # --- allocation --------------------------------------------------------------------

    def _solve(self, d: np.ndarray) -> np.ndarray:
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
        refined = refine_on_active_set(self._b_w, d_w, t_qp, self._lo_a, self._hi_a)
        if refined is not None:
            r_ref = self._b_w @ refined - d_w
            r_qp = self._b_w @ t_qp - d_w
            limit = float(r_qp @ r_qp) * (1.0 + REFINE_RTOL) + self._attained_tol**2
            if float(r_ref @ r_ref) <= limit:
                return refined
        return t_qp

    def allocate(self, demand: np.ndarray) -> AllocationResult:
        """Thrusts [N] for the torque/wrench ``demand`` (see the module docstring)."""
        m, n = self._b.shape
        d = check_demand(demand, m)
        if self._avail.size == 0 or not np.all(np.isfinite(d)):
            return trivial_result(d, n)
        t_a = self._solve(d)
        if self._all_available:
            thrust = t_a
        else:
            thrust = np.zeros(n)
            thrust[self._avail] = t_a
        achieved = self._b @ thrust
        r = d - achieved
        in_range = self._range_T @ r
        saturated = math.sqrt(float(in_range @ in_range)) > self._attained_tol
        return AllocationResult(
            frozen(thrust), frozen(achieved), math.sqrt(float(r @ r)), saturated
        )
