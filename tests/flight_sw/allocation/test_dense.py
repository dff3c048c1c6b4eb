"""The allocators' float kernels against their numpy/LAPACK reference forms.

Back to back on random problems of thruster-set size (m ≤ 6 rows, n ≤ 16 thrusters, with
and without negative bounds): the box QP reaches the same active set and optimum as the
numpy one, the refinement the same thrusts as lstsq, the Jacobi SVD the same least-norm
solutions as LAPACK; and the cases the float forms once handed to numpy (a singular or
semi-definite free set, an ill-conditioned least-squares step, rounds that do not settle)
are answered by the float forms themselves, equal to the references.
"""

from __future__ import annotations

import numpy as np
import pytest

from flight_sw.allocation import dense, dense_active_set
from flight_sw.allocation.active_set import (
    ACTIVE_RTOL,
    BOX_GTOL,
    BOX_XTOL,
    FREE,
    MAX_PDAS_ITER,
    PRIMAL_ITER_PER_VAR,
    box_qp,
    refine_on_active_set,
)
from flight_sw.allocation.base import RANK_RTOL

from .active_set_reference import box_qp_numpy, primal_active_set, refine_lstsq

N_PROBLEMS = 200
REGULARIZATION = 1e-6  # as the bounded allocator's default
SOLUTION_ATOL = 1e-9  # thrust [N]: the same QP optimum, up to round-off of two methods
OBJECTIVE_RTOL = 1e-12
SVD_RTOL = 1e-12  # least-norm solutions of two SVD methods, relative to the solution's size
SHAPES = ((3, 8), (6, 16), (6, 12), (6, 6), (8, 3), (16, 6))


def _problem(rng: np.random.Generator, i: int) -> tuple[np.ndarray, ...]:
    """Effectiveness b (m×n), demand d and bounds of the i-th random problem."""
    m, n = ((3, 8), (6, 16), (6, 12), (6, 6))[i % 4]
    b = rng.normal(size=(m, n))
    d = rng.normal(size=m) * float(rng.choice([0.5, 5.0, 40.0]))
    lo = np.zeros(n) if i % 3 else np.full(n, -2.3)
    hi = np.full(n, 2.35 if i % 3 == 0 else 5.0)
    return b, d, lo, hi


def _rank_deficient(rng: np.random.Generator, rows: int, cols: int) -> np.ndarray:
    """A random rows×cols matrix of rank min(rows, cols) − 1 (exactly dependent columns)."""
    rank = min(rows, cols) - 1
    return rng.normal(size=(rows, rank)) @ rng.normal(size=(rank, cols))


def _pdas(m_mat: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray,
          start: np.ndarray, rounds: int, definite: bool = True
          ) -> tuple[list[float], list[int], bool]:
    return dense_active_set.box_qp_pdas(m_mat.tolist(), c.tolist(), lo.tolist(), hi.tolist(),
                                        start.tolist(), rounds, BOX_XTOL, definite, RANK_RTOL)


def test_box_qp_pdas_equals_the_numpy_rounds(rng: np.random.Generator) -> None:
    """Same active set and optimum as box_qp_numpy from a cold and a warm start."""
    for i in range(N_PROBLEMS):
        b, d, lo, hi = _problem(rng, i)
        n = b.shape[1]
        eps = REGULARIZATION * float(np.mean(np.sum(b * b, axis=0)))
        m_mat, c = b.T @ b + eps * np.eye(n), b.T @ d
        cold = np.full(n, FREE, dtype=np.int8)
        ref_x, ref_state = box_qp_numpy(m_mat, c, lo, hi, cold, True)
        for start in (cold, ref_state):
            x, state, settled = _pdas(m_mat, c, lo, hi, start, MAX_PDAS_ITER)
            if not settled:  # the primal method finishes both the same way (tested below)
                continue
            assert state == ref_state.tolist(), i
            np.testing.assert_allclose(x, ref_x, rtol=0.0, atol=SOLUTION_ATOL)
            assert all(lo[k] <= x[k] <= hi[k] for k in range(n))
        x_api, _ = box_qp(m_mat, c, lo, hi, cold, True)
        ours, theirs = (float(0.5 * y @ m_mat @ y - c @ y) for y in (x_api, ref_x))
        assert ours <= theirs + OBJECTIVE_RTOL * max(1.0, abs(theirs))


