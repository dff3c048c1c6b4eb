"""Exact solver of ``min_{lo ≤ T ≤ hi} max_k ‖B_k T − v‖² + ε‖T‖²`` over a vertex set.

What it does: :class:`VertexMinimaxSolver` returns the thrust minimising the worst-case
residual over the vertex matrices ``B_k`` of a polytopic or polyhedral uncertainty set
(the robust allocators of :mod:`flight_sw.allocation.robust_polytopic` and
:mod:`flight_sw.allocation.robust_polyhedral`; seed 001, Theorems 1 and 2), by one of two
paths:

1. Scalar dual path (exact; the paper's structure, and any set whose vertices are all
   multiples ``B_k = s_k R`` of one matrix, detected to :data:`PROPORTIONAL_RTOL`).
   ``‖s y − v‖²`` (``y = R T``) is convex in ``s``, so only ``s₁ = min s_k`` and
   ``s₂ = max s_k`` matter. By the minimax theorem (convex in T on a compact box, linear
   in λ) the problem equals its Lagrange dual over ``λ ∈ [0, 1]``:

       g(λ) = min_{lo ≤ T ≤ hi} (1 − λ) f₁(T) + λ f₂(T) + ε‖T‖²,
              i.e. the box QP with M = a RᵀR + εI, c = b Rᵀv,
              a = (1 − λ)s₁² + λs₂², b = (1 − λ)s₁ + λs₂,

   ``g`` concave with ``g'(λ) = f₂ − f₁`` at the inner solution ``T(λ)`` (Danskin). Each
   inner problem is solved exactly by the dense active-set
   :func:`~flight_sw.allocation.active_set.box_qp` (warm-started from the previous active
   set); ``g'(λ) = 0`` by safeguarded Newton (``g''`` from the sensitivity of ``T`` on its
   active set; :func:`~flight_sw.allocation.root_finding.monotone_root`), started from the
   previous allocation's λ (cold: ``s₁/(s₁ + s₂)``, the optimum for attainable demands).
   It stops on the certified duality gap ``F(T(λ)) − g(λ) ≤`` :data:`SQP_RTOL` × ``F``
   (``F`` the primal objective; the gap is ``(1 − λ)(f₂ − f₁)`` or ``λ(f₁ − f₂)``), so the
   returned thrust is optimal to that relative accuracy, not a bound.
2. General vertices: the epigraph form ``min t s.t. ‖B_k T − v‖² ≤ t`` is a convex QCQP,
   solved by sequential quadratic programming with OSQP subproblems (Han's SQP for
   minimax; Nocedal & Wright 2006, ch. 18): at ``T_j`` with multipliers ``λ`` (from the
   previous subproblem, uniform at the start)

       minimise_{T, t}  t + ½ (T − T_j)ᵀ H_λ (T − T_j) + ε ‖T‖²
       subject to  f_k + g_kᵀ (T − T_j) ≤ t  (all k),  lo ≤ T ≤ hi,

   with ``f_k = ‖B_k T_j − v‖²``, ``g_k = 2 B_kᵀ(B_k T_j − v)`` and the exact Lagrangian
   Hessian ``H_λ = 2 Σ λ_k B_kᵀ B_k``; the subproblem's duals are the next ``λ``, and a
   backtracking line search on the worst-case objective makes it globally convergent. It
   stops when the predicted decrease is below :data:`SQP_RTOL` of the objective or after
   ``max_sqp_iter`` iterations. This path is exact but slower (OSQP subproblems: a few
   milliseconds); it is only taken for vertex sets without the scalar structure.

Both are deterministic (bounded iteration counts, no time limit); the warm start (λ and
active set of the previous call, per instance; ``warm_start`` also warm-starts OSQP) means
the same sequence of demands gives bit-identical thrusts.

ε = ``regularization`` × mean diagonal of ``mean_k B_kᵀ B_k`` makes the optimum unique.
With a single vertex (ρ = 0) it is the bounded least-squares problem, and the ε → 0
active-set refinement of :mod:`flight_sw.allocation.active_set` is applied to the result.

Inputs: the K×m×k vertex stack over the available thrusters, their bounds ``lo``/``hi``
[N], ε, the iteration bound, the warm-start switch and the objective floor (squared
demand units) below which decreases and gaps count as zero. Output: thrusts [N] (k,).

Assumptions: the residual is convex in the uncertain parameters (so the worst case sits
at a vertex); finite vertices.

Sources: seed 001, sec. 4 (Theorems 1–2); El Ghaoui & Lebret 1997, "Robust solutions to
least-squares problems with uncertain data", SIAM J. Matrix Anal. Appl. 18(4)
1035–1064; Sion 1958 (minimax theorem); Han 1981, "Variable metric methods for minimizing
a class of nondifferentiable functions", Math. Prog. 20, 1–13 (SQP for minimax); Nocedal
& Wright 2006, ch. 18; Stellato et al. 2020 (OSQP).
"""

