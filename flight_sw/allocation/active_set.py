"""The exact stages of the bounded allocators: a dense box QP and the active-set refinement.

What it does (numpy arrays in and out; the arithmetic runs on floats in
:mod:`flight_sw.allocation.dense_active_set`, compiled, its one implementation):

- :func:`box_qp`: ``argmin_{lo ≤ x ≤ hi} ½ xᵀMx − cᵀx`` for a symmetric positive
  (semi-)definite ``M`` and its active set, warm-started from a guess of the active set
  (OSQP's, or the previous call's);
- :func:`refine_on_active_set`: the ε → 0 least-norm least-squares thrusts on the
  active set of a box-QP solution (:data:`ACTIVE_RTOL`), and :func:`refine`, which keeps
  them when they do not increase the residual (:data:`REFINE_RTOL`);
- :func:`ridge`: the ridge ε that makes ``M = BᵀB + εI`` definite, a fraction of the mean
  diagonal of ``BᵀB`` (the mean squared column norm of ``B``).

The bounded QP allocator (:mod:`flight_sw.allocation.qp_osqp`), the robust ones
(:mod:`~flight_sw.allocation.robust_polytopic`, :mod:`~flight_sw.allocation.robust_lft`)
and the pseudo-inverse's repair (:mod:`flight_sw.allocation.pseudo_inverse`) share them.

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

from flight_sw.allocation import dense_active_set as kernel
from flight_sw.allocation.base import RANK_RTOL
from flight_sw.allocation.dense import mat_vec, sq_norm
from flight_sw.allocation.dense_active_set import AT_LOWER, AT_UPPER, FREE  # active-set states

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


def ridge(b: np.ndarray, rtol: float) -> float:
    """``rtol`` × the mean squared column norm of ``b`` (the mean diagonal of ``bᵀb``);
    0 for a matrix without columns."""
    if b.size == 0:
        return 0.0
    return rtol * float(np.mean(np.sum(b * b, axis=0)))


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
    rows, d_l = b.tolist(), d.tolist()
    r_ref = sq_norm([a - x for a, x in zip(mat_vec(rows, refined.tolist()), d_l, strict=True)])
    r_t = sq_norm([a - x for a, x in zip(mat_vec(rows, t.tolist()), d_l, strict=True)])
    if r_ref <= r_t * (1.0 + REFINE_RTOL) + floor:
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
    held, the free thrusters get ``(b_w,F)⁺ (d_w − b_w,A t_A)`` (least-norm; singular
    values below RANK_RTOL × the largest count as zero); free ones that leave the box are
    then held at the violated bound and the step repeated (at most n times).
    """
    out = kernel.refine_active_set(b_w.tolist(), d_w.tolist(), t.tolist(), lo.tolist(),
                                   hi.tolist(), ACTIVE_RTOL, RANK_RTOL)
    return None if out is None else np.array(out)


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
    variable; pass the previous answer's to warm-start): at most :data:`MAX_PDAS_ITER`
    primal-dual active-set rounds, then the primal active-set method
    (:func:`flight_sw.allocation.dense_active_set.box_qp`); ``m_list``: ``M`` as nested
    lists, when the caller keeps it (``M.tolist()`` otherwise).
    """
    x, st = kernel.box_qp(m_mat.tolist() if m_list is None else m_list, c.tolist(),
                          lo.tolist(), hi.tolist(), state.tolist(), definite, MAX_PDAS_ITER,
                          BOX_XTOL, BOX_GTOL, PRIMAL_ITER_PER_VAR, RANK_RTOL)
    return np.array(x), np.array(st, dtype=np.int8)
