"""Small dense linear algebra on Python floats (compiled with mypyc): the package's one solver.

What it does: the linear solves of the flight software's per-cycle kernels, written out
for their sizes (n ≤ 16 unknowns, m ≤ 6 rows), where numpy's per-call overhead (~1-10 µs
a call, dozens of calls per cycle) is most of the time and the arithmetic is a few
thousand flops. Users: the allocators' exact active-set stages
(:mod:`flight_sw.allocation.dense_active_set`) and the RLS inertia identifier's kernel
(:mod:`flight_sw.estimation.rls_kernel`).

- :func:`cholesky_solve`: ``A[idx, idx] x = b`` for a symmetric positive-definite ``A``;
  None when a pivot is at or below a relative threshold (the matrix is singular or too
  ill-conditioned for this form: the caller then takes :func:`least_norm_svd`).
- :func:`least_norm_svd`: the least-norm least-squares solution ``x = A⁺ b`` of any
  r×c matrix (singular, rank-deficient or ill-conditioned), by the one-sided Jacobi SVD
  (Hestenes): plane rotations of the columns of ``A`` (or of ``Aᵀ`` when ``A`` has more
  columns than rows) until every pair is orthogonal to :data:`JACOBI_RTOL`; then
  ``A V = W`` with orthogonal columns ``w_k = σ_k u_k`` and
  ``x = Σ_k v_k (w_k·b)/σ_k²`` over the ``σ_k > rcond · max σ`` (the others count as zero,
  as LAPACK's ``lstsq`` with the same ``rcond``). One-sided Jacobi computes the singular
  values to high relative accuracy (Demmel & Veselić 1992), so the rank decision is
  sharp; at most :data:`MAX_JACOBI_SWEEPS` sweeps (it converges quadratically, typically
  in 5-8).
- :func:`least_norm`: the least-norm least-squares solution of ``B[:, free] x ≈ r``: by
  the normal equations of the smaller Gram matrix (``B_Fᵀ B_F`` if at most m are free,
  else ``B_F B_Fᵀ``) and Cholesky when well conditioned (pivots above
  :data:`LSQ_PIVOT_RTOL` × their diagonal entry), else by :func:`least_norm_svd` on
  ``B_F`` itself (no squared condition number).
- :func:`spd_solve`: ``A[idx, idx] x = b`` by Cholesky, or by :func:`least_norm_svd` with
  ``rcond`` when a pivot fails (a singular free set: the least-norm solution).
- :func:`mat_vec`, :func:`sq_norm` and :func:`norm`: ``A x``, ``‖x‖²`` and ``‖x‖`` with every sum
  in index order, for
  the flight software's per-cycle products: numpy's ``@`` and ``np.linalg.norm`` go
  through the BLAS kernel OpenBLAS picks for the CPU (their sums, and so the last bits,
  differ between CPUs), and these make a run's arithmetic the same on every machine.

In and out: plain lists (matrices as lists of rows), float64 arithmetic.

Assumptions: finite inputs (a non-finite input gives a non-finite answer, never an
exception). Sources: Golub & Van Loan 2013, "Matrix Computations", 4th ed., sec. 4.2
(Cholesky), 5.3 (normal equations), 8.6.3 (one-sided Jacobi SVD); Hestenes 1958, "Inversion
of matrices by biorthogonalization", J. SIAM 6(1) 51–90; Demmel & Veselić 1992, "Jacobi's
method is more accurate than QR", SIAM J. Matrix Anal. Appl. 13(4) 1204–1245.
"""

from __future__ import annotations

import math

# A Cholesky pivot of the ε-regularised box-QP matrix below this × its diagonal entry means
# the matrix is not numerically positive definite (the regularisation keeps it ~1e-6).
PD_PIVOT_RTOL = 1e-12
# A Cholesky pivot of a least-squares Gram matrix below this × its diagonal entry (a column
# within ~1e-4 rad of the others' span: condition number above ~1e4) leaves it to the SVD.
LSQ_PIVOT_RTOL = 1e-8
# One-sided Jacobi: a pair of columns counts as orthogonal when |wᵢ·wⱼ| ≤ this × ‖wᵢ‖‖wⱼ‖
# (a few units of round-off), and at most this many sweeps over all pairs are made.
JACOBI_RTOL = 1e-15
MAX_JACOBI_SWEEPS = 40

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


