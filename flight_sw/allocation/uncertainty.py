"""Uncertainty sets of the thruster effectiveness matrix and their worst-case residuals.

What it does: describes the three structured uncertainty sets of seed 001, sec. 4, for the
true effectiveness matrix ``B(δ) = B₀ + ΔB`` and evaluates the worst-case residual
``max_ΔB ‖(B₀ + ΔB) T − v‖`` of a thrust vector ``T`` for a demand ``v``:

* regular polyhedral set (sec. 4, set ``Δ_I``, Theorem 1): ``ΔB(δ) = Σᵢ δᵢ Bᵢ`` (eq. 13)
  with ``δᵢ ∈ [−1, 1]``; its vertices are the ``2^q`` corner values ``δ ∈ Δ_E``
  (:func:`polyhedral_vertices`);
* polytopic set (``Δ_P``, Theorem 2): ``δᵢ ≥ 0``, ``Σ δᵢ = 1``; vertices ``B₀ + Bᵢ``
  (:func:`polytopic_vertices`);
* linear-fractional set (Theorem 3): ``ΔB = E F H`` with ``FᵀF ≤ I``.

For the first two the residual is a convex function of ``δ``, so its maximum over the set
is attained at a vertex: :func:`vertex_worst_case_residual` is exact (this is why
Theorems 1 and 2 only impose their LMIs at the vertices). For the linear-fractional set,
``{F h : ‖F‖ ≤ 1} = {w : ‖w‖ ≤ ‖h‖}`` (rank-one ``F = w hᵀ/‖h‖²`` reaches every such ``w``),
so with ``r = B₀T − v`` and ``h = H T`` the worst case is the trust-region maximum
``max_{‖w‖≤‖h‖} ‖r + E w‖²``. The S-lemma (one quadratic constraint) is lossless, and its
dual, with ``τ = 1/μ`` and ``EEᵀ = U diag(s) Uᵀ``, is the one-dimensional convex problem

    r_wc² = min_{0 < τ < 1/max s}  rᵀ(I − τ EEᵀ)⁻¹ r + ‖h‖²/τ
          = min_τ  Σⱼ (Uᵀr)ⱼ² / (1 − τ sⱼ) + ‖h‖²/τ,

which is exactly the Schur complement of the paper's LMI (20) (its ``δ`` is this ``τ``;
Lemma 1 there is the same bound), so Theorem 3 is exact for a full block ``F``
(El Ghaoui & Lebret 1997, Theorem 3.2 there for ``‖·‖``-bounded full-block data).
:func:`lft_tau_minimiser` solves it by bisection on the (increasing) derivative.

Inputs: matrices in demand rows × thrusters, thrust [N], demand in demand units.
Outputs: vertex stacks (K×m×n) and residual norms [demand units].

Assumptions: the uncertainty enters linearly (polyhedral/polytopic) or through a single
full block ``F`` (linear-fractional); ``δ`` has independent components in ``[−1, 1]``.

Sources: seed 001 (MRP control and robust allocation of a combined spacecraft), sec. 4,
eq. 13, Theorems 1–3, sec. 5 (``Bᵢ = wᵢ ρ B₀`` with weights 1, 1, 2, 2 and ρ = 0.1);
El Ghaoui & Lebret 1997, "Robust solutions to least-squares problems with uncertain
data", SIAM J. Matrix Anal. Appl. 18(4) 1035–1064; Boyd et al. 1994, "Linear Matrix
Inequalities in System and Control Theory", SIAM, sec. 2.6.3 (S-procedure).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

# Seed 001, sec. 5: B_i = w_i ρ B₀ with these weights (0.1, 0.1, 0.2, 0.2 for ρ = 0.1).
SEED001_BASIS_WEIGHTS = (1.0, 1.0, 2.0, 2.0)
SEED001_RHO = 0.1
# Seed 001, sec. 5: E = ρ · diag(1, 1.5, 1) (= diag(0.1, 0.15, 0.1)) and H (3×8).
SEED001_LFT_E_SHAPE = ((1.0, 0.0, 0.0), (0.0, 1.5, 0.0), (0.0, 0.0, 1.0))
SEED001_LFT_H = (
    (0.1, 0.0, 0.0, 0.1, -0.1, 0.1, 0.1, 0.1),
    (0.0, 0.1, 0.0, -0.1, 0.1, 0.1, 0.1, -0.1),
    (0.0, 0.0, 0.1, 0.1, 0.1, 0.1, 0.2, -0.1),
)
# Vertex enumeration is 2^q: refuse more basis matrices than this.
MAX_POLYHEDRAL_BASIS = 8
# The τ search runs on θ = τ·max s in [THETA_MIN, THETA_MAX] (the open interval (0, 1)).
THETA_MIN = 1e-12
THETA_MAX = 1.0 - 1e-12
TAU_BISECTIONS = 60
# Eigenvalues of EEᵀ below this fraction of the largest are treated as zero.
EIG_RTOL = 1e-12


def relative_basis(b0: np.ndarray, rho: float, weights: tuple[float, ...]) -> np.ndarray:
    """Seed 001 sec. 5 basis ``Bᵢ = wᵢ ρ B₀`` as a q×m×n stack."""
    return np.array([w * rho * np.asarray(b0, dtype=float) for w in weights])


def polyhedral_vertices(b0: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Distinct vertex matrices ``B₀ + Σ δᵢ Bᵢ``, ``δ ∈ {−1, 1}^q`` (K×m×n, K ≤ 2^q)."""
    b0 = np.asarray(b0, dtype=float)
    q = basis.shape[0]
    if q == 0:
        return b0[None].copy()
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=q)))
    stack = b0[None] + np.einsum("kq,qmn->kmn", signs, basis)
    return unique_vertices(stack)