def test_box_qp_pdas_warm_started_at_the_answer_takes_one_round(
        rng: np.random.Generator) -> None:
    """Started from the optimal active set, one round confirms it (max_rounds = 1 suffices)."""
    for i in range(N_PROBLEMS // 4):
        b, d, lo, hi = _problem(rng, i)
        n = b.shape[1]
        m_mat = b.T @ b + 1e-3 * np.eye(n)
        _, state = box_qp_numpy(m_mat, b.T @ d, lo, hi, np.full(n, FREE, dtype=np.int8), True)
        _, got, settled = _pdas(m_mat, b.T @ d, lo, hi, state, 1)
        assert settled and got == state.tolist()


def test_primal_active_set_equals_the_numpy_method(rng: np.random.Generator) -> None:
    """From the same feasible start (as after unsettled rounds), the same optimum."""
    for i in range(N_PROBLEMS // 2):
        b, d, lo, hi = _problem(rng, i)
        n = b.shape[1]
        eps = REGULARIZATION * float(np.mean(np.sum(b * b, axis=0)))
        m_mat, c = b.T @ b + eps * np.eye(n), b.T @ d
        x0 = rng.uniform(lo, hi)
        ref_x, _ = primal_active_set(m_mat, c, lo, hi, x0.copy(), True)
        x, _ = dense_active_set.primal_active_set(m_mat.tolist(), c.tolist(), lo.tolist(),
                                                  hi.tolist(), x0.tolist(), True, RANK_RTOL,
                                                  BOX_GTOL, PRIMAL_ITER_PER_VAR)
        np.testing.assert_allclose(x, ref_x, rtol=0.0, atol=SOLUTION_ATOL)


def test_box_qp_solves_a_singular_free_set_least_norm() -> None:
    """A free-set matrix that is not positive definite: the float form answers the
    least-norm solution itself, as the numpy/LAPACK reference does."""
    b = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # columns 0 and 1 equal: BᵀB singular
    m_mat, c = b.T @ b, np.array([1.0, 1.0, 0.5])
    lo, hi, cold = np.full(3, -9.0), np.full(3, 9.0), np.full(3, FREE, dtype=np.int8)
    assert dense.cholesky_solve(m_mat.tolist(), [0, 1, 2], c.tolist(), dense.PD_PIVOT_RTOL) \
        is None  # the Cholesky form cannot answer it
    for definite in (True, False):
        x, _ = box_qp(m_mat, c, lo, hi, cold, definite)
        np.testing.assert_allclose(x, [0.5, 0.5, 0.5], atol=SOLUTION_ATOL)
        ref, _ = box_qp_numpy(m_mat, c, lo, hi, cold, definite)
        np.testing.assert_allclose(x, ref, atol=SOLUTION_ATOL)


def test_box_qp_semidefinite_equals_the_numpy_reference(rng: np.random.Generator) -> None:
    """ε = 0 (M = BᵀB only semi-definite, more thrusters than rows): same optimum value."""
    for i in range(N_PROBLEMS // 4):
        b, d, lo, hi = _problem(rng, i)
        m_mat, c = b.T @ b, b.T @ d
        cold = np.full(b.shape[1], FREE, dtype=np.int8)
        x, _ = box_qp(m_mat, c, lo, hi, cold, False)
        ref, _ = box_qp_numpy(m_mat, c, lo, hi, cold, False)
        ours, theirs = (float(np.linalg.norm(b @ y - d)) for y in (x, ref))
        assert ours <= theirs + SOLUTION_ATOL * max(1.0, theirs)
        assert np.all(x >= lo) and np.all(x <= hi)


def test_refine_equals_lstsq(rng: np.random.Generator) -> None:
    """The refinement gives lstsq's thrusts (or both give None), every problem answered."""
    for i in range(N_PROBLEMS):
        b, d, lo, hi = _problem(rng, i)
        n = b.shape[1]
        eps = REGULARIZATION * float(np.mean(np.sum(b * b, axis=0)))
        t, _ = box_qp_numpy(b.T @ b + eps * np.eye(n), b.T @ d, lo, hi,
                            np.full(n, FREE, dtype=np.int8), True)
        got = refine_on_active_set(b, d, t, lo, hi)
        ref = refine_lstsq(b, d, t, lo, hi)
        assert (got is None) == (ref is None), i
        if ref is not None and got is not None:
            np.testing.assert_allclose(got, ref, rtol=0.0, atol=SOLUTION_ATOL)


def test_refine_answers_an_ill_conditioned_step_itself() -> None:
    """Two nearly parallel demand rows (B_F B_Fᵀ near singular): the normal equations
    decline, the SVD of B_F answers; the result is lstsq's."""
    b = np.array([[1.0, 1.0, 0.5], [1.0, 1.0 + 1e-7, 0.5]])
    d, lo, hi = np.array([1.0, 0.5]), np.full(3, -9.0), np.full(3, 9.0)
    t = np.zeros(3)
    gram = (b @ b.T).tolist()
    assert dense.cholesky_solve(gram, [0, 1], d.tolist(), dense.LSQ_PIVOT_RTOL) is None
    got = refine_on_active_set(b, d, t, lo, hi)
    ref = refine_lstsq(b, d, t, lo, hi)
    assert got is not None and ref is not None
    np.testing.assert_allclose(got, ref, atol=SOLUTION_ATOL)
    done = dense_active_set.refine_active_set(b.tolist(), d.tolist(), t.tolist(), lo.tolist(),
                                              hi.tolist(), ACTIVE_RTOL, RANK_RTOL)
    assert done is not None


@pytest.mark.parametrize(("rows", "cols"), SHAPES)
def test_least_norm_svd_equals_lapack(rows: int, cols: int, rng: np.random.Generator) -> None:
    """Full-rank and rank-deficient matrices, tall and wide: x = A⁺ b as LAPACK's lstsq."""
    for k in range(N_PROBLEMS // 10):
        a = rng.normal(size=(rows, cols)) if k % 2 else _rank_deficient(rng, rows, cols)
        b = rng.normal(size=rows)
        x = np.array(dense.least_norm_svd(a.tolist(), b.tolist(), RANK_RTOL))
        ref = np.linalg.lstsq(a, b, rcond=RANK_RTOL)[0]
        assert np.max(np.abs(x - ref)) <= SVD_RTOL * max(1.0, float(np.max(np.abs(ref))))


def test_least_norm_svd_of_zero_and_empty_matrices() -> None:
    """A zero matrix has the zero solution; an empty one none."""
    assert dense.least_norm_svd([[0.0, 0.0], [0.0, 0.0]], [1.0, 2.0], RANK_RTOL) == [0.0, 0.0]
    assert dense.least_norm_svd([], [], RANK_RTOL) == []


@pytest.mark.parametrize("n", [1, 2, 6, 16])
def test_cholesky_solve_known_answer(n: int) -> None:
    """A diagonal system and a subset of it: x = b / diag."""
    a = np.diag(np.arange(1.0, n + 1)).tolist()
    idx = list(range(0, n, 2)) or [0]
    x = dense.cholesky_solve(a, idx, [1.0] * len(idx), dense.PD_PIVOT_RTOL)
    assert x == pytest.approx([1.0 / (k + 1) for k in idx], rel=1e-15)


def test_mat_vec_and_norm_match_numpy() -> None:
    """``A x`` and ``‖x‖`` on floats equal numpy's to round-off on random 16×6 and 6×16
    matrices; every sum runs in index order (a known answer with cancellation)."""
    rng = np.random.default_rng(20261207)
    for shape in ((16, 6), (6, 16), (3, 3)):
        for _ in range(50):
            a, x = rng.normal(size=shape), rng.normal(size=shape[1])
            np.testing.assert_allclose(dense.mat_vec(a.tolist(), x.tolist()), a @ x,
                                       rtol=1e-13, atol=1e-14)
            assert dense.norm(x.tolist()) == pytest.approx(float(np.linalg.norm(x)), rel=1e-15)
    # left to right: (1e16 + 1) − 1e16 = 0 in doubles; a compensated or reordered sum gives 1
    assert dense.mat_vec([[1.0, 1.0, -1.0]], [1e16, 1.0, 1e16]) == [0.0]
