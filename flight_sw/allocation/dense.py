"""Small dense kernels of the bounded allocators, on Python floats (compiled with mypyc).

What it does: the two exact steps that follow OSQP's active-set guess in the bounded
allocators (:mod:`flight_sw.allocation.qp_osqp`, and the robust ones that share them),
written out for the problem sizes of a thruster set (n ≤ 16 thrusters, m ≤ 6 demand rows),
where numpy's per-call overhead (~1-10 µs a call, dozens of calls per solve) is most of the
time and the arithmetic itself is a few thousand flops:

- :func:`box_qp_pdas`: primal-dual active-set rounds for ``min ½ xᵀMx − cᵀx``,
  ``lo ≤ x ≤ hi``, with ``M`` symmetric positive definite (Hintermüller, Ito & Kunisch 2003,
  SIAM J. Optim. 13(3) 865–888): each round solves ``M_FF x_F = c_F − M_FA x_A`` on the
  free set by Cholesky, then moves variables to or from their bounds by the sign of the
  gradient ``g = Mx − c``; it ends when the active set repeats (the KKT conditions hold).
- :func:`refine_active_set`: the least-norm least-squares solution ``T_F = B_F⁺ (d − B_A T_A)``
  on an active set, growing the set when a free value leaves its box (at most n + 1
  steps); ``B_F⁺`` by the normal equations of the smaller Gram matrix (``B_Fᵀ B_F`` if at
  most m are free, else ``B_F B_Fᵀ``), by Cholesky.

In and out: plain lists (matrices as lists of rows), float64 arithmetic. Each returns None
where its fast form cannot answer with full accuracy: a Cholesky pivot at or below
:data:`PD_PIVOT_RTOL` (box QP) or :data:`LSQ_PIVOT_RTOL` (least squares) times its diagonal
entry, i.e. a singular or ill-conditioned free set; the callers then use their numpy forms
(LAPACK ``lstsq``, least-norm on singular sets), which define the result in those cases.
Active-set states: -1 at the lower bound, 0 free, 1 at the upper bound (as
:mod:`~flight_sw.allocation.qp_osqp`).

Assumptions: ``lo ≤ hi`` elementwise (``lo == hi`` is a fixed variable, held at ``lo``),
finite inputs.
"""

from __future__ import annotations

import math

AT_LOWER, FREE, AT_UPPER = -1, 0, 1
# A Cholesky pivot of the ε-regularised box-QP matrix below this × its diagonal entry means
# the matrix is not numerically positive definite (the regularisation keeps it ~1e-6).
PD_PIVOT_RTOL = 1e-12
# A Cholesky pivot of a least-squares Gram matrix below this × its diagonal entry (a column
# within ~1e-4 rad of the others' span: condition number above ~1e4) leaves it to lstsq.
LSQ_PIVOT_RTOL = 1e-8

Matrix = list[list[float]]


def cholesky_solve(a: Matrix, idx: list[int], b: list[float], pivot_rtol: float
                   ) -> list[float] | None:
    """``x`` with ``A[idx, idx] x = b`` (``b`` in the order of ``idx``) by Cholesky; None if
    a pivot is at or below ``pivot_rtol`` × its diagonal entry (or not a number)."""
    n = len(idx)
    low: Matrix = [[0.0] * n for _ in range(n)]
    for i in range(n):
        a_i = a[idx[i]]
        l_i = low[i]
        for j in range(i + 1):
            l_j = low[j]
            s = a_i[idx[j]]
            for k in range(j):
                s -= l_i[k] * l_j[k]
            if i == j:
                if not s > pivot_rtol * a_i[idx[i]]:
                    return None
                l_i[i] = math.sqrt(s)
            else:
                l_i[j] = s / l_j[j]
    y = [0.0] * n
    for i in range(n):
        s = b[i]
        l_i = low[i]
        for k in range(i):
            s -= l_i[k] * y[k]
        y[i] = s / l_i[i]
    x = [0.0] * n
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s -= low[k][i] * x[k]
        x[i] = s / low[i][i]
    return x


