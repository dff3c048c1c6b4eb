"""Reference forms of the allocators' active-set kernels, on numpy and LAPACK.

The package solves the box QP and the active-set refinement once, on floats
(:mod:`flight_sw.allocation.dense_active_set`, its Jacobi-SVD fallback included). These are
the same methods written with numpy arrays and LAPACK (``np.linalg.solve``, least-norm
``np.linalg.lstsq``), as the package had them before: the tests hold the package to them.

Methods: primal-dual active-set rounds (Hintermüller, Ito & Kunisch 2003, SIAM J. Optim.
13(3) 865–888), the primal active-set method (Nocedal & Wright 2006, alg. 16.3), the
least-norm least-squares refinement on an active set (Björck 1996, sec. 5.2).
"""

from __future__ import annotations

import numpy as np

from flight_sw.allocation.active_set import (
    ACTIVE_RTOL,
    AT_LOWER,
    AT_UPPER,
    BOX_GTOL,
    BOX_XTOL,
    FREE,
    MAX_PDAS_ITER,
    PRIMAL_ITER_PER_VAR,
)
from flight_sw.allocation.base import RANK_RTOL


def refine_lstsq(
    b_w: np.ndarray, d_w: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray | None:
    """:func:`~flight_sw.allocation.active_set.refine_on_active_set` with LAPACK's
    least-norm lstsq at every step."""
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


def free_solve(
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


def box_qp_numpy(
    m_mat: np.ndarray,
    c: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    state: np.ndarray,
    definite: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """The box QP of :func:`~flight_sw.allocation.active_set.box_qp` with numpy and LAPACK
    throughout (LU solve, least-norm lstsq on singular free sets)."""
    fixed = lo >= hi
    st = np.where(fixed, AT_LOWER, state).astype(np.int8)
    xtol = BOX_XTOL * (hi - lo)
    x = np.minimum(np.maximum(np.zeros_like(c), lo), hi)
    for _ in range(MAX_PDAS_ITER):
        free = st == FREE
        x_bound = np.where(st == AT_LOWER, lo, np.where(st == AT_UPPER, hi, 0.0))
        x = free_solve(m_mat, c, x_bound, free, definite)
        g = m_mat @ x - c
        new = np.full(st.shape, FREE, dtype=np.int8)
        new[(free & (x > hi + xtol)) | ((st == AT_UPPER) & (g <= 0.0))] = AT_UPPER
        new[(free & (x < lo - xtol)) | ((st == AT_LOWER) & (g >= 0.0)) | fixed] = AT_LOWER
        if np.array_equal(new, st):
            return np.minimum(np.maximum(x, lo), hi), st
        st = new
    return primal_active_set(m_mat, c, lo, hi, np.minimum(np.maximum(x, lo), hi), definite)


def primal_active_set(
    m_mat: np.ndarray,
    c: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    x: np.ndarray,
    definite: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Primal active-set method for the box QP from a feasible ``x`` (numpy/LAPACK)."""
    st = np.where(x <= lo, AT_LOWER, np.where(x >= hi, AT_UPPER, FREE)).astype(np.int8)
    for _ in range(PRIMAL_ITER_PER_VAR * x.size + 1):
        free = st == FREE
        step = free_solve(m_mat, c, x, free, definite) - x
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
