"""Dense kernels of the RLS inertia identifier, on Python floats (compiled with mypyc).

What it does: the per-cycle arithmetic of :mod:`flight_sw.estimation.rls_inertia` written
out for its fixed sizes (3 axes, 6 parameters), where numpy's per-call overhead (~1-10 µs a
call, some thirty calls a cycle, a 51-sample stack with a 50-cycle window) is most of the
time and the arithmetic itself is about two thousand flops:

- :func:`gyroscopic`: ``[ω×] Ω(ω)`` (3×6, flat), the gyroscopic term of Euler's equation
  (seed 001 eq. (2)) linear in ``θ = (J11, J12, J13, J22, J23, J33)``.
- :func:`window_equation`: ``(Φ, y)`` of Euler's equation integrated over a window of
  samples by the trapezoidal rule (the equation of the identifier's module docstring).
- :func:`rls_step`: one RLS step with forgetting factor (seed 001 §2), the symmetrisation
  and the constant-trace bound on ``P``, and the discounted information ``R``.
- :func:`exceeds`: whether ``A − m I`` is positive definite (``λ_min(A) > m``), by
  Cholesky, for the identifier's excitation and positive-definiteness gates.

Cholesky factorisations and solves are :func:`flight_sw.allocation.dense.cholesky_solve`'s,
the singular-value fallback :func:`flight_sw.allocation.dense.least_norm_svd`'s (the
allocators' kernels, compiled in the same group): the package's one dense solver.

In and out: plain lists, matrices as lists of rows, float64. Rates [rad/s], torques [N m],
times [s], ``θ`` [kg m²], ``P`` [(kg m²)²], ``R`` [(rad/s²)²].

Ill-conditioned steps: the 3×3 innovation matrix ``S = λ I + Φ P Φᵀ`` is positive definite
in exact arithmetic (``S ≥ λ I``), but with ``P Φᵀ`` ~1e14 × λ or more (a huge initial
covariance, nearly dependent regressor rows) a Cholesky pivot can fall to round-off. When
a pivot is at or below :data:`S_PIVOT_RTOL` times its diagonal entry, :func:`rls_step`
solves ``S K_rᵀ = (P Φᵀ)_rᵀ`` by the one-sided Jacobi SVD instead (pseudo-inverse with no
cut-off: every non-zero singular value is inverted, as an exact solve would), which stays
accurate wherever the data determine the answer; it says so in its fourth return value,
and the identifier counts these steps. Only a non-finite result (overflow, NaN in the
inputs) is refused: :func:`rls_step` returns None and the identifier skips the step (also
counted).

Assumptions: finite inputs, ``P`` and ``R`` symmetric, ``0 < λ ≤ 1``.

Source: seed 001 ("Attitude control and structure robust control allocation for combined
spacecraft"), §2: Euler equation (2) and the three RLS equations with forgetting factor.
"""

from __future__ import annotations

import math

from flight_sw.allocation.dense import cholesky_solve, least_norm_svd

N_AXES = 3
N_PARAMS = 6
TRAPEZOID_WEIGHT = 0.5
# A Cholesky pivot of S below this × its diagonal entry: S is not numerically positive
# definite (only when P Φᵀ is ~1e14 × λ or more); the Jacobi SVD solves it instead.
S_PIVOT_RTOL = 1e-14
# Singular values of S counted as zero by the SVD solve: none but exact zeros (S is positive
# definite in exact arithmetic; the SVD is taken for accuracy, not to regularise).
S_SVD_RCOND = 0.0

Vector = list[float]
Matrix = list[list[float]]


def momentum_regressor(w: Vector) -> Matrix:
    """``Ω(ω)`` (3×6) with ``J ω = Ω(ω) θ``."""
    w1, w2, w3 = w[0], w[1], w[2]
    return [
        [w1, w2, w3, 0.0, 0.0, 0.0],
        [0.0, w1, 0.0, w2, w3, 0.0],
        [0.0, 0.0, w1, 0.0, w2, w3],
    ]


def gyroscopic(w: Vector) -> Vector:
    """``[ω×] Ω(ω)`` (3×6) written out, flat in row order (18 entries)."""
    w1, w2, w3 = w[0], w[1], w[2]
    return [
        0.0, -w1 * w3, w1 * w2, -w2 * w3, w2 * w2 - w3 * w3, w2 * w3,
        w1 * w3, w2 * w3, w3 * w3 - w1 * w1, 0.0, -w1 * w2, -w1 * w3,
        -w1 * w2, w1 * w1 - w2 * w2, -w2 * w3, w1 * w2, w1 * w3, 0.0,
    ]


def window_equation(
    h_s: Vector, omega_first: Vector, omega_last: Vector, gyro: list[Vector], torque: Matrix
) -> tuple[Matrix, Vector]:
    """``(Φ, y)`` of Euler's equation integrated over ``len(h_s)`` periods.

    ``h_s[k]`` is the length of period k [s] (> 0), ``gyro`` the N + 1 samples'
    ``[ω×]Ω(ω)`` (flat, as :func:`gyroscopic`), ``torque`` the N periods' mean torques
    [N m]. With ``T = Σ h_k``:
    ``Φ = Ω((ω_last − ω_first)/T) + (1/T) Σ_k ½ h_k (G_k + G_{k+1})``,
    ``y = (1/T) Σ_k h_k τ_k``; the trapezoid sum is taken per sample, with the weight
    ``½ (h_{k−1} + h_k)`` of the two periods it bounds.
    """
    n = len(h_s)
    total_s = 0.0
    for k in range(n):
        total_s += h_s[k]
    inv_t = 1.0 / total_s
    weight = [0.0] * (n + 1)
    for k in range(n + 1):
        weight[k] = TRAPEZOID_WEIGHT * ((h_s[k - 1] if k > 0 else 0.0) + (h_s[k] if k < n else 0.0))
    dw = [(omega_last[i] - omega_first[i]) * inv_t for i in range(N_AXES)]
    phi = momentum_regressor(dw)
    for i in range(N_AXES):
        p_i = phi[i]
        for j in range(N_PARAMS):
            e = i * N_PARAMS + j
            s = 0.0
            for k in range(n + 1):
                s += weight[k] * gyro[k][e]
            p_i[j] += s * inv_t
    y = [0.0] * N_AXES
    for i in range(N_AXES):
        s = 0.0
        for k in range(n):
            s += h_s[k] * torque[k][i]
        y[i] = s * inv_t
    return phi, y


