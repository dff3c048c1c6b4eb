"""Small dense linear programmes of the allocators' design time, on HiGHS (highspy).

What it does: :func:`solve_lp` solves ``min cᵀx`` subject to ``A_eq x = b_eq``,
``A_ub x ≤ b_ub`` and ``lo ≤ x ≤ hi`` (``±inf`` for a free side) with the HiGHS dual
simplex (Huangfu & Hall 2018, "Parallelizing the dual revised simplex method", Math.
Prog. Comp. 10, 119–142), the solver scipy's ``linprog`` runs by default, called through
its own Python binding: importing it takes ~20 ms where ``scipy.optimize`` takes ~0.3 s,
which the flight software's start-up would otherwise pay (issue 23). tests/ check it
against ``scipy.optimize.linprog``.

Used at construction only (never in the cycle): the pseudo-inverse allocator's null
vectors (:mod:`flight_sw.allocation.pseudo_inverse`). Sizes: a few tens of variables.

HiGHS writes a banner to the process's standard output (C level) when a solver object is
made, before any option can turn it off (ERGO-Code/HiGHS issue 2749): the object is made
with file descriptor 1 pointed at ``os.devnull`` for that moment, so the flight
software's log and ``--check`` stay clean.
"""

from __future__ import annotations

import os
import sys

import highspy
import numpy as np

_INF = float(highspy.kHighsInf)


def _quiet_solver() -> highspy.Highs:
    """A HiGHS object with its output off, made without its banner on standard output."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            h = highspy.Highs()
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    h.setOptionValue("output_flag", False)
    return h


def _finite_or_inf(x: np.ndarray) -> np.ndarray:
    """``x`` with ``±inf`` as HiGHS's infinity."""
    return np.clip(np.asarray(x, dtype=float), -_INF, _INF)


def solve_lp(
    cost: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    a_eq: np.ndarray | None = None,
    b_eq: np.ndarray | None = None,
    a_ub: np.ndarray | None = None,
    b_ub: np.ndarray | None = None,
) -> np.ndarray | None:
    """An optimal ``x`` of ``min costᵀx`` s.t. ``a_eq x = b_eq``, ``a_ub x ≤ b_ub``,
    ``lo ≤ x ≤ hi``; None when the programme is infeasible or unbounded."""
    n = len(cost)
    rows, row_lo, row_hi = [], [], []
    if a_eq is not None and b_eq is not None:
        rows.append(np.asarray(a_eq, dtype=float).reshape(-1, n))
        row_lo.append(np.asarray(b_eq, dtype=float))
        row_hi.append(np.asarray(b_eq, dtype=float))
    if a_ub is not None and b_ub is not None:
        rows.append(np.asarray(a_ub, dtype=float).reshape(-1, n))
        row_lo.append(np.full(len(b_ub), -_INF))
        row_hi.append(np.asarray(b_ub, dtype=float))
    a = np.vstack(rows) if rows else np.zeros((0, n))
    lp = highspy.HighsLp()
    lp.num_col_ = n
    lp.num_row_ = a.shape[0]
    lp.col_cost_ = np.asarray(cost, dtype=float)
    lp.col_lower_ = _finite_or_inf(lo)
    lp.col_upper_ = _finite_or_inf(hi)
    lp.row_lower_ = _finite_or_inf(np.concatenate(row_lo)) if rows else np.zeros(0)
    lp.row_upper_ = _finite_or_inf(np.concatenate(row_hi)) if rows else np.zeros(0)
    cols = [np.flatnonzero(a[:, j]) for j in range(n)]
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int32)
    lp.a_matrix_.index_ = np.concatenate(cols).astype(np.int32) if n else np.zeros(0, np.int32)
    lp.a_matrix_.value_ = np.concatenate([a[c, j] for j, c in enumerate(cols)]) if n \
        else np.zeros(0)
    h = _quiet_solver()
    h.passModel(lp)
    h.run()
    if h.getModelStatus() != highspy.HighsModelStatus.kOptimal:
        return None
    return np.array(h.getSolution().col_value, dtype=float)