def polytopic_vertices(b0: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Distinct vertex matrices ``B₀ + Bᵢ`` of the polytopic set (K×m×n, K ≤ q)."""
    b0 = np.asarray(b0, dtype=float)
    if basis.shape[0] == 0:
        return b0[None].copy()
    return unique_vertices(b0[None] + basis)


def unique_vertices(stack: np.ndarray) -> np.ndarray:
    """``stack`` without repeated matrices (first occurrence kept, order preserved)."""
    flat = stack.reshape(stack.shape[0], -1)
    _, first = np.unique(flat, axis=0, return_index=True)
    return stack[np.sort(first)]


def vertex_worst_case_residual(vertices: np.ndarray, thrust: np.ndarray, v: np.ndarray) -> float:
    """``max_k ‖B_k T − v‖``: the exact worst case over the polytope with these vertices."""
    r = vertices @ thrust - v[None]
    return float(np.sqrt(np.max(np.sum(r * r, axis=1))))


def lft_tau_minimiser(c2: np.ndarray, s: np.ndarray, h2: float) -> tuple[float, float]:
    """``(τ*, value)`` minimising ``Σ c2ⱼ/(1 − τ sⱼ) + h2/τ`` over ``0 < τ < 1/max s``.

    ``c2`` = squared components of the residual in the eigenbasis of ``EEᵀ`` (eigenvalues
    ``s`` ≥ 0). Convex in τ: bisection on the derivative over θ = τ·max s. Returns
    ``(0, Σ c2)`` when ``E`` or ``h`` vanish (no uncertainty acts).
    """
    s_max = float(np.max(s)) if s.size else 0.0
    if s_max <= 0.0 or h2 <= 0.0:
        return 0.0, float(np.sum(c2))
    sn = s / s_max  # eigenvalues in units of the largest: θ ∈ (0, 1)
    cs = (c2 * sn).tolist()
    sl = sn.tolist()
    lo, hi = THETA_MIN, THETA_MAX

    def slope(theta: float) -> float:
        # d/dθ of the objective, in θ units (h2 scaled by s_max accordingly).
        acc = 0.0
        for cj, sj in zip(cs, sl, strict=True):
            den = 1.0 - theta * sj
            acc += cj / (den * den)
        return acc - h2 * s_max / (theta * theta)

    if slope(hi) <= 0.0:
        theta = hi
    elif slope(lo) >= 0.0:
        theta = lo
    else:
        for _ in range(TAU_BISECTIONS):
            mid = 0.5 * (lo + hi)
            if slope(mid) > 0.0:
                hi = mid
            else:
                lo = mid
        theta = 0.5 * (lo + hi)
    tau = theta / s_max
    value = float(np.sum(c2 / (1.0 - theta * sn))) + h2 / tau
    return tau, value


def lft_worst_case_residual(
    b0: np.ndarray, e: np.ndarray, h: np.ndarray, thrust: np.ndarray, v: np.ndarray
) -> float:
    """``max_{‖F‖≤1} ‖(B₀ + E F H) T − v‖`` (exact, via the lossless S-lemma dual)."""
    r = np.asarray(b0, dtype=float) @ thrust - v
    hv = np.asarray(h, dtype=float) @ thrust
    s, u = np.linalg.eigh(np.asarray(e, dtype=float) @ np.asarray(e, dtype=float).T)
    s = np.where(s > EIG_RTOL * max(float(np.max(s)), 0.0), s, 0.0)
    c2 = (u.T @ r) ** 2
    _, value = lft_tau_minimiser(c2, s, float(hv @ hv))
    return math.sqrt(max(value, 0.0))


def lft_worst_case_perturbation(
    b0: np.ndarray, e: np.ndarray, h: np.ndarray, thrust: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """A maximising ``F`` (``‖F‖ ≤ 1``, rank one) for the worst case above.

    From the S-lemma stationarity ``w = τ (I − τ EᵀE)⁻¹ Eᵀ r`` (scaled onto the sphere
    ``‖w‖ = ‖h‖`` when round-off leaves it inside), ``F = w hᵀ/‖h‖²``.
    """
    e = np.asarray(e, dtype=float)
    r = np.asarray(b0, dtype=float) @ thrust - v
    hv = np.asarray(h, dtype=float) @ thrust
    h2 = float(hv @ hv)
    if h2 <= 0.0:
        return np.zeros((e.shape[1], hv.shape[0]))
    s, u = np.linalg.eigh(e @ e.T)
    s = np.where(s > EIG_RTOL * max(float(np.max(s)), 0.0), s, 0.0)
    tau, _ = lft_tau_minimiser((u.T @ r) ** 2, s, h2)
    if tau <= 0.0:
        return np.zeros((e.shape[1], hv.shape[0]))
    w = tau * np.linalg.solve(np.eye(e.shape[1]) - tau * e.T @ e, e.T @ r)
    norm_w = float(np.linalg.norm(w))
    if norm_w > 0.0:
        w *= math.sqrt(h2) / norm_w
    return np.outer(w, hv) / h2
