"""The exact stages of the bounded allocators: a dense box QP and the active-set refinement.

What it does (numpy arrays in and out; the arithmetic runs on floats in
:mod:`flight_sw.allocation.dense`, compiled):

- :func:`box_qp`: ``argmin_{lo ≤ x ≤ hi} ½ xᵀMx − cᵀx`` for a symmetric positive
  (semi-)definite ``M`` and its active set, warm-started from a guess of the active set
  (OSQP's, or the previous call's);
- :func:`refine_on_active_set`: the ε → 0 least-norm least-squares thrusts on the
  active set of a box-QP solution (:data:`ACTIVE_RTOL`), and :func:`refine`, which keeps
  them when they do not increase the residual (:data:`REFINE_RTOL`).

The bounded QP allocator (:mod:`flight_sw.allocation.qp_osqp`) and the robust ones
(:mod:`~flight_sw.allocation.robust_polytopic`, :mod:`~flight_sw.allocation.robust_lft`)
share them.

Units: thrusts [N], demands in demand units; ``M`` and ``c`` in the caller's units.
Assumptions: ``lo ≤ hi`` elementwise (``lo == hi`` holds a variable fixed), finite inputs.

Sources: Hintermüller, Ito & Kunisch 2003, "The primal-dual active set strategy as a
semismooth Newton method", SIAM J. Optim. 13(3) 865–888; Nocedal & Wright 2006,
"Numerical Optimization", 2nd ed., alg. 16.3 (primal active set); Björck 1996,
"Numerical Methods for Least Squares Problems", sec. 5.2 (active-set methods for bounded
least squares).
"""

from __future__ import annotations

import numpy as np

from flight_sw.allocation import dense
from flight_sw.allocation.base import RANK_RTOL
from flight_sw.allocation.dense import AT_LOWER, AT_UPPER, FREE  # active-set states

# A thrust within ACTIVE_RTOL × (hi − lo) of a bound is taken as sitting on it.
ACTIVE_RTOL = 1e-6
# Relative slack on the residual when accepting the refined solution.
REFINE_RTOL = 1e-9
# Primal-dual active-set rounds of box_qp before its primal active-set fallback.
MAX_PDAS_ITER = 12
# Bound on the primal active-set iterations of the fallback, per variable.
PRIMAL_ITER_PER_VAR = 8
# A free variable must leave its box by more than this × (hi − lo) to be put on the bound.
BOX_XTOL = 1e-12
# Multiplier signs within this × (|c| + |M||x|) of zero count as correct (round-off).
BOX_GTOL = 1e-13

__all__ = ["AT_LOWER", "AT_UPPER", "FREE"]


def bound_active(t: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether a thrust of ``t`` sits on a bound (within :data:`ACTIVE_RTOL` × (hi − lo))."""
    tol = ACTIVE_RTOL * (hi - lo)
    return bool(np.any((t <= lo + tol) | (t >= hi - tol)))


def refine(b: np.ndarray, d: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray,
           floor: float) -> np.ndarray:
    """The refined thrusts of :func:`refine_on_active_set` if they exist and their squared
    residual ``‖B T − d‖²`` is at most ``(1 + REFINE_RTOL)`` × that of ``t`` plus ``floor``;
    else ``t``."""
    refined = refine_on_active_set(b, d, t, lo, hi)
    if refined is None:
        return t
    r_ref, r_t = b @ refined - d, b @ t - d
    if float(r_ref @ r_ref) <= float(r_t @ r_t) * (1.0 + REFINE_RTOL) + floor:
        return refined
    return t


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