from __future__ import annotations

import math

import numpy as np
import osqp
import scipy.sparse as sp

from flight_sw.allocation.active_set import FREE, box_qp, refine
from flight_sw.allocation.base import RANK_RTOL
from flight_sw.allocation.dense import PD_PIVOT_RTOL, spd_solve
from flight_sw.allocation.osqp_lean import LeanOsqp, osqp_settings
from flight_sw.allocation.root_finding import monotone_root

# Stop when the predicted decrease of the worst-case objective is below this fraction of it.
SQP_RTOL = 1e-9
# Armijo line search: sufficient-decrease fraction and the number of step halvings.
ARMIJO_FRACTION = 1e-4
MAX_STEP_HALVINGS = 30
# Proximal weight on the epigraph variable t, relative to 1/(current objective): keeps the
# subproblem strongly convex in t (ADMM converges slowly on LP-like directions); the term
# vanishes at a fixed point (t = current objective), so the SQP's solution is unchanged.
T_PROX_WEIGHT = 1.0
# Vertices within this × ‖B_ref‖_F of a multiple of the reference vertex B_ref count as
# scalar multiples of it (the scalar dual path applies).
PROPORTIONAL_RTOL = 1e-12
# First λ of the scalar dual path when s₁ + s₂ ≤ 0 and nothing to warm-start from.
LAMBDA_FALLBACK_START = 0.5


