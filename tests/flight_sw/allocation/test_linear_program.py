"""The design-time linear programmes on HiGHS, against scipy's linprog as the reference."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from flight_sw.allocation.linear_program import solve_lp

N_RANDOM = 40
# Optimal objectives of the two solvers agree to this, relative to the objective's size.
OBJECTIVE_RTOL = 1e-9
# Constraint violation allowed in a returned solution (HiGHS's primal feasibility default).
FEASIBILITY_TOL = 1e-7


def _random_lp(rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """A feasible, bounded LP: x0 in a box, equalities through it, one inequality row."""
    n, m = int(rng.integers(3, 12)), int(rng.integers(1, 3))
    lo, hi = -rng.uniform(0.0, 2.0, n), rng.uniform(0.5, 3.0, n)
    x0 = rng.uniform(lo, hi)
    a_eq = rng.normal(size=(m, n))
    a_ub = rng.normal(size=(1, n))
    return rng.normal(size=n), lo, hi, a_eq, a_eq @ x0, a_ub, a_ub @ x0 + 0.1


def test_optimum_matches_scipy_linprog() -> None:
    """Random feasible LPs: the same optimal objective as linprog, and a feasible point."""
    rng = np.random.default_rng(3)
    for _ in range(N_RANDOM):
        cost, lo, hi, a_eq, b_eq, a_ub, b_ub = _random_lp(rng)
        x = solve_lp(cost, lo, hi, a_eq, b_eq, a_ub, b_ub)
        ref = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq,
                      bounds=list(zip(lo, hi, strict=True)))
        assert ref.status == 0 and x is not None
        scale = 1.0 + abs(ref.fun)
        assert abs(cost @ x - ref.fun) <= OBJECTIVE_RTOL * scale
        assert np.abs(a_eq @ x - b_eq).max() <= FEASIBILITY_TOL
        assert (a_ub @ x - b_ub).max() <= FEASIBILITY_TOL
        assert np.all(x >= lo - FEASIBILITY_TOL) and np.all(x <= hi + FEASIBILITY_TOL)


def test_infeasible_and_unbounded_give_none() -> None:
    """x = 2 with x ≤ 1 has no point; min −x over x ≥ 0 has no optimum."""
    assert solve_lp(np.ones(1), np.zeros(1), np.ones(1), np.ones((1, 1)), np.array([2.0])) is None
    assert solve_lp(-np.ones(1), np.zeros(1), np.full(1, np.inf)) is None


def test_free_variable_bounds_and_equality_rows() -> None:
    """min x0 + x1, x0 − x1 = 0, x0 = 1 (x1 free): the known answer (1, 1)."""
    x = solve_lp(np.ones(2), np.array([1.0, -np.inf]), np.array([1.0, np.inf]),
                 np.array([[1.0, -1.0]]), np.zeros(1))
    assert x is not None
    np.testing.assert_array_equal(x, [1.0, 1.0])


def test_no_banner_on_standard_output(capfd: pytest.CaptureFixture[str]) -> None:
    """HiGHS's start-up banner is kept off the process's standard output (C level)."""
    solve_lp(np.ones(2), np.zeros(2), np.ones(2))
    out, err = capfd.readouterr()
    assert out == "" and err == ""