def exceeds(a: Matrix, m: float) -> bool:
    """Whether ``A − m I`` (A symmetric) is positive definite, i.e. ``λ_min(A) > m``."""
    n = len(a)
    shifted = [[a[i][j] - m if i == j else a[i][j] for j in range(n)] for i in range(n)]
    return cholesky_solve(shifted, list(range(n)), [0.0] * n, 0.0) is not None


def rls_step(
    p: Matrix, theta: Vector, info: Matrix, phi: Matrix, y: Vector, lam: float,
    trace_cap: float,
) -> tuple[Matrix, Vector, Matrix, bool] | None:
    """One RLS step: ``(P_k, θ_k, R_k, by_svd)``, or None if the result is not finite.

    ``K = P Φᵀ S⁻¹`` with ``S = λ I3 + Φ P Φᵀ``, ``θ_k = θ + K (y − Φ θ)``,
    ``P_k = sym((P − K Φ P)/λ)`` scaled to trace ``trace_cap`` if above it,
    ``R_k = λ R + Φᵀ Φ``. ``by_svd``: ``S`` failed the Cholesky gate and was solved by the
    Jacobi SVD (module docstring).
    """
    # P Φᵀ (6×3); P symmetric, so Φ P = (P Φᵀ)ᵀ
    pf = [[0.0] * N_AXES for _ in range(N_PARAMS)]
    for r in range(N_PARAMS):
        p_r = p[r]
        pf_r = pf[r]
        for i in range(N_AXES):
            f_i = phi[i]
            s = 0.0
            for c in range(N_PARAMS):
                s += p_r[c] * f_i[c]
            pf_r[i] = s
    smat = [[0.0] * N_AXES for _ in range(N_AXES)]
    for i in range(N_AXES):
        f_i = phi[i]
        for j in range(N_AXES):
            s = lam if i == j else 0.0
            for c in range(N_PARAMS):
                s += f_i[c] * pf[c][j]
            smat[i][j] = s
    for i in range(N_AXES):  # symmetrise (Φ P Φᵀ is symmetric up to round-off)
        for j in range(i):
            v = 0.5 * (smat[i][j] + smat[j][i])
            smat[i][j] = v
            smat[j][i] = v
    # K = P Φᵀ S⁻¹: each row k_r solves S k_rᵀ = (P Φᵀ)_rᵀ
    axes = list(range(N_AXES))
    gain: Matrix = []
    by_svd = False
    for r in range(N_PARAMS):
        row = cholesky_solve(smat, axes, pf[r], S_PIVOT_RTOL)
        if row is None:
            by_svd = True
            break
        gain.append(row)
    if by_svd:
        gain = [least_norm_svd(smat, pf[r], S_SVD_RCOND) for r in range(N_PARAMS)]
    innovation = [0.0] * N_AXES
    for i in range(N_AXES):
        f_i = phi[i]
        s = y[i]
        for c in range(N_PARAMS):
            s -= f_i[c] * theta[c]
        innovation[i] = s
    theta_new = [0.0] * N_PARAMS
    for r in range(N_PARAMS):
        k_r = gain[r]
        s = theta[r]
        for i in range(N_AXES):
            s += k_r[i] * innovation[i]
        theta_new[r] = s
    # P_k = (P − K (P Φᵀ)ᵀ)/λ, symmetrised
    p_new = [[0.0] * N_PARAMS for _ in range(N_PARAMS)]
    inv_lam = 1.0 / lam
    for r in range(N_PARAMS):
        k_r = gain[r]
        p_r = p[r]
        q_r = p_new[r]
        for c in range(N_PARAMS):
            pf_c = pf[c]
            s = p_r[c]
            for i in range(N_AXES):
                s -= k_r[i] * pf_c[i]
            q_r[c] = s * inv_lam
    trace = 0.0
    for r in range(N_PARAMS):
        q_r = p_new[r]
        for c in range(r):
            v = 0.5 * (q_r[c] + p_new[c][r])
            q_r[c] = v
            p_new[c][r] = v
        trace += q_r[r]
    if trace > trace_cap:
        scale = trace_cap / trace
        for r in range(N_PARAMS):
            q_r = p_new[r]
            for c in range(N_PARAMS):
                q_r[c] *= scale
    info_new = [[0.0] * N_PARAMS for _ in range(N_PARAMS)]
    for r in range(N_PARAMS):
        i_r = info[r]
        o_r = info_new[r]
        for c in range(N_PARAMS):
            s = lam * i_r[c]
            for i in range(N_AXES):
                s += phi[i][r] * phi[i][c]
            o_r[c] = s
    for v in theta_new:
        if not math.isfinite(v):
            return None
    for q_r in p_new:
        for v in q_r:
            if not math.isfinite(v):
                return None
    return p_new, theta_new, info_new, by_svd