def _upper_pattern(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSC (row index, column index, indptr) of a dense upper triangle k×k."""
    rows = np.concatenate([np.arange(j + 1) for j in range(k)])
    cols = np.concatenate([np.full(j + 1, j) for j in range(k)])
    indptr = np.concatenate([[0], np.cumsum(np.arange(1, k + 1))])
    return rows, cols, indptr


def _scalar_structure(vertices: np.ndarray) -> tuple[np.ndarray, float, float] | None:
    """``(R, s_min, s_max)`` when every vertex is ``s_k R`` (``R`` the largest), else None."""
    norms = np.sqrt(np.einsum("kmn,kmn->k", vertices, vertices))
    ref = vertices[int(np.argmax(norms))]
    ref2 = float(np.sum(ref * ref))
    if ref2 <= 0.0:
        return ref, 1.0, 1.0
    scales = np.einsum("kmn,mn->k", vertices, ref) / ref2
    dev = vertices - scales[:, None, None] * ref[None]
    dev_max = float(np.max(np.sqrt(np.einsum("kmn,kmn->k", dev, dev))))
    if dev_max > PROPORTIONAL_RTOL * math.sqrt(ref2):
        return None
    return ref, float(np.min(scales)), float(np.max(scales))


class VertexMinimaxSolver:
    """``argmin_{lo ≤ T ≤ hi} max_k ‖B_k T − v‖² + ε‖T‖²`` by SQP on OSQP (module docstring)."""

    def __init__(
        self,
        vertices: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        regularization: float,
        max_iter: int,
        warm_start: bool,
        f_floor: float,
    ) -> None:
        n_vert, _, k = vertices.shape
        self._v = vertices
        self._lo, self._hi = lo, hi
        self._k, self._n_vert = k, n_vert
        self._max_iter = max_iter
        self._f_floor = f_floor
        self._gram2 = 2.0 * np.einsum("kmi,kmj->kij", vertices, vertices)
        mean_gram = self._gram2.mean(axis=0) / 2.0
        self._eps = regularization * float(np.mean(np.diag(mean_gram)))
        self._pinv_mean = np.linalg.pinv(vertices.mean(axis=0), rcond=RANK_RTOL)
        self._scalar = _scalar_structure(vertices)
        self._warm = warm_start
        if self._scalar is not None:
            ref, _, _ = self._scalar
            self._ref_gram = ref.T @ ref
            self._state = np.full(k, FREE, dtype=np.int8)
            self._lam_warm = math.nan
            self._definite = self._eps > 0.0
        # P: dense upper triangle over T (the epigraph variable t has no quadratic term).
        p_rows, p_cols, p_ptr = _upper_pattern(k)
        self._p_rows, self._p_cols = p_rows, p_cols
        p_rows = np.concatenate([p_rows, [k]])
        p_cols = np.concatenate([p_cols, [k]])
        self._p_rows, self._p_cols = p_rows, p_cols
        p_ptr_full = np.concatenate([p_ptr, [p_ptr[-1] + 1]])
        self._p_dense = np.eye(k + 1)
        p = sp.csc_matrix((self._p_dense[p_rows, p_cols], p_rows, p_ptr_full), shape=(k + 1, k + 1))
        # A: rows 0..K−1 [g_kᵀ, −1] (dense), rows K..K+k−1 [I, 0]; CSC order per column.
        a_rows, a_cols = [], []
        for j in range(k):
            a_rows += [*range(n_vert), n_vert + j]
            a_cols += [j] * (n_vert + 1)
        a_rows += list(range(n_vert))
        a_cols += [k] * n_vert
        self._a_rows, self._a_cols = np.array(a_rows), np.array(a_cols)
        self._a_dense = np.zeros((n_vert + k, k + 1))
        self._a_dense[:n_vert, :k] = 1.0
        self._a_dense[:n_vert, k] = -1.0
        self._a_dense[n_vert:, :k] = np.eye(k)
        a_ptr = np.concatenate([np.arange(k + 1) * (n_vert + 1), [k * (n_vert + 1) + n_vert]])
        a = sp.csc_matrix(
            (self._a_dense[self._a_rows, self._a_cols], self._a_rows, a_ptr),
            shape=(n_vert + k, k + 1),
        )
        self._l = np.concatenate([np.full(n_vert, -np.inf), lo])
        self._u = np.concatenate([np.zeros(n_vert), hi])
        self._q = np.zeros(k + 1)
        self._q[k] = 1.0
        problem = osqp.OSQP()
        problem.setup(p, self._q, a, self._l, self._u, **osqp_settings(warm_start))
        self._osqp = LeanOsqp(problem)

    def _objective(self, t: np.ndarray, v: np.ndarray) -> float:
        r = self._v @ t - v[None]
        return float(np.max(np.sum(r * r, axis=1))) + self._eps * float(t @ t)

    def solve(self, v: np.ndarray) -> np.ndarray:
        """The robust thrust (available thrusters only) for demand ``v``."""
        t = self._solve_scalar(v) if self._scalar is not None else self._solve_sqp(v)
        if self._n_vert == 1:
            t = self._refine_single_vertex(t, v)
        return t

    def _solve_scalar(self, v: np.ndarray) -> np.ndarray:
        """Vertices ``s_k R``: the one-dimensional dual of the module docstring."""
        assert self._scalar is not None
        ref, s1, s2 = self._scalar
        gram, eps, lo, hi = self._ref_gram, self._eps, self._lo, self._hi
        rv = ref.T @ v
        eye = np.eye(self._k)
        v2 = float(v @ v)
        best: list[tuple[float, np.ndarray]] = []

        def inner(lam: float) -> tuple[np.ndarray, float, float]:
            a = (1.0 - lam) * s1 * s1 + lam * s2 * s2
            b = (1.0 - lam) * s1 + lam * s2
            m_mat = a * gram + eps * eye
            t, self._state = box_qp(m_mat, b * rv, lo, hi, self._state, self._definite)
            y = ref @ t
            yy, yv = float(y @ y), float(y @ v)
            f1 = s1 * s1 * yy - 2.0 * s1 * yv + v2
            f2 = s2 * s2 * yy - 2.0 * s2 * yv + v2
            obj = max(f1, f2) + eps * float(t @ t)
            if not best or obj < best[0][0]:
                best[:] = [(obj, t)]
            return t, f2 - f1, obj

        if s2 <= s1:
            return inner(0.0)[0]

        def evaluate(lam: float) -> tuple[float, float, bool]:
            t, h, obj = inner(lam)
            gap = (1.0 - lam) * h if h > 0.0 else -lam * h  # F(T(λ)) − g(λ) ≥ F(T(λ)) − F*
            done = gap <= SQP_RTOL * obj + self._f_floor
            # ψ = −h is increasing in λ; ψ' from the sensitivity of T on its active set.
            free = self._state == FREE
            idx = np.flatnonzero(free)
            dpsi = math.nan
            if idx.size and not done:
                a = (1.0 - lam) * s1 * s1 + lam * s2 * s2
                rhs = ((s2 - s1) * rv - (s2 * s2 - s1 * s1) * (gram @ t))[idx]
                m_ff = a * gram[np.ix_(idx, idx)] + eps * eye[: idx.size, : idx.size]
                dt = np.array(spd_solve(m_ff.tolist(), list(range(idx.size)), rhs.tolist(),
                                        PD_PIVOT_RTOL, RANK_RTOL))
                dy = ref[:, idx] @ dt
                y = ref @ t
                dh = (s2 - s1) * (2.0 * (s1 + s2) * float(y @ dy) - 2.0 * float(v @ dy))
                dpsi = -dh
            return -h, dpsi, done

        # Cold start: λ = s₁/(s₁ + s₂), the optimum when the demand stays attainable.
        lam0 = s1 / (s1 + s2) if s1 + s2 > 0.0 else LAMBDA_FALLBACK_START
        if not self._warm:
            self._state[:] = FREE
        elif math.isfinite(self._lam_warm):
            lam0 = self._lam_warm
        self._lam_warm = monotone_root(evaluate, lam0, 0.0, 1.0)
        return best[0][1]

    def _solve_sqp(self, v: np.ndarray) -> np.ndarray:
        """General vertices: the SQP on OSQP of the module docstring."""
        lo, hi, k, n_vert = self._lo, self._hi, self._k, self._n_vert
        t = np.minimum(np.maximum(self._pinv_mean @ v, lo), hi)
        lam = np.full(n_vert, 1.0 / n_vert)
        obj = self._objective(t, v)
        for _ in range(self._max_iter):
            r = self._v @ t - v[None]
            f = np.sum(r * r, axis=1)
            g = 2.0 * np.einsum("kmi,km->ki", self._v, r)
            h = np.einsum("k,kij->ij", lam, self._gram2)
            self._p_dense[:k, :k] = h + 2.0 * self._eps * np.eye(k)
            prox = T_PROX_WEIGHT / max(obj, self._f_floor)
            self._p_dense[k, k] = prox
            self._a_dense[:n_vert, :k] = g
            self._u[:n_vert] = g @ t - f
            self._q[:k] = -(h @ t)
            self._q[k] = 1.0 - prox * obj
            self._osqp.update(
                Px=self._p_dense[self._p_rows, self._p_cols],
                Ax=self._a_dense[self._a_rows, self._a_cols],
                q=self._q,
                l=self._l,
                u=self._u,
            )
            res = self._osqp.solve()
            x = res.x
            if x.shape != (k + 1,) or not np.all(np.isfinite(x)):
                break
            t_new = np.minimum(np.maximum(x[:k], lo), hi)
            step = t_new - t
            model = float(np.max(f + g @ step)) + self._eps * float(t_new @ t_new)
            decrease = obj - model
            if decrease <= SQP_RTOL * obj + self._f_floor:
                break
            y = np.maximum(res.y[:n_vert], 0.0)
            if float(y.sum()) > 0.0:
                lam = y / float(y.sum())
            alpha = 1.0
            for _ in range(MAX_STEP_HALVINGS):
                cand = t + alpha * step
                cand_obj = self._objective(cand, v)
                if cand_obj <= obj - ARMIJO_FRACTION * alpha * decrease:
                    t, obj = cand, cand_obj
                    break
                alpha *= 0.5
            else:
                break
        return t

    def _refine_single_vertex(self, t: np.ndarray, v: np.ndarray) -> np.ndarray:
        """One vertex (ρ = 0): the ε → 0 active-set refinement of the bounded QP allocator."""
        return refine(self._v[0], v, t, self._lo, self._hi, self._f_floor)
