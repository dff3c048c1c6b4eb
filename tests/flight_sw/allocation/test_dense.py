"""The allocators' dense kernels on Python floats against their numpy/LAPACK forms.

Back to back on random problems of thruster-set size (m ≤ 6 rows, n ≤ 16 thrusters, with
and without negative bounds): the Cholesky box QP reaches the same active set and optimum
as the numpy one, the normal-equation refinement the same thrusts as lstsq; ill-conditioned
problems are handed back (None) to the numpy forms, which then decide.
"""

from __future__ import annotations

import numpy as np
import pytest

from flight_sw.allocation import dense
from flight_sw.allocation.active_set import (
    ACTIVE_RTOL,
    BOX_XTOL,
    FREE,
    MAX_PDAS_ITER,
    box_qp,
    box_qp_numpy,
    refine_lstsq,
    refine_on_active_set,
)

N_PROBLEMS = 200
REGULARIZATION = 1e-6  # as the bounded allocator's default
SOLUTION_ATOL = 1e-9  # thrust [N]: the same QP optimum, up to round-off of two methods
OBJECTIVE_RTOL = 1e-12


def _problem(rng: np.random.Generator, i: int) -> tuple[np.ndarray, ...]:
    """Effectiveness b (m×n), demand d and bounds of the i-th random problem."""
    m, n = ((3, 8), (6, 16), (6, 12), (6, 6))[i % 4]
    b = rng.normal(size=(m, n))
    d = rng.normal(size=m) * float(rng.choice([0.5, 5.0, 40.0]))
    lo = np.zeros(n) if i % 3 else np.full(n, -2.3)
    hi = np.full(n, 2.35 if i % 3 == 0 else 5.0)
    return b, d, lo, hi


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
            fast = dense.box_qp_pdas(m_mat.tolist(), c.tolist(), lo.tolist(), hi.tolist(),
                                     start.tolist(), MAX_PDAS_ITER, BOX_XTOL)
            assert fast is not None
            x, state, settled = fast
            if not settled:  # the primal fallback finishes both the same way
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
        fast = dense.box_qp_pdas(m_mat.tolist(), (b.T @ d).tolist(), lo.tolist(), hi.tolist(),
                                 state.tolist(), 1, BOX_XTOL)
        assert fast is not None and fast[2] and fast[1] == state.tolist()


def test_box_qp_pdas_hands_a_singular_matrix_back() -> None:
    """A free-set matrix that is not positive definite gives None (numpy decides)."""
    b = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # columns 0 and 1 equal: BᵀB singular
    m_mat = b.T @ b
    fast = dense.box_qp_pdas(m_mat.tolist(), [1.0, 1.0, 0.5], [-9.0] * 3, [9.0] * 3,
                             [FREE] * 3, MAX_PDAS_ITER, BOX_XTOL)
    assert fast is None
    x, _ = box_qp(m_mat, np.array([1.0, 1.0, 0.5]), np.full(3, -9.0), np.full(3, 9.0),
                  np.full(3, FREE, dtype=np.int8), True)
    np.testing.assert_allclose(x, [0.5, 0.5, 0.5], atol=1e-12)  # least-norm on the free set


def test_refine_equals_lstsq(rng: np.random.Generator) -> None:
    """The normal-equation refinement gives lstsq's thrusts (or both give None)."""
    answered = 0
    for i in range(N_PROBLEMS):
        b, d, lo, hi = _problem(rng, i)
        n = b.shape[1]
        eps = REGULARIZATION * float(np.mean(np.sum(b * b, axis=0)))
        t, _ = box_qp_numpy(b.T @ b + eps * np.eye(n), b.T @ d, lo, hi,
                            np.full(n, FREE, dtype=np.int8), True)
        done, fast = dense.refine_active_set(b.tolist(), d.tolist(), t.tolist(), lo.tolist(),
                                             hi.tolist(), ACTIVE_RTOL)
        ref = refine_lstsq(b, d, t, lo, hi)
        if not done:
            continue
        answered += 1
        if ref is None:
            assert fast is None, i
            continue
        assert fast is not None, i
        np.testing.assert_allclose(fast, ref, rtol=0.0, atol=SOLUTION_ATOL)
    assert answered >= N_PROBLEMS // 2  # the fast form answers the usual problems


def test_refine_hands_an_ill_conditioned_step_back() -> None:
    """Two nearly parallel demand rows (B_F B_Fᵀ near singular): the fast form declines; the
    result is lstsq's."""
    b = np.array([[1.0, 1.0, 0.5], [1.0, 1.0 + 1e-7, 0.5]])
    d, lo, hi = np.array([1.0, 0.5]), np.full(3, -9.0), np.full(3, 9.0)
    t = np.zeros(3)
    done, fast = dense.refine_active_set(b.tolist(), d.tolist(), t.tolist(), lo.tolist(),
                                         hi.tolist(), ACTIVE_RTOL)
    assert (done, fast) == (False, None)
    got = refine_on_active_set(b, d, t, lo, hi)
    ref = refine_lstsq(b, d, t, lo, hi)
    assert got is not None and ref is not None
    np.testing.assert_allclose(got, ref, atol=1e-12)


@pytest.mark.parametrize("n", [1, 2, 6, 16])
def test_cholesky_solve_known_answer(n: int) -> None:
    """A diagonal system and a subset of it: x = b / diag."""
    a = np.diag(np.arange(1.0, n + 1)).tolist()
    idx = list(range(0, n, 2)) or [0]
    x = dense.cholesky_solve(a, idx, [1.0] * len(idx), dense.PD_PIVOT_RTOL)
    assert x == pytest.approx([1.0 / (k + 1) for k in idx], rel=1e-15)
