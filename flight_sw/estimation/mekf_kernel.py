"""Covariance kernels of the MEKF on Python floats (compiled with mypyc).

What it does: the 6×6 covariance arithmetic of :mod:`flight_sw.estimation.mekf`, written out
for its fixed size, with every sum in one fixed order:

- :func:`propagate_covariance`: ``P ← Φ P Φᵀ + Q_k`` with ``Φ = [[Φ11, Φ12], [0, I]]`` and
  ``Q_k = [[q11 I, q12 I], [q12 I, q22 I]]``, by blocks (``A = P11``, ``B = P12``,
  ``C = P22``): ``B' = Φ11 B + Φ12 C``, ``A' = (Φ11 A + Φ12 Bᵀ) Φ11ᵀ + B' Φ12ᵀ``,
  ``C' = C``, then ``Q_k`` added (162 multiply-adds instead of a 6×6 product's 432).
- :func:`star_tracker_update`: the update with ``H = [I 0]``, ``R = r I``: ``S = A + r I``,
  ``K = P Hᵀ S⁻¹`` (Cholesky of ``S``, :func:`flight_sw.allocation.dense.cholesky_solve`,
  the package's one dense solver), ``x̂ = K y`` and the Joseph form
  ``P ← (I − KH) P (I − KH)ᵀ + r K Kᵀ``, symmetrised.

Why not numpy: a 6×6 ``@`` and ``np.linalg.solve`` call the BLAS/LAPACK kernel that
OpenBLAS picks for the CPU at run time (Haswell, SkylakeX, Zen, ...), and those kernels sum
in different orders. The same lockstep run then gave different traces on two machines (the
formation-keeping scenario's first differing valve command came at 29.5 s). Here the bits
depend on IEEE double arithmetic only, so a trace is the same on every x86-64 machine; and
a kernel call costs a few µs where numpy's per-call overhead was most of the time.

In and out: ``P`` as a flat row-major list of 36 floats (attitude error ``a`` [rad] rows
0-2, gyro bias error ``Δb`` [rad/s] rows 3-5); ``Φ11``, ``Φ12`` flat row-major 3×3 (Φ12
[s]); ``q11`` [rad²], ``q12`` [rad²/s], ``q22`` [(rad/s)²]; ``r`` [rad²]; ``y`` [rad].

Assumptions: ``P`` symmetric positive semi-definite, ``r > 0``; a non-finite ``P`` or ``y``
is refused (:func:`star_tracker_update` returns None, the filter counts the sample).

Sources: Markley & Crassidis 2014, "Fundamentals of Spacecraft Attitude Determination and
Control", §6.2 (the MEKF's Φ, Q_k and update); Bucy & Joseph 1968 (the Joseph form).
"""

from __future__ import annotations

import math

from flight_sw.allocation.dense import cholesky_solve

N_AXES = 3
N_STATES = 6
# S = A + r I is positive definite for r > 0: any positive pivot is accepted, and only a
# non-finite or non-positive one (NaN inputs) refuses the update.
S_PIVOT_RTOL = 0.0
AXES = [0, 1, 2]


def _at(m: list[float], i: int, j: int) -> float:
    return m[N_AXES * i + j]