def _jacobi_columns(cols: Matrix) -> Matrix:
    """Rotate the columns ``cols`` (each a list) in place until pairwise orthogonal; return
    the accumulated rotation ``V`` (as columns: ``V[k]`` is the k-th right singular vector)."""
    k = len(cols)
    v: Matrix = [[1.0 if i == j else 0.0 for i in range(k)] for j in range(k)]
    for _ in range(MAX_JACOBI_SWEEPS):
        rotated = False
        for i in range(k - 1):
            ci = cols[i]
            vi = v[i]
            for j in range(i + 1, k):
                cj = cols[j]
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for e in range(len(ci)):
                    alpha += ci[e] * ci[e]
                    beta += cj[e] * cj[e]
                    gamma += ci[e] * cj[e]
                if not abs(gamma) > JACOBI_RTOL * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.hypot(1.0, zeta))
                cs = 1.0 / math.sqrt(1.0 + t * t)
                sn = cs * t
                for e in range(len(ci)):
                    p, q = ci[e], cj[e]
                    ci[e] = cs * p - sn * q
                    cj[e] = sn * p + cs * q
                vj = v[j]
                for e in range(k):
                    p, q = vi[e], vj[e]
                    vi[e] = cs * p - sn * q
                    vj[e] = sn * p + cs * q
        if not rotated:
            break
    return v


def least_norm_svd(a: Matrix, b: list[float], rcond: float) -> list[float]:
    """``x = A⁺ b``, the least-norm least-squares solution of ``A x ≈ b`` (A: r×c rows),
    singular values ``σ ≤ rcond · max σ`` counted as zero (module docstring)."""
    rows = len(a)
    cols_a = len(a[0]) if rows else 0
    if rows == 0 or cols_a == 0:
        return [0.0] * cols_a
    transpose = rows < cols_a
    if transpose:  # columns of Aᵀ (the rows of A): fewer of them
        w = [list(a[i]) for i in range(rows)]
    else:
        w = [[a[i][j] for i in range(rows)] for j in range(cols_a)]
    v = _jacobi_columns(w)
    norms2 = [0.0] * len(w)
    sigma_max = 0.0
    for k in range(len(w)):
        s = 0.0
        for val in w[k]:
            s += val * val
        norms2[k] = s
        sigma_max = max(sigma_max, math.sqrt(s))
    x = [0.0] * cols_a
    for k in range(len(w)):
        if not math.sqrt(norms2[k]) > rcond * sigma_max or norms2[k] == 0.0:
            continue
        wk = w[k]
        vk = v[k]
        s = 0.0
        if transpose:  # Aᵀ V = W: x = Σ_k w_k (v_k·b)/σ_k²
            for e in range(rows):
                s += vk[e] * b[e]
            coef = s / norms2[k]
            for e in range(cols_a):
                x[e] += coef * wk[e]
        else:  # A V = W: x = Σ_k v_k (w_k·b)/σ_k²
            for e in range(rows):
                s += wk[e] * b[e]
            coef = s / norms2[k]
            for e in range(cols_a):
                x[e] += coef * vk[e]
    return x


def spd_solve(a: Matrix, idx: list[int], b: list[float], pivot_rtol: float, rcond: float
              ) -> list[float]:
    """``A[idx, idx] x = b`` for a symmetric positive semi-definite ``A``: Cholesky while its
    pivots stay above ``pivot_rtol``, else the least-norm solution (:func:`least_norm_svd`)."""
    x = cholesky_solve(a, idx, b, pivot_rtol)
    if x is not None:
        return x
    return least_norm_svd([[a[i][j] for j in idx] for i in idx], b, rcond)


def least_norm(b: Matrix, free: list[int], r: list[float], rcond: float) -> list[float]:
    """The least-norm least-squares ``x`` of ``B[:, free] x ≈ r`` (module docstring): normal
    equations of the smaller Gram matrix when well conditioned, else the SVD of ``B_F``."""
    rows = len(b)
    f = len(free)
    x: list[float] | None
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
        x = cholesky_solve(gram, list(range(f)), rhs, LSQ_PIVOT_RTOL)
    else:
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
        x = None
        if y is not None:
            x = [0.0] * f
            for i in range(f):
                cf = free[i]
                s = 0.0
                for k in range(rows):
                    s += b[k][cf] * y[k]
                x[i] = s
    if x is not None:
        return x
    return least_norm_svd([[b[k][cf] for cf in free] for k in range(rows)], r, rcond)


def mat_vec(a: Matrix, x: list[float]) -> list[float]:
    """``A x`` for ``A`` as a list of rows, each sum in index order."""
    out = [0.0] * len(a)
    n = len(x)
    for i in range(len(a)):
        row = a[i]
        acc = 0.0
        for k in range(n):
            acc += row[k] * x[k]
        out[i] = acc
    return out


def sq_norm(x: list[float]) -> float:
    """``‖x‖²``, the sum of squares in index order."""
    acc = 0.0
    for v in x:
        acc += v * v
    return acc


def norm(x: list[float]) -> float:
    """The Euclidean norm of ``x`` (:func:`sq_norm`'s root)."""
    return math.sqrt(sq_norm(x))