def box_qp_pdas(m: Matrix, c: list[float], lo: list[float], hi: list[float],
                state: list[int], max_rounds: int, xtol_rel: float
                ) -> tuple[list[float], list[int], bool] | None:
    """Primal-dual active-set rounds of the box QP (module docstring) from ``state``.

    Returns ``(x, state, settled)``: ``x`` clipped to the box; ``settled`` False when the
    set did not repeat within ``max_rounds`` (``x`` is then the last round's, a start for a
    primal active-set method). None when a free-set matrix is not positive definite.
    ``xtol_rel``: a free value must leave its box by more than this × (hi − lo) to be put
    on the bound.
    """
    n = len(c)
    st = [AT_LOWER if lo[i] >= hi[i] else state[i] for i in range(n)]
    x = [min(max(0.0, lo[i]), hi[i]) for i in range(n)]
    for _ in range(max_rounds):
        free: list[int] = []
        for i in range(n):
            s_i = st[i]
            if s_i == FREE:
                free.append(i)
                x[i] = 0.0
            else:
                x[i] = lo[i] if s_i == AT_LOWER else hi[i]
        if free:
            rhs: list[float] = []
            for i in free:
                row = m[i]
                s = c[i]
                for j in range(n):
                    if st[j] != FREE:
                        s -= row[j] * x[j]
                rhs.append(s)
            sol = cholesky_solve(m, free, rhs, PD_PIVOT_RTOL)
            if sol is None:
                return None
            for k in range(len(free)):
                x[free[k]] = sol[k]
        new = [FREE] * n
        for i in range(n):
            if lo[i] >= hi[i]:
                new[i] = AT_LOWER
                continue
            s_i = st[i]
            if s_i == FREE:
                xtol = xtol_rel * (hi[i] - lo[i])
                if x[i] < lo[i] - xtol:
                    new[i] = AT_LOWER
                elif x[i] > hi[i] + xtol:
                    new[i] = AT_UPPER
                continue
            row = m[i]
            g = -c[i]
            for j in range(n):
                g += row[j] * x[j]
            if s_i == AT_UPPER and g <= 0.0:
                new[i] = AT_UPPER
            elif s_i == AT_LOWER and g >= 0.0:
                new[i] = AT_LOWER
        if new == st:
            return [min(max(x[i], lo[i]), hi[i]) for i in range(n)], st, True
        st = new
    return x, st, False


def least_norm(b: Matrix, free: list[int], r: list[float]) -> list[float] | None:
    """The least-norm least-squares ``x`` of ``B[:, free] x ≈ r`` by the normal equations of
    the smaller Gram matrix; None when that matrix is ill-conditioned (LSQ_PIVOT_RTOL)."""
    rows = len(b)
    f = len(free)
    if f <= rows:  # (B_Fᵀ B_F) x = B_Fᵀ r
        gram = [[0.0] * f for _ in range(f)]
        rhs = [0.0] * f
        for i in range(f):
            ci = free[i]
            s = 0.0
            for k in range(rows):
                s += b[k][ci] * r[k]
            rhs[i] = s
            for j in range(i + 1):
                cj = free[j]
                s = 0.0
                for k in range(rows):
                    s += b[k][ci] * b[k][cj]
                gram[i][j] = s
                gram[j][i] = s
        return cholesky_solve(gram, list(range(f)), rhs, LSQ_PIVOT_RTOL)
    gram = [[0.0] * rows for _ in range(rows)]  # (B_F B_Fᵀ) y = r, x = B_Fᵀ y
    for i in range(rows):
        b_i = b[i]
        for j in range(i + 1):
            b_j = b[j]
            s = 0.0
            for cf in free:
                s += b_i[cf] * b_j[cf]
            gram[i][j] = s
            gram[j][i] = s
    y = cholesky_solve(gram, list(range(rows)), r, LSQ_PIVOT_RTOL)
    if y is None:
        return None
    x = [0.0] * f
    for i in range(f):
        cf = free[i]
        s = 0.0
        for k in range(rows):
            s += b[k][cf] * y[k]
        x[i] = s
    return x


def refine_active_set(b: Matrix, d: list[float], t: list[float], lo: list[float],
                      hi: list[float], active_rtol: float) -> tuple[bool, list[float] | None]:
    """The least-norm least-squares thrusts on the active set of ``t`` (module docstring).

    A value within ``active_rtol`` × (hi − lo) of a bound is held there. Returns
    ``(True, x)``, or ``(True, None)`` when the free values keep leaving the box, or
    ``(False, None)`` when a least-squares step was ill-conditioned (the caller decides
    with lstsq).
    """
    n = len(t)
    rows = len(b)
    tol = [active_rtol * (hi[i] - lo[i]) for i in range(n)]
    state = [FREE] * n
    for i in range(n):
        if t[i] <= lo[i] + tol[i]:
            state[i] = AT_LOWER
        elif t[i] >= hi[i] - tol[i]:
            state[i] = AT_UPPER
    for _ in range(n + 1):
        out = [lo[i] if state[i] == AT_LOWER else hi[i] if state[i] == AT_UPPER else 0.0
               for i in range(n)]
        free = [i for i in range(n) if state[i] == FREE]
        if not free:
            return True, out
        r = [0.0] * rows
        for k in range(rows):
            b_k = b[k]
            s = d[k]
            for j in range(n):
                s -= b_k[j] * out[j]
            r[k] = s
        sol = least_norm(b, free, r)
        if sol is None:
            return False, None
        moved = False
        for k in range(len(free)):
            i = free[k]
            if sol[k] < lo[i] - tol[i]:
                state[i] = AT_LOWER
                moved = True
            elif sol[k] > hi[i] + tol[i]:
                state[i] = AT_UPPER
                moved = True
        if not moved:
            for k in range(len(free)):
                i = free[k]
                out[i] = min(max(sol[k], lo[i]), hi[i])
            return True, out
    return True, None