def propagate_covariance(p: list[float], phi11: list[float], phi12: list[float],
                         q11: float, q12: float, q22: float) -> list[float]:
    """``Φ P Φᵀ + Q_k`` for ``Φ = [[Φ11, Φ12], [0, I]]`` (flat row-major lists)."""
    n = N_STATES
    # T1 = Φ11 A + Φ12 Bᵀ and B' = Φ11 B + Φ12 C (3×3, row-major)
    t1 = [0.0] * 9
    b_new = [0.0] * 9
    for i in range(N_AXES):
        f0, f1, f2 = _at(phi11, i, 0), _at(phi11, i, 1), _at(phi11, i, 2)
        g0, g1, g2 = _at(phi12, i, 0), _at(phi12, i, 1), _at(phi12, i, 2)
        for j in range(N_AXES):
            t1[N_AXES * i + j] = (f0 * p[j] + f1 * p[n + j] + f2 * p[2 * n + j]
                                  + g0 * p[j * n + 3] + g1 * p[j * n + 4] + g2 * p[j * n + 5])
            b_new[N_AXES * i + j] = (f0 * p[3 + j] + f1 * p[n + 3 + j] + f2 * p[2 * n + 3 + j]
                                     + g0 * p[3 * n + 3 + j] + g1 * p[4 * n + 3 + j]
                                     + g2 * p[5 * n + 3 + j])
    out = list(p)
    for i in range(N_AXES):
        for j in range(i, N_AXES):  # A' = T1 Φ11ᵀ + B' Φ12ᵀ, upper triangle then mirrored
            a = (_at(t1, i, 0) * _at(phi11, j, 0) + _at(t1, i, 1) * _at(phi11, j, 1)
                 + _at(t1, i, 2) * _at(phi11, j, 2) + _at(b_new, i, 0) * _at(phi12, j, 0)
                 + _at(b_new, i, 1) * _at(phi12, j, 1) + _at(b_new, i, 2) * _at(phi12, j, 2))
            if i == j:
                a += q11
            out[i * n + j] = a
            out[j * n + i] = a
        for j in range(N_AXES):
            b = _at(b_new, i, j) + (q12 if i == j else 0.0)
            out[i * n + 3 + j] = b
            out[(3 + j) * n + i] = b
        out[(3 + i) * n + 3 + i] += q22
    return out


def star_tracker_update(p: list[float], r: float, y: list[float]
                        ) -> tuple[list[float], list[float]] | None:
    """``(x̂, P⁺)`` of the update with ``H = [I 0]``, ``R = r I`` and residual ``y`` [rad];
    None when ``S = A + r I`` is not numerically positive definite or a result is not
    finite (a non-finite input anywhere in ``P`` or ``y``)."""
    n = N_STATES
    s = [[p[i * n + j] + (r if i == j else 0.0) for j in range(N_AXES)] for i in range(N_AXES)]
    gain: list[list[float]] = []
    for i in range(n):  # row i of K = S⁻¹ P[i, :3] (S and P symmetric)
        k_i = cholesky_solve(s, AXES, [p[i * n], p[i * n + 1], p[i * n + 2]], S_PIVOT_RTOL)
        if k_i is None:
            return None
        gain.append(k_i)
    dx = [k[0] * y[0] + k[1] * y[1] + k[2] * y[2] for k in gain]
    # M = I − K H: columns 0-2 are e_j − K[:, j], columns 3-5 those of I
    m = [[(1.0 if i == j else 0.0) - (gain[i][j] if j < N_AXES else 0.0) for j in range(n)]
         for i in range(n)]
    mp = [[0.0] * n for _ in range(n)]  # M P (no sum(): Python 3.12 compensates it)
    for i in range(n):
        m_i = m[i]
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += m_i[k] * p[k * n + j]
            mp[i][j] = acc
    joseph = [[0.0] * n for _ in range(n)]  # M P Mᵀ + r K Kᵀ
    for i in range(n):
        mp_i, k_i = mp[i], gain[i]
        for j in range(n):
            m_j, k_j = m[j], gain[j]
            acc = 0.0
            for k in range(n):
                acc += mp_i[k] * m_j[k]
            joseph[i][j] = acc + r * (k_i[0] * k_j[0] + k_i[1] * k_j[1] + k_i[2] * k_j[2])
    out = [0.0] * (n * n)
    finite = True
    for i in range(n):
        finite = finite and math.isfinite(dx[i])
        for j in range(n):
            v = 0.5 * (joseph[i][j] + joseph[j][i])
            finite = finite and math.isfinite(v)
            out[i * n + j] = v
    return (dx, out) if finite else None
