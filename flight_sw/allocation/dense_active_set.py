"""Active-set kernels of the bounded allocators on Python floats (compiled with mypyc).

What it does: the exact steps that follow OSQP's active-set guess in the bounded
allocators (:mod:`flight_sw.allocation.qp_osqp` and the robust ones, through
:mod:`flight_sw.allocation.active_set`), for thruster-set sizes (n ≤ 16, m ≤ 6), with the
linear solves of :mod:`flight_sw.allocation.dense`:

- :func:`box_qp`: ``argmin_{lo ≤ x ≤ hi} ½ xᵀMx − cᵀx`` for a symmetric positive
  semi-definite ``M``, warm-started from a guess of the active set:
  primal-dual active-set rounds (:func:`box_qp_pdas`; Hintermüller, Ito & Kunisch 2003,
  SIAM J. Optim. 13(3) 865–888): each round solves ``M_FF x_F = c_F − M_FA x_A`` on the
  free set, then moves variables to or from their bounds by the sign of the gradient
  ``g = Mx − c``; they end when the set repeats (then the KKT conditions hold). Should
  they not settle within ``max_rounds``, the primal active-set method
  (:func:`primal_active_set`; Nocedal & Wright 2006, alg. 16.3), finite for a convex QP,
  finishes from the clipped iterate.
- :func:`refine_active_set`: the least-norm least-squares solution
  ``T_F = B_F⁺ (d − B_A T_A)`` on an active set, growing the set when a free value leaves
  its box (at most n + 1 steps).

Free-set solves: Cholesky when ``M`` is definite (the allocators' ridge ε keeps it so) and
the pivots pass :data:`~flight_sw.allocation.dense.PD_PIVOT_RTOL`; otherwise — ``M`` only
semi-definite (ε = 0) or a singular free set — the least-norm solution by the Jacobi SVD
with ``rcond`` (:func:`~flight_sw.allocation.dense.least_norm_svd`). The least-squares
steps of the refinement likewise fall back from the normal equations to the SVD of
``B_F``. So every case is answered here; there is no second (numpy/LAPACK) form.

In and out: plain lists (matrices as lists of rows), float64. Active-set states: -1 at
the lower bound, 0 free, 1 at the upper bound.

Assumptions: ``lo ≤ hi`` elementwise (``lo == hi`` is a fixed variable, held at ``lo``),
finite inputs.
"""

from __future__ import annotations

from flight_sw.allocation.dense import (
    PD_PIVOT_RTOL,
    Matrix,
    least_norm,
    least_norm_svd,
    spd_solve,
)

AT_LOWER, FREE, AT_UPPER = -1, 0, 1


def _free_solve(m: Matrix, c: list[float], x: list[float], free: list[int], definite: bool,
                rcond: float) -> list[float]:
    """``x`` with its free entries replaced by the solution of ``M_FF x_F = c_F − M_FA x_A``
    (Cholesky if ``definite``, least-norm otherwise or on a singular free set)."""
    out = list(x)
    if not free:
        return out
    n = len(c)
    is_free = [False] * n
    for i in free:
        is_free[i] = True
    rhs: list[float] = []
    for i in free:
        row = m[i]
        s = c[i]
        for j in range(n):
            if not is_free[j]:
                s -= row[j] * x[j]
        rhs.append(s)
    if definite:
        sol = spd_solve(m, free, rhs, PD_PIVOT_RTOL, rcond)
    else:
        sol = least_norm_svd([[m[i][j] for j in free] for i in free], rhs, rcond)
    for k in range(len(free)):
        out[free[k]] = sol[k]
    return out


def box_qp_pdas(m: Matrix, c: list[float], lo: list[float], hi: list[float],
                state: list[int], max_rounds: int, xtol_rel: float, definite: bool,
                rcond: float) -> tuple[list[float], list[int], bool]:
    """Primal-dual active-set rounds of the box QP (module docstring) from ``state``.

    Returns ``(x, state, settled)``: ``x`` clipped to the box; ``settled`` False when the
    set did not repeat within ``max_rounds`` (``x`` is then the last round's, a start for
    :func:`primal_active_set`). ``xtol_rel``: a free value must leave its box by more than
    this × (hi − lo) to be put on the bound.
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
        if free:  # M_FF x_F = c_F − M_FA x_A (written out: the per-cycle hot path)
            rhs: list[float] = []
            for i in free:
                row = m[i]
                s = c[i]
                for j in range(n):
                    if st[j] != FREE:
                        s -= row[j] * x[j]
                rhs.append(s)
            if definite:
                sol = spd_solve(m, free, rhs, PD_PIVOT_RTOL, rcond)
            else:
                sol = least_norm_svd([[m[i][j] for j in free] for i in free], rhs, rcond)
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


def primal_active_set(m: Matrix, c: list[float], lo: list[float], hi: list[float],
                      x0: list[float], definite: bool, rcond: float, gtol_rel: float,
                      iter_per_var: int) -> tuple[list[float], list[int]]:
    """Primal active-set method for the box QP from the feasible ``x0`` (module docstring).

    Each iteration solves the equality-constrained problem on the free set and steps
    towards it, stopping at the first bound met (which joins the active set); at a full
    step the bound with the most wrongly signed multiplier is freed, until every
    multiplier has the right sign within ``gtol_rel`` × (|c| + |Mx| + 1). At most
    ``iter_per_var`` × n + 1 iterations.
    """
    n = len(c)
    x = list(x0)
    st = [AT_LOWER if x[i] <= lo[i] else AT_UPPER if x[i] >= hi[i] else FREE
          for i in range(n)]
    for _ in range(iter_per_var * n + 1):
        free = [i for i in range(n) if st[i] == FREE]
        target = _free_solve(m, c, x, free, definite, rcond)
        step = [target[i] - x[i] for i in range(n)]
        alpha = 1.0
        ratio = [1.0] * n
        for i in free:
            if step[i] > 0.0:
                ratio[i] = (hi[i] - x[i]) / step[i]
            elif step[i] < 0.0:
                ratio[i] = (lo[i] - x[i]) / step[i]
            alpha = min(alpha, ratio[i])
        x = [min(max(x[i] + alpha * step[i], lo[i]), hi[i]) for i in range(n)]
        if alpha < 1.0:
            for i in free:
                if ratio[i] <= alpha:
                    if step[i] < 0.0:
                        st[i] = AT_LOWER
                    elif step[i] > 0.0:
                        st[i] = AT_UPPER
            continue
        c_max = 0.0
        mx_max = 0.0
        g = [0.0] * n
        for i in range(n):
            row = m[i]
            s = 0.0
            for j in range(n):
                s += row[j] * x[j]
            g[i] = s - c[i]
            c_max = max(c_max, abs(c[i]))
            mx_max = max(mx_max, abs(s))
        gtol = gtol_rel * (c_max + mx_max + 1.0)
        worst = 0
        worst_val = -1.0
        for i in range(n):
            wrong = 0.0
            if lo[i] < hi[i]:
                if st[i] == AT_LOWER:
                    wrong = -g[i]
                elif st[i] == AT_UPPER:
                    wrong = g[i]
            if i == 0 or wrong > worst_val:
                worst, worst_val = i, wrong
        if worst_val <= gtol:
            break
        st[worst] = FREE
    return x, st


def box_qp(m: Matrix, c: list[float], lo: list[float], hi: list[float], state: list[int],
           definite: bool, max_rounds: int, xtol_rel: float, gtol_rel: float,
           iter_per_var: int, rcond: float) -> tuple[list[float], list[int]]:
    """``argmin_{lo ≤ x ≤ hi} ½ xᵀMx − cᵀx`` and its active set (module docstring)."""
    x, st, settled = box_qp_pdas(m, c, lo, hi, state, max_rounds, xtol_rel, definite, rcond)
    if settled:
        return x, st
    n = len(c)
    clipped = [min(max(x[i], lo[i]), hi[i]) for i in range(n)]
    return primal_active_set(m, c, lo, hi, clipped, definite, rcond, gtol_rel, iter_per_var)


def refine_active_set(b: Matrix, d: list[float], t: list[float], lo: list[float],
                      hi: list[float], active_rtol: float, rcond: float
                      ) -> list[float] | None:
    """The least-norm least-squares thrusts on the active set of ``t`` (module docstring).

    A value within ``active_rtol`` × (hi − lo) of a bound is held there. Returns the
    thrusts, or None when the free values keep leaving the box.
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
            return out
        r = [0.0] * rows
        for k in range(rows):
            b_k = b[k]
            s = d[k]
            for j in range(n):
                s -= b_k[j] * out[j]
            r[k] = s
        sol = least_norm(b, free, r, rcond)
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
            return out
    return None
